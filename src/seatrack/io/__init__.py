"""seatrack.io."""
