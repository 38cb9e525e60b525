"""``seatrack.navigate``: own-ship position and heading from radar echoes of mapped
landmarks (JP H03-66630), as ``seatrack navigate``; the frame holds the values of NAV.csv.
"""

from __future__ import annotations

import contextlib
import math
import tempfile
from collections.abc import Mapping
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from seatrack.api.inputs import Source
from seatrack.api.inputs import as_file
from seatrack.api.inputs import read_frame
from seatrack.api.options import option_in
from seatrack.api.options import option_positive
from seatrack.io.table import MAX_DISTANCE_M
from seatrack.io.table import InputError

__all__ = [
    "navigate",
    "navigator_config",
    "start_state",
    "run_navigation",
    "check_origin",
    "OPTION_NAMES",
    "MAX_START_SPEED_MPS",
    "MAX_ANTENNA_OFFSET_M",
]

#: largest own-ship speed accepted at the start, m/s (about 200 kn)
MAX_START_SPEED_MPS = 100.0
#: largest antenna offset from the reference point, m
MAX_ANTENNA_OFFSET_M = 1000.0


#: the ``seatrack navigate`` option of each argument of :func:`navigate`: the ``names``
#: the command gives :func:`start_state`, :func:`navigator_config` and :func:`check_origin`
OPTION_NAMES: dict[str, str] = {
    "start": "--start",
    "antenna_period_s": "--antenna-period",
    "range_limit_m": "--range-limit",
    "antenna_offset_m": "--antenna-offset",
    "method": "--method",
    "clutter_density": "--clutter-density",
    "origin": "--origin",
}


def _names(names: Mapping[str, str] | None) -> dict[str, str]:
    """Argument -> the name messages give it: ``names``, else the argument itself."""
    return {k: k for k in OPTION_NAMES} | dict(names or {})


def start_state(
    x_m: float,
    y_m: float,
    heading_deg: float,
    speed_mps: float,
    *,
    names: Mapping[str, str] | None = None,
) -> list[float]:
    """The initial state ``[X, Y, alpha, Xdot, Ydot, 0]`` (velocity along the heading).

    Raises
    ------
    InputError
        A value out of range (``|x|, |y| <= 1e8`` m, heading in [-360, 720] deg,
        ``|speed| <=`` :data:`MAX_START_SPEED_MPS`), named as ``start x_m`` etc. (``start``
        replaced by ``names["start"]``: ``--start x_m`` on the command line).
    """
    start = _names(names)["start"]
    option_in(f"{start} x_m", x_m, -MAX_DISTANCE_M, MAX_DISTANCE_M)
    option_in(f"{start} y_m", y_m, -MAX_DISTANCE_M, MAX_DISTANCE_M)
    option_in(f"{start} heading_deg", heading_deg, -360.0, 720.0)
    option_in(f"{start} speed_mps", speed_mps, -MAX_START_SPEED_MPS, MAX_START_SPEED_MPS)
    a = math.radians(heading_deg)
    return [x_m, y_m, a, speed_mps * math.sin(a), speed_mps * math.cos(a), 0.0]


def navigator_config(
    period: float,
    range_limit: float,
    offset: float,
    method: str,
    clutter: float,
    *,
    names: Mapping[str, str] | None = None,
) -> Any:
    """The :class:`~seatrack.navigation.navigator.NavigatorConfig` of the arguments of
    :func:`navigate` (each checked, named as :func:`navigate` names it, or as ``names``
    says: :data:`OPTION_NAMES` on the command line)."""
    from dataclasses import replace

    from seatrack.navigation.navigator import NavigatorConfig

    name = _names(names)
    option_positive(name["antenna_period_s"], period, 3600.0)
    option_positive(name["range_limit_m"], range_limit, MAX_DISTANCE_M)
    option_in(name["antenna_offset_m"], offset, -MAX_ANTENNA_OFFSET_M, MAX_ANTENNA_OFFSET_M)
    option_positive(name["clutter_density"], clutter, 1.0)
    if method not in ("ekf", "srif"):
        raise InputError(f"{name['method']} must be 'ekf' or 'srif', got {method!r}")
    cfg = NavigatorConfig(
        antenna_period=period, range_limit=range_limit, antenna_offset=offset, method=method
    )
    return replace(cfg, gate=replace(cfg.gate, clutter_density=clutter))


def check_origin(
    lat_deg: float, lon_deg: float, *, names: Mapping[str, str] | None = None
) -> tuple[float, float]:
    """``(lat_deg, lon_deg)`` of a local frame's origin, checked (named ``origin lat_deg``
    etc., ``origin`` replaced by ``names["origin"]``)."""
    origin = _names(names)["origin"]
    option_in(f"{origin} lat_deg", lat_deg, -90.0, 90.0)
    option_in(f"{origin} lon_deg", lon_deg, -180.0, 180.0)
    return lat_deg, lon_deg


