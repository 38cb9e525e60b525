"""Writing simulated measurements and truth as CSV files (degrees and knots at this edge).

* Plots (``PLOTS.csv`` format, read back by :func:`seatrack.io.plots.read_plots`):
  ``track,time_s,range_m,azimuth_deg[,elevation_deg][,range_rate_mps],sensor_x_m,sensor_y_m,sensor_z_m``;
  one row per detection, missed scans are left out.
* Bearings (``BEARINGS.csv`` for TMA):
  ``contact,time_s,bearing_deg,observer_x_m,observer_y_m,sigma_deg``.
* Truth: ``[target,]time_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,course_deg,speed_mps,turn_rate_dps``.

Numbers are written with full float precision (``repr``), so a file read back gives the
same values bit for bit. :func:`plots_from_measurements` builds the in-memory
:class:`~seatrack.filters.base.Plots` a track method takes, without a file.
"""

from __future__ import annotations

import csv
from collections.abc import Iterable
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import STATE_COLUMNS
from seatrack.filters.base import Plots
from seatrack.geometry import bearing_rad_to_deg
from seatrack.io.atomic import atomic_write
from seatrack.io.table import InputError
from seatrack.io.table import angle_deg
from seatrack.io.table import between
from seatrack.io.table import coordinate
from seatrack.io.table import read_csv_table
from seatrack.io.table import seconds
from seatrack.simulate.sensors import Measurements
from seatrack.simulate.trajectories import Trajectory

FloatArray = NDArray[np.float64]

__all__ = [
    "BEARING_COLUMNS",
    "TRUTH_COLUMNS",
    "plots_from_measurements",
    "write_plots",
    "write_clutter",
    "write_bearings",
    "write_truth",
    "write_target_states",
    "read_truth",
]

BEARING_COLUMNS = ("contact", "time_s", "bearing_deg", "observer_x_m", "observer_y_m", "sigma_deg")
TRUTH_COLUMNS = ("time_s", *STATE_COLUMNS, "course_deg", "speed_mps", "turn_rate_dps")


#: largest speed (m/s) accepted in a truth file (about 20,000 kn)
MAX_SPEED_MPS = 1e4
#: largest |turn rate| (deg/s) accepted in a truth file
MAX_TURN_RATE_DPS = 3600.0


def _num(v: float) -> str:
    return repr(float(v))


def _az_deg(rad: FloatArray) -> FloatArray:
    """Azimuth in degrees guaranteed inside [0, 360) after the conversion."""
    d = np.atleast_1d(np.asarray(bearing_rad_to_deg(rad), dtype=float))
    return np.where(d >= 360.0, 0.0, d)


def _component(meas: Measurements, name: str) -> FloatArray | None:
    if name not in meas.components:
        return None
    return meas.z[:, meas.components.index(name)]


def plots_from_measurements(meas: Measurements, track_id: str = "1") -> Plots:
    """In-memory :class:`~seatrack.filters.base.Plots` of the detected scans of ``meas`` (no file).

    Parameters
    ----------
    meas : Measurements
        Simulated range/azimuth(/elevation)(/range rate) measurements of one target.
    track_id : str

    Returns
    -------
    Plots
        Only detected scans, labelled ``track_id``; ``line`` holds the scan index of each
        plot (0-based), so outputs can be put back on the full scan grid with
        ``np.flatnonzero(meas.detected)``.
        Sensor velocity is the simulated one (not a finite difference).

    Raises
    ------
    ValueError
        If the measurements have no range or no azimuth.
    """
    rng = _component(meas, "range")
    az = _component(meas, "azimuth")
    if rng is None or az is None:
        raise ValueError(
            f"plots need range and azimuth; measurements have {', '.join(meas.components)}"
        )
    keep = np.flatnonzero(meas.detected)
    el = _component(meas, "elevation")
    rr = _component(meas, "range_rate")
    return Plots(
        t=meas.t[keep].copy(),
        range=rng[keep].copy(),
        azimuth=az[keep].copy(),
        elevation=None if el is None else el[keep].copy(),
        range_rate=None if rr is None else rr[keep].copy(),
        sensor=meas.sensor_pos[keep].copy(),
        sensor_vel=meas.sensor_vel[keep].copy(),
        line=keep.astype(np.int64),
        track=np.full(keep.size, str(track_id)),
    )


