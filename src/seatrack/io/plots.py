"""Radar / sonar plot files (``PLOTS.csv``) for ``seatrack track``.

Columns (header names exact; extra columns allowed):

* ``track`` (optional): run / track id; rows of one id form one track; default one track.
* ``time_s``: seconds, strictly increasing within a track.
* ``range_m``: slant range, m (> 0).
* ``azimuth_deg``: true azimuth / bearing, degrees clockwise from North, in [0, 360).
* ``elevation_deg`` (optional): degrees up; absent -> 2-D plots.
* ``range_rate_mps`` (optional): m/s, positive opening.
* ``sensor_x_m``, ``sensor_y_m``, ``sensor_z_m`` (optional): sensor position (East, North,
  Up); absent -> sensor at the origin. Sensor velocity (for range rate) is taken from the
  finite differences of its positions.

Inside seatrack angles are radians (converted here, at the edge).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from seatrack.io.table import InputError, Table, check_times, read_csv_table

FloatArray = NDArray[np.float64]

__all__ = ["PlotTrack", "read_plots", "PLOT_COLUMNS"]

PLOT_COLUMNS = ("time_s", "range_m", "azimuth_deg")
_OPTIONAL = (
    "track",
    "elevation_deg",
    "range_rate_mps",
    "sensor_x_m",
    "sensor_y_m",
    "sensor_z_m",
)


@dataclass(frozen=True)
class PlotTrack:
    """The plots of one track, SI units and radians.

    Attributes
    ----------
    track : str
        Track id.
    t : (N,) s
    range : (N,) m
    azimuth : (N,) rad, clockwise from North, [0, 2 pi)
    elevation : (N,) rad or None (2-D plots)
    range_rate : (N,) m/s or None
    sensor : (N, 3) m  -- sensor position East, North, Up
    sensor_vel : (N, 3) m/s -- sensor velocity (finite differences of ``sensor``)
    lines : (N,) int -- source line of each plot
    """

    track: str
    t: FloatArray
    range: FloatArray
    azimuth: FloatArray
    elevation: FloatArray | None
    range_rate: FloatArray | None
    sensor: FloatArray
    sensor_vel: FloatArray
    lines: NDArray[np.int64]

    @property
    def is_3d(self) -> bool:
        return self.elevation is not None

    def __len__(self) -> int:
        return int(self.t.size)


def _sensor_velocity(t: FloatArray, s: FloatArray) -> FloatArray:
    if t.size < 2:
        return np.zeros_like(s)
    return np.stack([np.gradient(s[:, k], t) for k in range(3)], -1)


def read_plots(path: str | Path) -> list[PlotTrack]:
    """Read and validate a PLOTS.csv file into one :class:`PlotTrack` per track id.

    Raises
    ------
    InputError
        Naming the file, line and problem: missing columns, NaN/inf or empty values,
        non-positive range, azimuth outside [0, 360), elevation outside [-90, 90],
        unsorted or duplicate times within a track, a column present for only some rows.
    """
    tab = read_csv_table(path, PLOT_COLUMNS, _OPTIONAL, text=("track",))
    _check_values(tab)
    check_times(tab, "time_s", group="track", strict=True)
    ids = tab["track"] if "track" in tab else np.full(len(tab), "1")
    out = []
    for tid in dict.fromkeys(ids.tolist()):
        m = ids == tid
        sub = tab.subset(m)
        t = sub["time_s"]
        sensor = np.zeros((t.size, 3))
        for k, c in enumerate(("sensor_x_m", "sensor_y_m", "sensor_z_m")):
            if c in sub:
                sensor[:, k] = sub[c]
        out.append(
            PlotTrack(
                track=str(tid) if tid != "" else "1",
                t=t,
                range=sub["range_m"],
                azimuth=np.radians(sub["azimuth_deg"]),
                elevation=np.radians(sub["elevation_deg"]) if "elevation_deg" in sub else None,
                range_rate=sub["range_rate_mps"] if "range_rate_mps" in sub else None,
                sensor=sensor,
                sensor_vel=_sensor_velocity(t, sensor),
                lines=sub.lines,
            )
        )
    return out


def _check_values(tab: Table) -> None:
    def bad(mask: NDArray[np.bool_], what: str) -> None:
        if mask.any():
            i = int(np.argmax(mask))
            raise InputError(f"{tab.path}, line {tab.lines[i]}: {what}")

    for c in _OPTIONAL[1:]:
        if c in tab:
            nan = np.isnan(tab[c])
            if nan.any() and not nan.all():
                bad(nan, f"column {c} is empty here but filled on other rows")
    bad(tab["range_m"] <= 0, "range_m must be > 0")
    az = tab["azimuth_deg"]
    bad((az < 0) | (az >= 360), "azimuth_deg must be in [0, 360)")
    if "elevation_deg" in tab:
        el = tab["elevation_deg"]
        bad(np.abs(el) > 90, "elevation_deg must be in [-90, 90]")
