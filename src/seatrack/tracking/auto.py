"""The per-track filter from the registry, with process noise chosen from the data when the
user gives none.

* The scan period ``T``: the median interval between distinct plot times.
* Any registered method (:mod:`seatrack.filters.registry`) is built from the user's
  configuration table (method keys, sensor keys flat or in ``[sensor]``) for the plots'
  dimensions; 2-D methods track 3-D plots in the horizontal plane.
* Process noise, when the table has none of the method's noise keys (:data:`NOISE_KEYS`),
  follows :data:`AUTO_NOISE`, chosen per method on the tuning scenarios of
  ``benchmarks/multitarget.py --methods`` (disjoint from its evaluation scenarios):

  - ``"levels"`` -- the method's white-noise-acceleration PSD ``q`` is set to the
    straight-leg level of the target class, ``q_s = a_s^2 T`` (``a_s`` = 0.02 m/s^2: sea
    and steering), and the filter is wrapped in
    :class:`~seatrack.tracking.adaptive.NoiseLevels`, an IMM that adds
    ``q_m = accel^2 T / 2`` during manoeuvres (``accel`` = 0.7 m/s^2 for ships: a 3 deg/s
    turn at 27 kn; switching probability :data:`P_SWITCH` per scan; a new track starts on
    a straight leg with probability :data:`P_START`; optional coordinated-turn models,
    :data:`TURN_RATE` each way, off by default: on the tuning scenarios they lower the
    mean GOSPA by 1.7 % but cost 37-42 % more time per scan at 1,000 ships, and their
    variable-structure form loses the gain first -- docs/tracking.md);
  - ``"wrap"`` -- the method as its defaults configure it, wrapped in the same IMM (its
    own noise is the low level);
  - ``"own"`` -- the method's defaults, untouched (a method with its own manoeuvre
    handling, or one the wrapper did not improve).

  A method whose noise keys the user set is always used as configured.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from seatrack.filters.registry import Method
from seatrack.filters.registry import build
from seatrack.filters.registry import method_class
from seatrack.models.motion import ALONG_TRACK_RATIO
from seatrack.tracking.adaptive import NoiseLevels

__all__ = [
    "SHIP_ACCEL",
    "STRAIGHT_ACCEL",
    "P_SWITCH",
    "P_START",
    "TURN_RATE",
    "TURN_ACCEL",
    "TURN_THRESHOLD",
    "AUTO_NOISE",
    "NOISE_KEYS",
    "scan_period",
    "noise_levels",
    "user_gave_noise",
    "per_track_filter",
]

#: manoeuvre acceleration of the default target class (ships), m/s^2
SHIP_ACCEL = 0.7
#: acceleration noise on straight legs, m/s^2 (tuning scenarios of
#: ``benchmarks/multitarget.py``: 0.05 / 0.03 / 0.02 / 0.01 -> mean GOSPA 152.9 / 152.3 /
#: 152.1 / 152.1 m with the other defaults of this module; their legs are exactly straight)
STRAIGHT_ACCEL = 0.02
#: probability per scan of switching between the noise levels
P_SWITCH = 0.01
#: probability that a new track starts in the straight-leg level (ships sail straight most
#: of the time; tuning scenarios: 0.5 / 0.8 / 0.9 / 0.95 -> 152.6 / 152.2 / 152.1 / 152.2 m)
P_START = 0.9

#: turn rate of the coordinated-turn models of the noise IMM (one each way), deg/s; 0: none
#: (the default of ``TrackerConfig.turn_rate``, key ``turn_rate_dps``). Tuning scenarios,
#: turn models on every track, off / 1.5 / 2 / 3 deg/s -> mean GOSPA 152.14 / 150.10 /
#: 149.56 / 150.32 m; off by default: at 2 deg/s +37-42 % processor time per scan at 1,000
#: ships, +8-10 % at S10's scale (docs/tracking.md)
TURN_RATE = 0.0
#: white-noise acceleration of the turn models, m/s^2 (their PSD ``a^2 T``; 2 deg/s turns:
#: 0.05 / 0.15 -> 149.56 / 149.83 m)
TURN_ACCEL = 0.05
#: a track evaluates its turn models while the probability that it is off the straight-leg
#: level exceeds this (:class:`~seatrack.tracking.adaptive.NoiseLevels` ``turn_threshold``;
#: 0 / 0.05 / 0.1 / 0.2 / 0.5 -> 149.56 / 151.05 / 151.62 / 152.54 / 152.48 m, with
#: 100 / 95 / 65 / 30 / 20 % of the track-scans evaluating them)
TURN_THRESHOLD = 0.0

#: automatic process noise of each registered method (see the module docstring), from the
#: mean GOSPA (m) on the tuning scenarios given only the sensor noise, own / wrap [/ levels]
#: (``python benchmarks/multitarget.py --methods``, with each method's defaults)
AUTO_NOISE: dict[str, str] = {
    "ekf": "levels",  # 180.2 / 181.2 / 152.1 (its default q = 1 suits no target class)
    "ekf-rb": "wrap",  # 177.3 / 152.2: its sonar q (0.02 m/s^2) needs the manoeuvre level
    "huber": "own",  # 156.6 / 156.6: a level IMM already (wrap is void)
    "student-t": "own",  # 155.9 / 155.9: idem
    "robust": "own",  # 156.6 / 156.6: idem
    "robust-adaptive": "own",  # 155.8 / 155.8: idem
    "turning": "own",  # 155.5 / 155.5: idem
    "imm": "own",  # 183.9 / 183.9: its update starts from its model states (wrap is void)
    "mm": "own",  # 155.5 / 155.5: a level IMM already
    "mm-rangerate": "own",  # as mm (needs range rate: not in the tuning scenarios)
    # the sources' methods run as their sources describe, process noise included
    "turning-spec": "own",  # 172.4 / 173.5
    "robust-spec": "own",  # 182.1 / 182.1
    "robust-adaptive-spec": "own",  # 184.5 / 184.4
    "mm-spec": "own",  # 248.8 / 248.8
    "mm-rangerate-spec": "own",
}

#: configuration keys that set a method's process noise or target class
NOISE_KEYS = frozenset(
    {"q", "q_nominal", "q_cv", "q_ct", "q_omega", "sigma_accel", "sigma_accel_mps2",
     "accel", "accel_g", "sigma_a", "target"}
)  # fmt: skip


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


def user_gave_noise(table: Mapping[str, Any]) -> bool:
    """Whether a method table sets the process noise (or the target class)."""
    return bool(NOISE_KEYS & set(table))


def per_track_filter(
    name: str,
    table: Mapping[str, Any] | None,
    d: int,
    range_rate: bool,
    period: float,
    source: str = "config",
    rule: str | None = None,
    turn_rate: float = math.radians(TURN_RATE),
) -> tuple[Method, str]:
    """The per-track filter ``name`` for ``d``-D plots, and the noise rule applied.

    Parameters
    ----------
    name : a registered method
    table : method keys and sensor keys (flat or ``[sensor]``)
    d, range_rate : the plots' dimensions and whether they carry range rate
    period : scan period (s), for the automatic noise levels
    rule : override :data:`AUTO_NOISE` (``"levels"``, ``"wrap"``, ``"own"``; for the
        benchmark that chooses the table)
    turn_rate : rad/s -- coordinated-turn models of the automatic noise IMM, one each way
        (0: none; ``TrackerConfig.turn_rate``)

    Returns
    -------
    (Method, rule) -- ``rule`` is ``"given"`` when the table sets the noise.
    """
    tab = dict(table or {})
    if user_gave_noise(tab):
        return build(name, tab, d=d, range_rate=range_rate, source=source), "given"
    how = rule or AUTO_NOISE.get(name, "own")
    if how not in ("levels", "wrap", "own"):
        raise ValueError(f"unknown noise rule {how!r}")
    q_s, q_m = noise_levels(period)
    if how == "levels":
        fields = {f.name for f in dataclasses.fields(method_class(name).Config)}
        if "q" not in fields:
            raise ValueError(f"method {name} has no q: its automatic noise cannot be 'levels'")
        m = build(name, {**tab, "q": q_s}, d=d, range_rate=range_rate, source=source)
    else:
        m = build(name, tab, d=d, range_rate=range_rate, source=source)
    if how == "own":
        return m, how
    own = q_s if how == "levels" else 0.0
    w = float(turn_rate)
    levels = NoiseLevels(
        m.filter,
        (0.0, q_m - own),
        P_SWITCH,
        along_track_ratio=ALONG_TRACK_RATIO,
        start=P_START,
        turn_rates=(w, -w) if w > 0 else (),
        turn_noise=max(TURN_ACCEL**2 * period - own, 0.0),
        turn_threshold=TURN_THRESHOLD,
    )
    return dataclasses.replace(m, filter=levels), how
