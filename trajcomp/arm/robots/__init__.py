"""Built-in robot descriptions (YAML package data), one file per arm."""
