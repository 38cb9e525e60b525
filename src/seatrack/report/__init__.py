"""seatrack.report."""
