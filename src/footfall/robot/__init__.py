"""Robot descriptions."""
