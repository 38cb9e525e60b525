"""seatrack.tma."""
