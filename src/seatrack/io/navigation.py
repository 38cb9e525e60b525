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
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing_rad_to_deg
from seatrack.io.atomic import atomic_write
from seatrack.io.suspect import rad_per_s_warning
from seatrack.io.suspect import warn
from seatrack.io.table import between
from seatrack.io.table import check_times
from seatrack.io.table import positive
from seatrack.io.table import read_csv_table
from seatrack.io.table import seconds
from seatrack.navigation.navigator import Echoes
from seatrack.navigation.navigator import NavResult
from seatrack.progress import Progress

FloatArray = NDArray[np.float64]

__all__ = [
    "require_navigation",
    "read_echoes",
    "write_echoes",
    "read_gyro",
    "write_gyro",
    "write_nav",
    "NAV_COLUMNS",
]

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


#: largest |turn rate| accepted in GYRO.csv, deg/s (ten revolutions a second)
MAX_TURN_RATE_DPS = 3600.0


def read_echoes(path: str | Path) -> Echoes:
    """Read ECHOES.csv (angles to radians). Errors name the file and line.

    Checks: ``time_s`` finite, within +-:data:`~seatrack.io.table.MAX_TIME_S` and sorted
    (ties allowed: one pulse, several range bins); ``range_m`` in (0, 1e8] m;
    ``antenna_deg`` in [-360, 720]; ``amplitude`` finite when given.
    """
    t = read_csv_table(
        path,
        required=["time_s", "antenna_deg", "range_m"],
        optional=["amplitude"],
        checks=(seconds("time_s"), positive("range_m"), between("antenna_deg", -360.0, 720.0)),
    )
    check_times(t, "time_s", strict=False)
    a = t["antenna_deg"]
    return Echoes(t["time_s"], np.mod(np.radians(a), 2 * np.pi), t["range_m"], t.path, t.lines)


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
    with atomic_write(path) as fh:
        np.savetxt(fh, np.column_stack(cols), fmt=fmt, delimiter=",", header=head, comments="")


def read_gyro(path: str | Path) -> tuple[FloatArray, FloatArray]:
    """Read GYRO.csv; returns times (s) and turn rates (rad/s).

    Checks: ``time_s`` finite, within +-:data:`~seatrack.io.table.MAX_TIME_S` and strictly
    increasing; ``|turn_rate_dps| <=`` :data:`MAX_TURN_RATE_DPS`.
    """
    lim = MAX_TURN_RATE_DPS
    t = read_csv_table(
        path,
        required=["time_s", "turn_rate_dps"],
        checks=(seconds("time_s"), between("turn_rate_dps", -lim, lim)),
    )
    check_times(t, "time_s", strict=True)
    warn([rad_per_s_warning(t.path, "turn_rate_dps", t["turn_rate_dps"])])
    return t["time_s"], np.radians(t["turn_rate_dps"])


def write_gyro(path: str | Path, t: ArrayLike, rate: ArrayLike) -> None:
    """Write GYRO.csv from times (s) and turn rates (rad/s)."""
    data = np.column_stack([np.asarray(t, float), np.degrees(np.asarray(rate, float))])
    with atomic_write(path) as fh:
        np.savetxt(fh, data, fmt=["%.3f", "%.6f"], delimiter=",", header="time_s,turn_rate_dps",
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
    with atomic_write(path) as fh:
        np.savetxt(fh, data, fmt=fmt, delimiter=",", header=",".join(NAV_COLUMNS), comments="")


#: peak bytes per predictor tick of a navigation run, an estimate: the state, its sigmas
#: and time (104 bytes) in the loop and the result, and the NAV.csv text being written
NAV_BYTES_PER_TICK = 500
#: seconds per predictor tick of the navigation loop, an estimate (a log of 9.6e6 cycles
#: takes about 15 min on a 2-core machine: 94 us)
NAV_SECONDS_PER_TICK = 1e-4


def require_navigation(
    echoes: Echoes, antenna_period_s: float, steps_per_rev: int, command: str = "seatrack navigate"
) -> Progress:
    """Refuse a navigation run over the memory or time budget (:mod:`seatrack.io.budget`),
    from the span of the echo log: one predictor tick per ``antenna_period_s /
    steps_per_rev`` seconds, however few the echoes (a gap costs as much as a log).
    Returns the run's :class:`~seatrack.progress.Progress` (in filter cycles)."""
    from seatrack.io.budget import require

    t = np.asarray(echoes.t, float)
    span = float(t.max() - t.min()) if t.size >= 2 else 0.0
    ticks = span * steps_per_rev / antenna_period_s
    seconds = ticks * NAV_SECONDS_PER_TICK
    require(
        f"{echoes.source}: the echo log spans {span:g} s, {ticks:.3g} filter cycles",
        memory_bytes=ticks * NAV_BYTES_PER_TICK,
        seconds=seconds,
    )
    return Progress(command, ticks, "filter cycles", seconds)