def write_plots(path: str | Path, tracks: Iterable[tuple[str, Measurements]]) -> int:
    """Write the detections of several targets to one PLOTS.csv file.

    Parameters
    ----------
    path : output file
    tracks : iterable of (track id, Measurements) -- each needs range and azimuth, all
        with the same components

    Returns
    -------
    int
        Number of rows written (rows sorted by time, then by track order).
    """
    tracks = list(tracks)
    if not tracks:
        raise ValueError("no tracks to write")
    comps = tracks[0][1].components
    for tid, m in tracks:
        if m.components != comps:
            raise ValueError(f"track {tid}: components {m.components} differ from {comps}")
    header = ["track", "time_s", "range_m", "azimuth_deg"]
    header += ["elevation_deg"] if "elevation" in comps else []
    header += ["range_rate_mps"] if "range_rate" in comps else []
    header += ["sensor_x_m", "sensor_y_m", "sensor_z_m"]
    rows: list[tuple[float, int, list[str]]] = []
    for order, (tid, m) in enumerate(tracks):
        p = plots_from_measurements(m, tid)
        az = _az_deg(p.azimuth) if len(p) else np.zeros(0)
        for i in range(len(p)):
            row = [str(tid), _num(p.t[i]), _num(p.range[i]), _num(az[i])]
            if p.elevation is not None:
                row.append(_num(np.degrees(p.elevation[i])))
            if p.range_rate is not None:
                row.append(_num(p.range_rate[i]))
            row += [_num(v) for v in p.sensor[i]]
            rows.append((float(p.t[i]), order, row))
    rows.sort(key=lambda r: (r[0], r[1]))
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(r[2] for r in rows)
    return len(rows)


def write_clutter(
    path: str | Path, t: FloatArray, rng: FloatArray, azimuth: FloatArray, sensor_pos: FloatArray
) -> int:
    """Write false plots: ``time_s,range_m,azimuth_deg,sensor_x_m,sensor_y_m,sensor_z_m``.

    Several false plots share a scan time, so this is not a track file for
    :func:`~seatrack.io.plots.read_plots` (which needs strictly increasing times per track).
    """
    az = _az_deg(azimuth) if np.size(t) else np.zeros(0)
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_s", "range_m", "azimuth_deg", "sensor_x_m", "sensor_y_m", "sensor_z_m"])
        for i in range(np.size(t)):
            w.writerow([_num(t[i]), _num(rng[i]), _num(az[i])] + [_num(v) for v in sensor_pos[i]])
    return int(np.size(t))


def write_bearings(
    path: str | Path, contacts: Iterable[tuple[str, Measurements]], sigma_deg: float
) -> int:
    """Write bearings of one or more contacts to a BEARINGS.csv file.

    Parameters
    ----------
    path : output file
    contacts : iterable of (contact id, Measurements with an ``azimuth`` component)
    sigma_deg : float
        Nominal bearing standard deviation (degrees) written on every row.

    Returns
    -------
    int
        Number of rows written (detected bearings only).
    """
    n = 0
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(BEARING_COLUMNS)
        for cid, m in contacts:
            b = _component(m, "azimuth")
            if b is None:
                raise ValueError(f"contact {cid}: measurements have no bearing (azimuth)")
            keep = np.flatnonzero(m.detected)
            deg = _az_deg(b[keep]) if keep.size else np.zeros(0)
            for j, i in enumerate(keep):
                w.writerow(
                    [
                        str(cid),
                        _num(m.t[i]),
                        _num(deg[j]),
                        _num(m.sensor_pos[i, 0]),
                        _num(m.sensor_pos[i, 1]),
                        _num(sigma_deg),
                    ]
                )
                n += 1
    return n


