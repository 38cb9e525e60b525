"""The radar site file (``radar.toml``) that ``seatrack live`` and ``seatrack fuse`` read.

One TOML file describes a radar: where it stands, how noisy its plots are, what it can
see, and how its plots are tracked::

    lat_deg = 57.70                 # antenna position (WGS 84)
    lon_deg = 11.85
    antenna_height_m = 20.0         # above the sea surface
    sigma_range_m = 20.0            # plot noise: the sensor keys, flat or in [sensor]
    sigma_azimuth_deg = 0.5
    max_range_m = 40000.0           # coverage
    blind_sectors_deg = [[120.0, 150.0]]   # clockwise from the first to the second bearing
    method = "ekf"                  # per-track filter of the multi-target tracker

    [tracker]                       # multi-target tracker keys (docs/tracking.md)
    max_speed_kn = 40.0

    [method_config]                 # keys of the per-track method (docs of the method)

Every key has a documented default except the position; units are those of the key's
suffix and are converted to SI and radians once, here (:mod:`seatrack.config`). The
bearings of ``blind_sectors_deg`` are true (clockwise from North); a sector ``[a, b]``
runs clockwise from ``a`` to ``b`` and may cross North (``[350, 10]``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import field
from pathlib import Path
from typing import Any

from seatrack.config import Checked
from seatrack.config import ConfigError
from seatrack.config import load_toml
from seatrack.config import param
from seatrack.config import parse_config
from seatrack.filters.base import SensorNoise
from seatrack.filters.registry import METHODS
from seatrack.filters.registry import split_config
from seatrack.tracking.tracker import TrackerConfig

__all__ = ["RadarSite", "RadarSetup", "parse_radar_config", "load_radar_config", "in_sector"]


@dataclass(frozen=True)
class RadarSite(Checked):
    """Position, coverage and scan timing of a radar (SI units and radians inside)."""

    lat: float = param(
        0.0, key="lat_deg", unit="deg", doc="antenna latitude (WGS 84)", min=-90.0, max=90.0
    )
    lon: float = param(
        0.0, key="lon_deg", unit="deg", doc="antenna longitude (WGS 84)", min=-180.0, max=180.0
    )
    antenna_height: float = param(
        15.0, key="antenna_height_m", unit="m", doc="antenna height above the sea", min=0,
        max=1e4,
    )  # fmt: skip
    target_height: float = param(
        5.0, key="target_height_m", unit="m",
        doc="height of a typical target's reflecting part (radar horizon)", min=0, max=1e4,
    )  # fmt: skip
    min_range: float = param(
        50.0, key="min_range_m", unit="m", doc="inner limit of coverage (blind zone)", min=0,
        max=1e7,
    )  # fmt: skip
    max_range: float = param(
        40000.0, key="max_range_m", unit="m", doc="instrumented range", min=0,
        exclusive_min=True, max=1e7,
    )  # fmt: skip
    blind_sectors: tuple[tuple[float, float], ...] = param(
        (), key="blind_sectors_deg", unit="deg",
        doc="sectors [from, to] (true bearings, clockwise) where the radar sees nothing",
    )  # fmt: skip
    detection_probability: float = param(
        0.9, doc="probability of detecting a target inside coverage", min=0, max=1,
        exclusive_min=True,
    )  # fmt: skip
    scan_timeout: float = param(
        2.0, key="scan_timeout_s", unit="s",
        doc="live: a scan closes when a later time arrives or after this wait", min=0,
        exclusive_min=True, max=3600.0,
    )  # fmt: skip
    scan_period: float = param(
        2.5, key="scan_period_s", unit="s",
        doc="live: antenna revolution period, for the per-track filter's automatic process "
        "noise (the batch tracker takes the median interval of the file)", min=0,
        exclusive_min=True, max=3600.0,
    )  # fmt: skip
    method: str = param("ekf", doc="per-track filter of the multi-target tracker")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.min_range >= self.max_range:
            raise ValueError(
                f"min_range_m ({self.min_range:g}) must be below max_range_m ({self.max_range:g})"
            )
        for i, sector in enumerate(self.blind_sectors):
            if len(sector) != 2 or not all(isinstance(v, float) for v in sector):
                raise ValueError(f"blind_sectors_deg[{i}]: expected [from_deg, to_deg]")
            if not all(0.0 <= v <= 2.0 * math.pi for v in sector):
                raise ValueError(f"blind_sectors_deg[{i}]: bearings must be within 0..360 deg")
        if self.method not in METHODS:
            raise ValueError(
                f"method: unknown method {self.method!r}; choose one of {', '.join(METHODS)}"
            )


@dataclass(frozen=True)
class RadarSetup:
    """A parsed ``radar.toml``: the site, the plots' noise, the tracker and method keys."""

    site: RadarSite
    sensor: SensorNoise
    tracker: TrackerConfig
    #: the per-track method's table (method keys plus the sensor keys), as
    #: :func:`seatrack.filters.registry.build` takes it
    method_table: dict[str, Any] = field(default_factory=dict)


def parse_radar_config(table: Mapping[str, Any], source: str = "radar config") -> RadarSetup:
    """A :class:`RadarSetup` from a parsed TOML table (see the module docstring).

    ``lat_deg`` and ``lon_deg`` are required; every other key has its documented default.

    Raises
    ------
    ConfigError
        A missing position, an unknown key (listing the valid ones) or a bad value.
    """
    sensor_tab, rest = split_config(table, source)
    tracker_tab = rest.pop("tracker", {})
    method_tab = rest.pop("method_config", {})
    for name, tab in (("tracker", tracker_tab), ("method_config", method_tab)):
        if not isinstance(tab, Mapping):
            raise ConfigError(f"{source}: [{name}] must be a table")
    for key in ("lat_deg", "lon_deg"):
        if key not in rest and key.removesuffix("_deg") not in rest:
            raise ConfigError(f"{source}: {key}: required (the radar's position)")
    site = parse_config(RadarSite, rest, source=source)
    sensor = parse_config(SensorNoise, sensor_tab, source=f"{source}: sensor")
    tracker = parse_config(TrackerConfig, tracker_tab, source=f"{source}: tracker")
    return RadarSetup(site, sensor, tracker, {**dict(method_tab), "sensor": dict(sensor_tab)})


def load_radar_config(path: str | Path) -> RadarSetup:
    """Read and parse a ``radar.toml`` (errors name the file and the key)."""
    return parse_radar_config(load_toml(path), source=str(path))


def in_sector(bearing: float, sector: tuple[float, float]) -> bool:
    """Whether the true ``bearing`` (rad) lies in ``sector`` = (from, to), clockwise, rad."""
    a, b = sector
    turn = 2.0 * math.pi
    return (bearing - a) % turn <= (b - a) % turn
