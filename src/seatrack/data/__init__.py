"""Data bundled with seatrack: example scenarios, real AIS samples and the table of target
classes (``target_classes.toml``, read by :mod:`seatrack.models.targets`).

The AIS samples (``seatrack/data/ais/*.csv``) are real, uncleaned position reports from
public sources; their provenance and licences are in ``seatrack/data/ais/README.md``.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["AIS_SAMPLES", "ais_sample"]

#: the bundled real AIS files, common schema ``mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg``
AIS_SAMPLES = (
    "no_vestland_20220901.csv",
    "dk_northsea_20221101_1h_selected.csv",
    "dk_northsea_20221101_1h_all.csv",
    "dk_gothenburg_20170705_cpa.csv",
    "us_boston_201401_trajectools.csv",
)


def ais_sample(name: str) -> Path:
    """Path of the bundled AIS sample ``name`` (one of :data:`AIS_SAMPLES`).

    Raises
    ------
    ValueError
        When ``name`` is not a bundled sample (the message lists them).
    """
    if name not in AIS_SAMPLES:
        raise ValueError(f"unknown AIS sample {name!r}; bundled: {', '.join(AIS_SAMPLES)}")
    return Path(str(resources.files("seatrack") / "data" / "ais" / name))
