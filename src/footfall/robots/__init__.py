"""Built-in robot descriptions (TOML)."""
