"""Models shipped with calib (README.md names their source and licence)."""