def run_navigation(
    landmarks: Source,
    echoes: Source,
    x0: Sequence[float],
    cfg: Any,
    gyro: Source | None = None,
    origin: tuple[float, float] | None = None,
) -> Any:
    """Read the map, the echoes and the gyro rates and run the navigator
    (:func:`seatrack.navigation.navigator.navigate`); returns its ``NavResult``."""
    from seatrack.io.landmarks import read_map_csv
    from seatrack.io.navigation import read_echoes
    from seatrack.io.navigation import read_gyro
    from seatrack.io.navigation import require_navigation
    from seatrack.navigation.navigator import navigate as run

    with contextlib.ExitStack() as stack:
        lm = read_map_csv(stack.enter_context(as_file(landmarks, "map")), origin)
        ech = read_echoes(stack.enter_context(as_file(echoes, "echoes")))
        bar = require_navigation(ech, cfg.antenna_period, cfg.steps_per_rev)  # the budget
        gy = None if gyro is None else read_gyro(stack.enter_context(as_file(gyro, "gyro")))
    return run(lm, ech, list(x0), cfg, gyro=gy, progress=bar)


def navigate(
    landmarks: Source,
    echoes: Source,
    *,
    start: Sequence[float],
    gyro: Source | None = None,
    antenna_period_s: float = 2.5,
    range_limit_m: float = 3000.0,
    antenna_offset_m: float = 0.0,
    method: str = "ekf",
    clutter_density: float = 1e-5,
    origin: tuple[float, float] | None = None,
) -> Any:
    """Own-ship position and heading from radar echoes of mapped landmarks, as
    ``seatrack navigate``.

    Parameters
    ----------
    landmarks : path, pandas.DataFrame, pyarrow.Table or dict of arrays
        The MAP columns ``id, kind, x_m, y_m, orientation_deg`` (or ``lat_deg, lon_deg``
        with ``origin``).
    echoes : path, DataFrame, pyarrow Table or dict
        The ECHOES columns ``time_s, antenna_deg, range_m``.
    start : (x_m, y_m, heading_deg, speed_mps)
        Own-ship position (m), heading (degrees from North) and speed (m/s) at the first
        echo.
    gyro : path, DataFrame, pyarrow Table or dict, optional
        The GYRO columns ``time_s, turn_rate_dps``.
    antenna_period_s : float
        Antenna revolution period, s.
    range_limit_m : float
        Radar range used for the search window, m.
    antenna_offset_m : float
        Antenna aft of the reference point, m.
    method : {"ekf", "srif"}
        Kalman filter (Joseph form) or square-root information filter.
    clutter_density : float
        False echoes per m^2 per revolution.
    origin : (lat_deg, lon_deg), optional
        Origin of the local frame, for a map in latitude and longitude.

    Returns
    -------
    pandas.DataFrame
        The NAV.csv columns: ``time_s, x_m, y_m, heading_deg, vx_mps, vy_mps,
        turn_rate_dps, std_x_m, std_y_m, std_heading_deg``, one row per filter cycle.

    Examples
    --------
    A simulated river passage: landmarks along the banks, the radar samples above the
    threshold (clutter included) and the gyro, given as arrays:

    >>> import numpy as np, seatrack
    >>> from seatrack.simulate.radar_echoes import channel_landmarks
    >>> from seatrack.simulate.radar_echoes import river_route
    >>> from seatrack.simulate.radar_echoes import simulate_radar
    >>> route = river_route(1500.0, 4.0)
    >>> marks = channel_landmarks(route, 8, np.random.default_rng(1))
    >>> sim = simulate_radar(route, marks, np.random.default_rng(2))
    >>> m = sim.nav_map
    >>> landmarks = {"id": m.ids, "kind": np.where(m.is_contour, "contour", "point"),
    ...              "x_m": m.xy[:, 0], "y_m": m.xy[:, 1],
    ...              "orientation_deg": np.where(m.is_contour, np.degrees(m.orientation), np.nan)}
    >>> e = sim.echoes
    >>> echoes = {"time_s": e.t, "antenna_deg": np.degrees(e.antenna), "range_m": e.range}
    >>> gyro = {"time_s": sim.gyro_t, "turn_rate_dps": np.degrees(sim.gyro_rate)}
    >>> x0 = sim.truth[0]
    >>> start = (x0[0], x0[1], np.degrees(x0[2]), np.hypot(x0[3], x0[4]))
    >>> nav = seatrack.navigate(landmarks, echoes, start=start, gyro=gyro)
    >>> list(nav.columns[:4])
    ['time_s', 'x_m', 'y_m', 'heading_deg']
    >>> late = nav["time_s"] > 60
    >>> x = np.interp(nav["time_s"], sim.truth_t, sim.truth[:, 0])
    >>> y = np.interp(nav["time_s"], sim.truth_t, sim.truth[:, 1])
    >>> err = np.hypot(nav["x_m"] - x, nav["y_m"] - y)[late]
    >>> bool(np.sqrt(np.mean(err**2)) < 10.0)
    True
    """
    if len(start) != 4:
        raise InputError(f"start must be (x_m, y_m, heading_deg, speed_mps), got {start!r}")
    x0 = start_state(*(float(v) for v in start))
    cfg = navigator_config(
        antenna_period_s, range_limit_m, antenna_offset_m, method, clutter_density
    )
    if origin is not None:
        origin = check_origin(*origin)
    res = run_navigation(landmarks, echoes, x0, cfg, gyro, origin)
    from seatrack.io.navigation import write_nav

    with tempfile.TemporaryDirectory(prefix="seatrack-") as folder:
        out = Path(folder) / "nav.csv"
        write_nav(out, res)
        return read_frame(out)
