"""ECHOES.csv, GYRO.csv and NAV.csv (landmark navigation files; degrees at the edge).

* ECHOES.csv: ``time_s``, ``antenna_deg`` (antenna angle relative to the bow, clockwise),
  ``range_m``, optional ``amplitude``; one row per above-threshold sample, sorted by time
  (several rows may share a time: one pulse, several range bins).
* GYRO.csv: ``time_s``, ``turn_rate_dps`` (clockwise positive), strictly increasing times.
* NAV.csv: ``time_s, x_m, y_m, heading_deg, vx_mps, vy_mps, turn_rate_dps, std_x_m,
  std_y_m, std_heading_deg``, one row per filter cycle.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seatrack.geometry import bearing_rad_to_deg
from seatrack.io.table import InputError, check_times, read_csv_table
from seatrack.navigation.navigator import Echoes, NavResult

FloatArray = NDArray[np.float64]

__all__ = ["read_echoes", "write_echoes", "read_gyro", "write_gyro", "write_nav", "NAV_COLUMNS"]

NAV_COLUMNS = (
    "time_s",
    "x_m",
    "y_m",
    "heading_deg",
    "vx_mps",
    "vy_mps",
    "turn_rate_dps",
    "std_x_m",
    "std_y_m",
    "std_heading_deg",
)


def read_echoes(path: str | Path) -> Echoes:
    """Read ECHOES.csv (angles to radians). Errors name the file and line."""
    t = read_csv_table(path, required=["time_s", "antenna_deg", "range_m"], optional=["amplitude"])
    check_times(t, "time_s", strict=False)
    r = t["range_m"]
    bad = np.flatnonzero(r <= 0)
    if bad.size:
        raise InputError(
            f"{t.path}, line {t.lines[bad[0]]}: range_m = {r[bad[0]]:g} must be positive"
        )
    a = t["antenna_deg"]
    bad = np.flatnonzero((a < -360.0) | (a > 720.0))
    if bad.size:
        raise InputError(
            f"{t.path}, line {t.lines[bad[0]]}: antenna_deg = {a[bad[0]]:g} "
            "is not an angle in degrees"
        )
    return Echoes(t["time_s"], np.mod(np.radians(a), 2 * np.pi), r, t.path, t.lines)


def write_echoes(path: str | Path, t: ArrayLike, antenna: ArrayLike, rng: ArrayLike,
                 amplitude: ArrayLike | None = None) -> None:  # fmt: skip
    """Write ECHOES.csv from times (s), antenna angles (rad) and ranges (m)."""
    cols = [np.asarray(t, float), np.degrees(np.asarray(antenna, float)), np.asarray(rng, float)]
    head = "time_s,antenna_deg,range_m"
    fmt = ["%.6f", "%.4f", "%.1f"]
    if amplitude is not None:
        cols.append(np.asarray(amplitude, float))
        head += ",amplitude"
        fmt.append("%.1f")
    np.savetxt(path, np.column_stack(cols), fmt=fmt, delimiter=",", header=head, comments="")


def read_gyro(path: str | Path) -> tuple[FloatArray, FloatArray]:
    """Read GYRO.csv; returns times (s) and turn rates (rad/s)."""
    t = read_csv_table(path, required=["time_s", "turn_rate_dps"])
    check_times(t, "time_s", strict=True)
    return t["time_s"], np.radians(t["turn_rate_dps"])


def write_gyro(path: str | Path, t: ArrayLike, rate: ArrayLike) -> None:
    """Write GYRO.csv from times (s) and turn rates (rad/s)."""
    data = np.column_stack([np.asarray(t, float), np.degrees(np.asarray(rate, float))])
    np.savetxt(path, data, fmt=["%.3f", "%.6f"], delimiter=",", header="time_s,turn_rate_dps",
               comments="")  # fmt: skip


def write_nav(path: str | Path, res: NavResult) -> None:
    """Write NAV.csv (heading in [0, 360) deg, rates in deg/s)."""
    x, s = res.x, res.std
    data = np.column_stack(
        [
            res.t,
            x[:, 0],
            x[:, 1],
            bearing_rad_to_deg(x[:, 2]),
            x[:, 3],
            x[:, 4],
            np.degrees(x[:, 5]),
            s[:, 0],
            s[:, 1],
            np.degrees(s[:, 2]),
        ]
    )
    fmt = ["%.3f", "%.2f", "%.2f", "%.3f", "%.3f", "%.3f", "%.4f", "%.2f", "%.2f", "%.3f"]
    np.savetxt(path, data, fmt=fmt, delimiter=",", header=",".join(NAV_COLUMNS), comments="")
