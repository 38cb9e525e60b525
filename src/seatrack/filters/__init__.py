"""seatrack.filters."""
