"""seatrack.navigation."""
