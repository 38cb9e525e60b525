"""Warnings for plausible but suspicious inputs: a column that looks like it is in the
wrong unit.

Each check returns the warning text (``FILE: column ... looks like ...``) or ``None``; the
readers print them with :func:`warn` as one ``warning: ...`` line on standard error after
the file was read, and go on: the values are legal, only unlikely. The heuristics are
deliberately narrow (at least :data:`MIN_ROWS` values, all of them in the suspicious range)
so that they stay silent on the bundled scenarios and examples:

* azimuths or bearings in radians: every value of a ``*_deg`` angle column in
  ``[0, 2 pi]``;
* ranges in kilometres: every ``range_m`` below :data:`KM_RANGE_BELOW_M`;
* times in milliseconds: consecutive rows of one track or contact a median of more than
  :data:`MS_STEP_ABOVE_S` seconds apart (a radar scans every few seconds, a sonar bearing
  comes every minute at most);
* AIS speeds in m/s, or latitude and longitude swapped (:class:`AisUnitCheck`): the
  speed and course of each vessel between consecutive reports, from its positions, against
  the reported SOG and COG: SOG a median 0.51 times the position speed is m/s; COG far from
  the position course but close to the course of the positions read with latitude and
  longitude exchanged is swapped columns;
* a gyro in rad/s: at least :data:`MIN_GYRO_ROWS` turn rates, every one below
  :data:`RAD_RATE_BELOW_DPS` in magnitude (a ship's gyro reads tenths of a degree per
  second on any passage with a bend; 0.05 rad/s is 2.9 deg/s).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "MIN_ROWS",
    "KM_RANGE_BELOW_M",
    "MS_STEP_ABOVE_S",
    "warn",
    "radians_warning",
    "km_warning",
    "ms_warning",
    "rad_per_s_warning",
    "AisUnitCheck",
    "MIN_GYRO_ROWS",
    "RAD_RATE_BELOW_DPS",
]

#: fewest values a heuristic looks at
MIN_ROWS = 10
#: every range below this (m) looks like kilometres
KM_RANGE_BELOW_M = 100.0
#: a median time step above this (s) between rows of one track looks like milliseconds
MS_STEP_ABOVE_S = 600.0
#: fewest gyro samples the rad/s heuristic looks at (10 s at 10 Hz)
MIN_GYRO_ROWS = 100
#: every |turn rate| below this (deg/s) looks like rad/s
RAD_RATE_BELOW_DPS = 0.05


def warn(messages: Iterable[str | None]) -> None:
    """Print each message (``None`` skipped) as one ``warning: ...`` line on stderr."""
    for m in messages:
        if m:
            print(f"warning: {m}", file=sys.stderr)


def radians_warning(path: str, column: str, deg: NDArray[np.float64]) -> str | None:
    """Every value of angle column ``column`` (degrees) in ``[0, 2 pi]``: radians?"""
    a = np.asarray(deg, float)
    a = a[np.isfinite(a)]
    if a.size < MIN_ROWS or a.min() < 0 or a.max() > 2 * math.pi or a.max() == a.min():
        return None
    return (
        f"{path}: every {column} is between {a.min():.3g} and {a.max():.3g}: it looks like "
        "radians (the column is in degrees)"
    )


def km_warning(path: str, column: str, metres: NDArray[np.float64]) -> str | None:
    """Every value of range column ``column`` below :data:`KM_RANGE_BELOW_M`: kilometres?"""
    r = np.asarray(metres, float)
    r = r[np.isfinite(r)]
    if r.size < MIN_ROWS or r.max() >= KM_RANGE_BELOW_M:
        return None
    return (
        f"{path}: every {column} is below {KM_RANGE_BELOW_M:g}: it looks like kilometres "
        "(the column is in metres)"
    )


def ms_warning(
    path: str, column: str, t: NDArray[np.float64], groups: NDArray[np.generic] | None = None
) -> str | None:
    """Rows of one group (track, contact; all rows when ``None``) a median of more than
    :data:`MS_STEP_ABOVE_S` apart in ``column`` (s): milliseconds?"""
    t = np.asarray(t, float)
    if t.size < MIN_ROWS:
        return None
    if groups is None:
        steps = np.diff(np.unique(t))
    else:
        g = np.asarray(groups)
        order = np.lexsort((t, g))
        same = g[order][1:] == g[order][:-1]
        steps = np.diff(t[order])[same]
    steps = steps[steps > 0]
    if steps.size < MIN_ROWS - 1:
        return None
    med = float(np.median(steps))
    if med <= MS_STEP_ABOVE_S:
        return None
    return (
        f"{path}: consecutive {column} values are a median {med:g} s apart: it looks like "
        "milliseconds (the column is in seconds)"
    )


def rad_per_s_warning(path: str, column: str, dps: NDArray[np.float64]) -> str | None:
    """Every turn rate of ``column`` (deg/s) below :data:`RAD_RATE_BELOW_DPS` over at least
    :data:`MIN_GYRO_ROWS` samples, not all zero: rad/s?"""
    a = np.abs(np.asarray(dps, float))
    a = a[np.isfinite(a)]
    if a.size < MIN_GYRO_ROWS or a.max() >= RAD_RATE_BELOW_DPS or a.max() == 0:
        return None
    return (
        f"{path}: every {column} is below {RAD_RATE_BELOW_DPS:g} in magnitude: it looks like "
        "rad/s (the column is in deg/s)"
    )


#: Earth radius for the flat-Earth step between consecutive AIS reports, m
_EARTH_M = 6_371_000.0


class AisUnitCheck:
    """Reported SOG and COG against the speed and course from consecutive positions of
    each vessel, accumulated group by group (at most :attr:`most` pairs kept).

    Only moving pairs count: same vessel, both rows usable, 5 to 120 s apart, more than
    20 m apart and SOG above 2 kn; at least 100 of them (100 with a COG for the course
    check).
    """

    most = 200_000

    def __init__(self) -> None:
        self.ratio: list[NDArray[np.float64]] = []
        self.off: list[NDArray[np.float64]] = []
        self.mirror: list[NDArray[np.float64]] = []
        self.n = 0

    def add(self, r: Any) -> None:
        """Add the reports of one group (an :class:`~seatrack.io.ais.AisReports`)."""
        from seatrack.geometry import angle_diff
        from seatrack.geometry import bearing
        from seatrack.geometry import mps_to_knots

        if self.n >= self.most:
            return
        ok = np.asarray(r.code) == 0
        mmsi = np.asarray(r.mmsi)[ok]
        t = np.asarray(r.t, float)[ok]
        lat = np.radians(np.asarray(r.lat, float)[ok])
        lon = np.radians(np.asarray(r.lon, float)[ok])
        sog = np.asarray(r.sog_kn, float)[ok]
        cog = np.radians(np.asarray(r.cog_deg, float)[ok])
        order = np.lexsort((t, mmsi))
        mmsi, t, lat, lon, sog, cog = (a[order] for a in (mmsi, t, lat, lon, sog, cog))
        dt = np.diff(t)
        dx = _EARTH_M * np.cos(lat[1:]) * angle_diff(lon[1:], lon[:-1])
        dy = _EARTH_M * (lat[1:] - lat[:-1])
        dist = np.hypot(dx, dy)
        use = (mmsi[1:] == mmsi[:-1]) & (dt >= 5) & (dt <= 120) & (dist > 20) & (sog[1:] > 2)
        self.ratio.append(sog[1:][use] / mps_to_knots(dist[use] / dt[use]))
        turn = use & np.isfinite(cog[1:])  # logs without COG: no course check
        course = bearing(dx[turn], dy[turn])
        # the course the positions give read the other way round (lat as lon, lon as lat)
        dx_alt = _EARTH_M * np.cos(lon[1:]) * angle_diff(lat[1:], lat[:-1])
        dy_alt = _EARTH_M * angle_diff(lon[1:], lon[:-1])
        alt = bearing(dx_alt[turn], dy_alt[turn])
        self.off.append(np.abs(angle_diff(cog[1:][turn], course)))
        self.mirror.append(np.abs(angle_diff(cog[1:][turn], alt)))
        self.n += int(use.sum())

    def warnings(self, where: str) -> list[str]:
        """The warnings for inputs ``where`` (none under :data:`MIN_ROWS` * 10 pairs)."""
        if self.n < 10 * MIN_ROWS:
            return []
        off_all, mirror_all = np.concatenate(self.off), np.concatenate(self.mirror)
        enough = off_all.size >= 10 * MIN_ROWS
        off = float(np.degrees(np.median(off_all))) if enough else 0.0
        mirror = float(np.degrees(np.median(mirror_all))) if enough else 180.0
        if off > 45 and mirror < 20:  # (the speeds between swapped positions mean nothing)
            return [
                f"{where}: the reported courses match the positions with latitude and "
                f"longitude swapped (median {mirror:.0f} deg off, {off:.0f} deg as given): "
                "lat and lon look swapped"
            ]
        ratio = float(np.median(np.concatenate(self.ratio)))
        if 0.45 < ratio < 0.58:
            return [
                f"{where}: sog_kn is a median {ratio:.2f} times the speed between the "
                "positions: it looks like m/s (the column is in knots)"
            ]
        return []
