"""Reading point-cloud files."""
