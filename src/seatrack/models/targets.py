"""Target classes: typical kinematics of ships, submarines, aircraft and fighters, and the
filter parameters they imply.

A :class:`TargetClass` holds the physical quantities of a kind of target (speeds, the
random accelerations of steady motion, the lateral acceleration and turn rate of its
manoeuvres, how long manoeuvres and straight legs last), each with its source in
:attr:`TargetClass.sources`. The four classes (:data:`TARGET_CLASSES`) are data: their
figures, units and sources are in ``seatrack/data/target_classes.toml``, read once at import
(:func:`load_target_classes`). From them it derives the process-noise parameters each kind
of filter needs, as documented rules of thumb:

* CV white-noise acceleration PSD ``q`` (m^2/s^3) for steady and for manoeuvring motion:
  the velocity change over one scan ``T`` should be of the order of the acceleration
  times ``T`` -- ``q = sigma_a^2 T`` makes the continuous model's velocity variance per
  scan ``q T`` equal to that of a piecewise-constant acceleration of std ``sigma_a``, for
  which Bar-Shalom, Li & Kirubarajan (2001, sec. 6.3.2) give the practical range
  ``0.5 a_M <= sigma_a <= a_M`` (``a_M`` the largest acceleration); the upper end is used.
* Singer model (Singer 1970; Li & Jilkov 2003, sec. IV): manoeuvre time constant
  ``tau_m`` = the typical manoeuvre duration, acceleration variance
  ``sigma_m^2 = A_max^2 / 3 (1 + 4 P_max - P_0)``.
* Coordinated turn: white acceleration ``q = a_t^2 T`` for the speed changes
  (``a_t`` the tangential acceleration) and turn-rate random-walk PSD
  ``q_omega = omega_typ^2 / tau_m`` (the turn rate wanders by its typical value over one
  manoeuvre time; ``omega_typ^2 / t_onset`` is the fast variant).
* IMM mode persistence: ``p_stay = exp(-T / tau)`` with ``tau`` the mean sojourn time of
  the mode (straight legs for the non-manoeuvring mode, manoeuvre duration for the
  manoeuvring one); for ``T << tau`` this is the familiar ``1 - T / tau`` (mean sojourn
  ``T / (1 - p_stay)``, Bar-Shalom et al. 2001, ch. 11).

:func:`suggest_parameters` turns a class, a scan interval and a sensor's noise into
suggested parameters, among them the tracking (manoeuvring) index
``lambda = sigma_a T^2 / sigma_w`` (Kalata 1984) and the fixed ``q`` of a CV Kalman
filter that minimises the predicted steady-state position mean squared error -- noise
plus the lag (bias) in a typical manoeuvre, weighted by the fraction of time spent
manoeuvring (the design idea of Blair 2008, evaluated here exactly with the steady-state
Riccati solution instead of closed-form alpha-beta approximations).

References
----------
* Y. Bar-Shalom, X. R. Li, T. Kirubarajan, *Estimation with Applications to Tracking and
  Navigation*, Wiley 2001 (ch. 6 process-noise design, ch. 11 IMM).
* S. Blackman, R. Popoli, *Design and Analysis of Modern Tracking Systems*, Artech House
  1999.
* R. A. Singer, "Estimating optimal tracking filter performance for manned maneuvering
  targets", IEEE Trans. AES-6(4), 1970.
* X. R. Li, V. P. Jilkov, "Survey of maneuvering target tracking. Part I: Dynamic models",
  IEEE Trans. AES-39(4), 2003.
* P. R. Kalata, "The tracking index: a generalized parameter for alpha-beta and
  alpha-beta-gamma target trackers", IEEE Trans. AES-20(2), 1984.
* W. D. Blair, "Design of nearly constant velocity track filters for tracking maneuvering
  targets", Proc. FUSION 2008.
* IMO resolution MSC.137(76), *Standards for ship manoeuvrability*, 2002; A. N. Cockcroft,
  J. N. F. Lameijer, *A Guide to the Collision Avoidance Rules* (manoeuvring information:
  a merchant ship turns 90 deg in 2-3 min, a full circle in 5-10 min).
* SKYbrary, "Standard Rate Turn" (3 deg/s; rate-half 1.5 deg/s for fast aircraft); ICAO
  holding turns at 25 deg bank or rate one, whichever is less.

Units: SI and radians inside (m/s, m/s^2, rad/s, s).
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import solve_discrete_are
from scipy.linalg import solve_discrete_lyapunov
from scipy.optimize import minimize_scalar

from seatrack.geometry import G0
from seatrack.geometry import KNOT_MPS

FloatArray = NDArray[np.float64]

__all__ = [
    "TargetClass",
    "FilterSuggestion",
    "TARGET_CLASSES",
    "SHIP",
    "SUBMARINE",
    "AIRCRAFT",
    "FIGHTER",
    "target_class",
    "load_target_classes",
    "SteadyState",
    "cv_steady_state",
    "predicted_mse",
    "suggest_parameters",
]

_DEG = math.pi / 180.0

_SPEED = MappingProxyType({"kn": KNOT_MPS, "mps": 1.0})
_ACCEL = MappingProxyType({"mps2": 1.0, "g": G0})
_RATE = MappingProxyType({"dps": _DEG, "rad_s": 1.0})
_TIME = MappingProxyType({"s": 1.0})
#: the numeric fields every class documents in ``sources``, each with the unit keys the
#: table of classes may give it in and their factor to SI (radians)
_UNITS: MappingProxyType[str, MappingProxyType[str, float]] = MappingProxyType(
    {
        "speed_typical": _SPEED,
        "speed_max": _SPEED,
        "accel_steady": _ACCEL,
        "accel_typical": _ACCEL,
        "accel_max": _ACCEL,
        "accel_tangential": _ACCEL,
        "turn_rate_typical": _RATE,
        "turn_rate_max": _RATE,
        "manoeuvre_time": _TIME,
        "straight_time": _TIME,
        "turn_onset_time": _TIME,
        "p_max_accel": MappingProxyType({"value": 1.0}),
    }
)
_DOCUMENTED = tuple(_UNITS)


@dataclass(frozen=True)
class TargetClass:
    """Typical kinematics of one kind of target (SI units, radians).

    Attributes
    ----------
    name : str
    speed_typical, speed_max : m/s -- cruising / tactical speed and the maximum speed.
    accel_steady : m/s^2 -- rms of the small random accelerations on straight legs (sea
        state, turbulence, autopilot and helmsman corrections).
    accel_typical : m/s^2 -- lateral acceleration of a typical manoeuvre
        (``turn_rate_typical * speed_typical``, rounded).
    accel_max : m/s^2 -- the largest acceleration of the class.
    accel_tangential : m/s^2 -- typical along-track acceleration of a speed change (what a
        coordinated-turn model's white acceleration must cover).
    turn_rate_typical, turn_rate_max : rad/s.
    manoeuvre_time : s -- typical duration of a manoeuvre (Singer's time constant).
    straight_time : s -- mean time between manoeuvres.
    turn_onset_time : s -- time to establish a turn (rudder and yaw response, roll-in).
    p_max_accel : float -- Singer's probability of the maximum acceleration.
    sources : field -> where the number comes from.
    """

    name: str
    speed_typical: float
    speed_max: float
    accel_steady: float
    accel_typical: float
    accel_max: float
    accel_tangential: float
    turn_rate_typical: float
    turn_rate_max: float
    manoeuvre_time: float
    straight_time: float
    turn_onset_time: float
    p_max_accel: float
    sources: Any = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        for f in _DOCUMENTED:
            v = getattr(self, f)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"target class {self.name}: {f} must be positive, got {v!r}")
        if not self.speed_typical <= self.speed_max:
            raise ValueError(f"target class {self.name}: speed_typical > speed_max")
        if not self.accel_tangential <= self.accel_max:
            raise ValueError(f"target class {self.name}: accel_tangential > accel_max")
        if not self.accel_steady <= self.accel_typical <= self.accel_max:
            raise ValueError(
                f"target class {self.name}: need accel_steady <= accel_typical <= accel_max"
            )
        if not self.turn_rate_typical <= self.turn_rate_max:
            raise ValueError(f"target class {self.name}: turn_rate_typical > turn_rate_max")
        if not self.p_max_accel < 0.5:
            raise ValueError(f"target class {self.name}: p_max_accel must be < 0.5")
        missing = [f for f in _DOCUMENTED if f not in self.sources]
        if missing:
            raise ValueError(f"target class {self.name}: no source for {', '.join(missing)}")
        object.__setattr__(self, "sources", MappingProxyType(dict(self.sources)))

    # -- derived process-noise parameters --------------------------------------------
    @property
    def manoeuvre_fraction(self) -> float:
        """Long-run fraction of time spent manoeuvring."""
        return self.manoeuvre_time / (self.manoeuvre_time + self.straight_time)

    def q_steady(self, dt: float) -> float:
        """CV white-noise acceleration PSD for straight legs, m^2/s^3 (``accel_steady^2 T``)."""
        return self.accel_steady**2 * _positive(dt, "dt")

    def q_manoeuvre(self, dt: float) -> float:
        """CV PSD that covers a typical manoeuvre, m^2/s^3 (``accel_typical^2 T``)."""
        return self.accel_typical**2 * _positive(dt, "dt")

    def q_max(self, dt: float) -> float:
        """CV PSD that covers the hardest manoeuvre, m^2/s^3 (``accel_max^2 T``)."""
        return self.accel_max**2 * _positive(dt, "dt")

    @property
    def singer_tau(self) -> float:
        """Singer manoeuvre time constant ``tau_m = 1/alpha``, s."""
        return self.manoeuvre_time

    @property
    def singer_sigma(self) -> float:
        """Singer acceleration std, m/s^2: ``sqrt(A_max^2/3 (1 + 4 P_max - P_0))`` with
        ``P_0`` the fraction of time without manoeuvre."""
        p0 = 1.0 - self.manoeuvre_fraction
        return math.sqrt(self.accel_max**2 / 3.0 * (1.0 + 4.0 * self.p_max_accel - p0))

    @property
    def singer_q(self) -> float:
        """PSD of the white noise driving the Singer acceleration, ``2 sigma_m^2 / tau_m``
        (m^2/s^5)."""
        return 2.0 * self.singer_sigma**2 / self.singer_tau

    def q_tangential(self, dt: float) -> float:
        """White-acceleration PSD of a coordinated-turn model, m^2/s^3
        (``accel_tangential^2 T``: speed changes are all that is left to it)."""
        return self.accel_tangential**2 * _positive(dt, "dt")

    @property
    def q_turn_rate(self) -> float:
        """Coordinated-turn turn-rate random-walk PSD, rad^2/s^3: ``omega_typ^2 / tau_m``
        (the turn rate wanders by its typical value over one manoeuvre time)."""
        return self.turn_rate_typical**2 / self.manoeuvre_time

    @property
    def q_turn_rate_onset(self) -> float:
        """The fast variant ``omega_typ^2 / t_onset`` (the turn rate can reach its typical
        value within the onset time of a turn), rad^2/s^3."""
        return self.turn_rate_typical**2 / self.turn_onset_time

    def p_stay(self, dt: float) -> tuple[float, float]:
        """IMM persistence ``(p_stay_straight, p_stay_manoeuvre)`` for scan interval ``dt``."""
        T = _positive(dt, "dt")
        return math.exp(-T / self.straight_time), math.exp(-T / self.manoeuvre_time)

    def transition_matrix(self, dt: float) -> FloatArray:
        """Two-mode IMM transition matrix ``pi[i, j] = P(mode j at k | mode i at k-1)``
        (rows sum to one; mode 0 straight, mode 1 manoeuvring)."""
        a, b = self.p_stay(dt)
        return np.array([[a, 1.0 - a], [1.0 - b, b]])


def _positive(v: float, name: str) -> float:
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive number, got {v!r}")
    return float(v)


# ---------------------------------------------------------------------------
# The four classes, read from seatrack/data/target_classes.toml
# ---------------------------------------------------------------------------
#: the bundled table of target classes (figures, units and sources), in seatrack/data
_TABLE_FILE = "target_classes.toml"

_REFERENCE = re.compile(r"\{([A-Za-z_]+)\}")


def load_target_classes(path: str | Path | None = None) -> MappingProxyType[str, TargetClass]:
    """Target classes from a TOML table (default: the bundled
    ``seatrack/data/target_classes.toml``, the source of :data:`TARGET_CLASSES`).

    Every class is a table of the fields of :class:`TargetClass` (name excepted), each a
    table with its value under the key of its unit (``kn``/``mps``, ``mps2``/``g``,
    ``dps``/``rad_s``, ``s``; ``value`` for ``p_max_accel``) and its ``source``; a source
    may cite an entry of the ``[references]`` table as ``{NAME}``. Values are converted to
    SI and radians (``value * factor``).

    Raises
    ------
    ValueError
        Naming the file and the key, for a missing or unknown key, a unit not allowed for
        the field, a value that is not a number, an unknown reference, or figures that
        :class:`TargetClass` refuses.
    """
    if path is None:
        text = (resources.files("seatrack") / "data" / _TABLE_FILE).read_text("utf-8")
        where = f"seatrack/data/{_TABLE_FILE}"
    else:
        text, where = Path(path).read_text(encoding="utf-8"), str(path)
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{where}: {e}") from None
    refs = doc.pop("references", {})
    if not isinstance(refs, dict) or not all(isinstance(v, str) for v in refs.values()):
        raise ValueError(f"{where}: references: expected a table of strings")
    classes = {}
    for name, table in doc.items():
        if not isinstance(table, dict):
            raise ValueError(f"{where}: {name}: expected a table of fields")
        _check_keys(where, name, set(table), set(_UNITS))
        figures = {f: _figure(where, f"{name}.{f}", table[f], _UNITS[f], refs) for f in _UNITS}
        try:
            classes[name] = TargetClass(
                name,
                **{f: v for f, (v, _) in figures.items()},
                sources={f: s for f, (_, s) in figures.items()},
            )
        except ValueError as e:
            raise ValueError(f"{where}: {e}") from None
    if not classes:
        raise ValueError(f"{where}: no target class")
    return MappingProxyType(classes)


def _check_keys(where: str, key: str, given: set[str], wanted: set[str]) -> None:
    if given - wanted:
        raise ValueError(f"{where}: {key}: unknown key(s) {', '.join(sorted(given - wanted))}")
    if wanted - given:
        raise ValueError(f"{where}: {key}: missing key(s) {', '.join(sorted(wanted - given))}")


def _figure(
    where: str, key: str, table: Any, units: Mapping[str, float], refs: Mapping[str, str]
) -> tuple[float, str]:
    """``(value in SI, source)`` of one ``[CLASS.FIELD]`` table."""
    if not isinstance(table, dict):
        raise ValueError(f"{where}: {key}: expected a table (unit key and source)")
    allowed = f"the value goes under one unit key of {', '.join(units)}, beside source"
    extra = sorted(set(table) - set(units) - {"source"})
    if extra:
        raise ValueError(f"{where}: {key}: unknown key(s) {', '.join(extra)} ({allowed})")
    unit = [k for k in table if k in units]
    if len(unit) != 1:
        raise ValueError(f"{where}: {key}: {len(unit)} unit keys ({allowed})")
    if "source" not in table:
        raise ValueError(f"{where}: {key}: missing key(s) source")
    v, source = table[unit[0]], table["source"]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ValueError(f"{where}: {key}.{unit[0]}: expected a number, got {v!r}")
    if not isinstance(source, str):
        raise ValueError(f"{where}: {key}.source: expected a string, got {source!r}")
    unknown = [r for r in _REFERENCE.findall(source) if r not in refs]
    if unknown:
        raise ValueError(f"{where}: {key}.source: unknown reference {{{unknown[0]}}}")
    return v * units[unit[0]], _REFERENCE.sub(lambda m: refs[m.group(1)], source)


#: name -> class (ship, submarine, aircraft, fighter), from the bundled table
TARGET_CLASSES: MappingProxyType[str, TargetClass] = load_target_classes()
SHIP = TARGET_CLASSES["ship"]
SUBMARINE = TARGET_CLASSES["submarine"]
AIRCRAFT = TARGET_CLASSES["aircraft"]
FIGHTER = TARGET_CLASSES["fighter"]


def target_class(name: str) -> TargetClass:
    """The target class called ``name`` (ValueError listing the known ones)."""
    try:
        return TARGET_CLASSES[name]
    except KeyError:
        raise ValueError(
            f"unknown target class {name!r}; choose one of {', '.join(TARGET_CLASSES)}"
        ) from None


# ---------------------------------------------------------------------------
# Steady-state CV Kalman filter on one axis, and the suggested parameters
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class SteadyState:
    """Steady-state behaviour of a one-axis CV Kalman filter with white-noise acceleration
    PSD ``q``, position noise ``sigma`` and scan ``T``.

    Attributes
    ----------
    alpha, beta : steady-state gains (position, velocity * T).
    noise_var : filtered position variance from measurement noise (plus the true process
        noise ``q_true``) -- a Lyapunov solution of the error dynamics.
    lag : filtered position error per m/s^2 of a constant acceleration (the bias; negative:
        the estimate trails).
    """

    alpha: float
    beta: float
    noise_var: float
    lag: float


def _cv_axis(T: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    F = np.array([[1.0, T], [0.0, 1.0]])
    Q1 = np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
    g = np.array([T**2 / 2, T])
    return F, Q1, g


def cv_steady_state(q: float, sigma: float, T: float, q_true: float = 0.0) -> SteadyState:
    """Steady state of a CV Kalman filter (one axis) designed with PSD ``q`` (m^2/s^3).

    The error ``e = estimate - truth`` of the filtered estimate obeys
    ``e+ = A e+ - (I - K H)(w + g a) + K v`` with ``A = (I - K H) F``: its covariance
    solves a discrete Lyapunov equation (measurement noise ``sigma^2``, true process noise
    PSD ``q_true``), and a constant acceleration ``a`` gives the bias (lag)
    ``-(I - A)^-1 (I - K H) g a`` (``g = [T^2/2, T]``).
    """
    F, Q1, g = _cv_axis(T)
    H = np.array([[1.0, 0.0]])
    R = np.array([[sigma**2]])
    P = solve_discrete_are(F.T, H.T, q * Q1 + 1e-12 * np.eye(2) * sigma**2, R)
    K = P @ H.T / (H @ P @ H.T + R)[0, 0]
    IKH = np.eye(2) - K @ H
    A = IKH @ F
    W = IKH @ (q_true * Q1) @ IKH.T + K @ R @ K.T
    S = solve_discrete_lyapunov(A, W)
    lag = -np.linalg.solve(np.eye(2) - A, IKH @ g)
    return SteadyState(float(K[0, 0]), float(K[1, 0] * T), float(S[0, 0]), float(lag[0]))


@dataclass(frozen=True)
class FilterSuggestion:
    """Filter parameters suggested for a target class, scan interval and sensor.

    Attributes
    ----------
    target : class name.
    dt : s -- scan interval.
    sigma_position : (2,) m -- plot noise along and across the line of sight at the range.
    tracking_index_steady, tracking_index_manoeuvre : Kalata's ``sigma_a T^2 / sigma_w``
        with the cross-range sigma and the steady / typical-manoeuvre acceleration.
    q_steady, q_manoeuvre, q_max : m^2/s^3 -- narrow-band, typical-manoeuvre and
        hardest-manoeuvre CV PSDs (``a^2 T``).
    q_fixed : m^2/s^3 -- one fixed CV PSD minimising the predicted position MSE
        (steady noise everywhere, plus the squared lag of a typical manoeuvre for the
        manoeuvring fraction of the time).
    predicted_rmse : m -- the square root of that MSE.
    q_turn_rate : rad^2/s^3 -- CT turn-rate random-walk PSD.
    singer_tau : s; singer_sigma : m/s^2.
    p_stay : (straight, manoeuvre) -- IMM persistence for ``dt``.
    """

    target: str
    dt: float
    sigma_position: tuple[float, float]
    tracking_index_steady: float
    tracking_index_manoeuvre: float
    q_steady: float
    q_manoeuvre: float
    q_max: float
    q_fixed: float
    predicted_rmse: float
    q_turn_rate: float
    singer_tau: float
    singer_sigma: float
    p_stay: tuple[float, float]


def predicted_mse(target: TargetClass, q: float, sigmas: tuple[float, ...], dt: float) -> float:
    """Predicted position MSE (m^2, summed over axes) of a CV filter with PSD ``q`` on
    ``target``: steady-state noise with the true steady process noise everywhere, plus the
    squared manoeuvre lag weighted by :attr:`TargetClass.manoeuvre_fraction`."""
    q_true = target.q_steady(dt)  # the steady motion itself, by the same a^2 T rule
    f = target.manoeuvre_fraction
    mse = 0.0
    for s in sigmas:
        ss = cv_steady_state(q, s, dt, q_true=q_true)
        mse += ss.noise_var + f * (ss.lag * target.accel_typical) ** 2 / len(sigmas)
    return mse


def suggest_parameters(
    target: TargetClass | str,
    dt: float,
    sigma_range: float,
    sigma_azimuth: float,
    range_: float,
) -> FilterSuggestion:
    """Suggested filter parameters for ``target`` seen every ``dt`` s by a sensor with
    noise ``sigma_range`` (m) and ``sigma_azimuth`` (rad) at a typical range ``range_`` (m).

    The manoeuvre lag is split evenly between the two axes (a turn accelerates the target
    across its track, which is along or across the line of sight with equal chance).
    """
    tc = target_class(target) if isinstance(target, str) else target
    T = _positive(dt, "dt")
    sig = (_positive(sigma_range, "sigma_range"), _positive(sigma_azimuth, "sigma_azimuth"))
    R = _positive(range_, "range_")
    sigmas = (sig[0], R * sig[1])
    sw = max(sigmas)

    def objective(logq: float) -> float:
        return predicted_mse(tc, math.exp(logq), sigmas, T)

    lo, hi = math.log(tc.q_steady(T) * 1e-2), math.log(tc.q_max(T) * 1e2)
    res = minimize_scalar(objective, bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    q_fixed = math.exp(float(res.x))
    return FilterSuggestion(
        target=tc.name,
        dt=T,
        sigma_position=(float(sigmas[0]), float(sigmas[1])),
        tracking_index_steady=tc.accel_steady * T**2 / sw,
        tracking_index_manoeuvre=tc.accel_typical * T**2 / sw,
        q_steady=tc.q_steady(T),
        q_manoeuvre=tc.q_manoeuvre(T),
        q_max=tc.q_max(T),
        q_fixed=q_fixed,
        predicted_rmse=math.sqrt(float(res.fun)),
        q_turn_rate=tc.q_turn_rate,
        singer_tau=tc.singer_tau,
        singer_sigma=tc.singer_sigma,
        p_stay=tc.p_stay(T),
    )
