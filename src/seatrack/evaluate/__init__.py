"""seatrack.evaluate."""