def write_truth(
    path: str | Path, trajectories: Sequence[tuple[str, Trajectory]] | Trajectory
) -> int:
    """Write truth trajectories (one file; a ``target`` column when given named trajectories).

    Parameters
    ----------
    path : output file
    trajectories : a Trajectory (no ``target`` column) or a sequence of (name, Trajectory)

    Returns
    -------
    int
        Number of rows written.
    """
    named = trajectories if not isinstance(trajectories, Trajectory) else [("", trajectories)]
    with_name = not isinstance(trajectories, Trajectory)
    n = 0
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow((["target"] if with_name else []) + list(TRUTH_COLUMNS))
        for name, tr in named:
            crs = _az_deg(tr.course)
            for i in range(tr.t.size):
                vals = [
                    tr.t[i],
                    *tr.pos[i],
                    *tr.vel[i],
                    crs[i],
                    tr.speed[i],
                    np.degrees(tr.turn_rate[i]),
                ]
                w.writerow(([name] if with_name else []) + [_num(v) for v in vals])
                n += 1
    return n


def write_target_states(
    path: str | Path, t: FloatArray, target: NDArray[np.int64], pos: FloatArray, vel: FloatArray
) -> int:
    """Write the truth of a multi-target run: one row per (time, live target) with
    ``time_s, target`` and the position and velocity columns (s, m, m/s); returns the rows."""
    cols = [t, *np.asarray(pos, dtype=float).T, *np.asarray(vel, dtype=float).T]
    text = [np.char.mod("%.6f", c) for c in cols]
    text.insert(1, np.asarray(target).astype(str))
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_s", "target", *STATE_COLUMNS])
        w.writerows(zip(*text, strict=True))
    return int(np.asarray(t).size)


def read_truth(path: str | Path) -> dict[str, Trajectory]:
    """Read a truth CSV written by :func:`write_truth` into trajectories keyed by target.

    A file without a ``target`` column gives one entry with key ``""``. Accelerations are
    not stored in the file and are returned as NaN.

    Raises
    ------
    InputError
        Naming the file and line (via :func:`seatrack.io.table.read_csv_table`): a value
        that is not a finite number or is implausible (``|time_s|`` beyond 2100 in Unix
        seconds, ``|x|`` over 1e8 m, speed over :data:`MAX_SPEED_MPS`, course outside
        [0, 360), turn rate over :data:`MAX_TURN_RATE_DPS`), or times not increasing.
    """
    checks = (
        seconds("time_s"),
        *(coordinate(c) for c in ("x_m", "y_m", "z_m")),
        *(between(c, -MAX_SPEED_MPS, MAX_SPEED_MPS) for c in ("vx_mps", "vy_mps", "vz_mps")),
        angle_deg("course_deg"),
        between("speed_mps", 0.0, MAX_SPEED_MPS),
        between("turn_rate_dps", -MAX_TURN_RATE_DPS, MAX_TURN_RATE_DPS),
    )
    tab = read_csv_table(path, TRUTH_COLUMNS, ("target",), text=("target",), checks=checks)
    names = tab["target"] if "target" in tab else np.full(len(tab), "")
    out: dict[str, Trajectory] = {}
    for name in dict.fromkeys(names.tolist()):
        sub = tab.subset(names == name)
        t = sub["time_s"]
        if np.any(np.diff(t) <= 0):
            i = int(np.argmax(np.diff(t) <= 0)) + 1
            raise InputError(
                f"{tab.path}, line {sub.lines[i]}: time_s not increasing for target {name!r}"
            )
        pos = np.stack([sub["x_m"], sub["y_m"], sub["z_m"]], -1)
        vel = np.stack([sub["vx_mps"], sub["vy_mps"], sub["vz_mps"]], -1)
        out[str(name)] = Trajectory(
            t,
            pos,
            vel,
            np.full_like(pos, np.nan),
            np.radians(sub["course_deg"]),
            sub["speed_mps"],
            np.radians(sub["turn_rate_dps"]),
        )
    return out
