"""Data files shipped with bodyfit (derived tables; see tools/)."""
