"""Settings chosen from the data when the user gives only the sensor noise.

* The scan period ``T``: the median interval between distinct plot times.
* The process noise of the per-track filter, from the target class. Ships sail straight
  legs disturbed by sea and steering (accelerations of a few cm/s^2) and manoeuvre now and
  then (turns and speed changes up to ``accel``, 0.7 m/s^2 for the default ship class: a
  3 deg/s turn at 27 kn). A filter whose configuration has a white-noise-acceleration PSD
  ``q`` the user did not set gets the straight-leg level ``q_s = a_s^2 T`` (``a_s`` =
  0.05 m/s^2) and is wrapped in :class:`~seatrack.tracking.adaptive.NoiseLevels`, an IMM
  that adds ``q_m = accel^2 T / 2`` during manoeuvres (switching probability 0.01 per
  scan). The levels and the switching probability were chosen on the tuning scenarios of
  ``benchmarks/multitarget.py`` (disjoint from its evaluation scenarios).

Filters without a ``q`` field, or whose ``q`` the user gave, are used as configured.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from seatrack.filters.base import RecursiveFilter, SensorNoise
from seatrack.tracking.adaptive import NoiseLevels

__all__ = [
    "SHIP_ACCEL",
    "STRAIGHT_ACCEL",
    "P_SWITCH",
    "scan_period",
    "noise_levels",
    "per_track_filter",
]

#: manoeuvre acceleration of the default target class (ships), m/s^2
SHIP_ACCEL = 0.7
#: acceleration noise on straight legs, m/s^2
STRAIGHT_ACCEL = 0.05
#: probability per scan of switching between the noise levels
P_SWITCH = 0.01


def scan_period(t: ArrayLike) -> float:
    """Median interval (s) between the distinct times ``t``; 1 s for a single scan."""
    u = np.unique(np.asarray(t, dtype=float))
    if u.size < 2:
        return 1.0
    return float(np.median(np.diff(u)))


def noise_levels(period: float, accel: float = SHIP_ACCEL) -> tuple[float, float]:
    """Straight-leg and manoeuvre white-noise acceleration PSDs (m^2/s^3) for the class."""
    if not (period > 0 and accel > 0):
        raise ValueError(f"need a positive scan period and acceleration, got {period}, {accel}")
    return STRAIGHT_ACCEL**2 * period, 0.5 * accel**2 * period


def per_track_filter(
    cls: Any,
    config: Any,
    given: Collection[str],
    sensor: SensorNoise,
    d: int,
    range_rate: bool,
    period: float,
    accel: float = SHIP_ACCEL,
) -> RecursiveFilter:
    """Build ``cls(config, sensor, d=d, range_rate=range_rate)``, with adaptive process
    noise when ``config`` has a ``q`` field that is not among the user's keys ``given``."""
    fields = {f.name: f for f in dataclasses.fields(config)}
    q_field = fields.get("q")
    auto = q_field is not None and not ({"q", str(q_field.metadata.get("key") or "q")} & set(given))
    if not auto:
        return cls(config, sensor, d=d, range_rate=range_rate)  # type: ignore[no-any-return]
    q_s, q_m = noise_levels(period, accel)
    flt = cls(dataclasses.replace(config, q=q_s), sensor, d=d, range_rate=range_rate)
    return NoiseLevels(flt, (0.0, q_m - q_s), P_SWITCH)
