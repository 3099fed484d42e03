"""footfall."""
