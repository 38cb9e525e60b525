"""The real AIS samples bundled in ``seatrack/data/ais`` (provenance in its README; never
edited), shared by the AIS tests."""

from pathlib import Path

from seatrack.data import AIS_SAMPLES
from seatrack.data import ais_sample

FILES = list(AIS_SAMPLES)


def data_file(name: str) -> Path:
    """Path of the bundled sample ``name``."""
    p = ais_sample(name)
    assert p.is_file(), f"bundled AIS sample missing from the installation: {p}"
    return p
