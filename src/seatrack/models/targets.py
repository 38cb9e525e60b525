"""Target classes: typical kinematics of ships, submarines, aircraft and fighters, and the
filter parameters they imply.

A :class:`TargetClass` holds the physical quantities of a kind of target (speeds, the
random accelerations of steady motion, the lateral acceleration and turn rate of its
manoeuvres, how long manoeuvres and straight legs last), each with its source in
:attr:`TargetClass.sources`. From them it derives the process-noise parameters each kind
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
from dataclasses import dataclass
from dataclasses import field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import solve_discrete_are
from scipy.linalg import solve_discrete_lyapunov
from scipy.optimize import minimize_scalar

from seatrack.geometry import G0

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
    "SteadyState",
    "cv_steady_state",
    "predicted_mse",
    "suggest_parameters",
]

_DEG = math.pi / 180.0
_KN = 1852.0 / 3600.0

#: the numeric fields every class documents in ``sources``
_DOCUMENTED = (
    "speed_typical",
    "speed_max",
    "accel_steady",
    "accel_typical",
    "accel_max",
    "accel_tangential",
    "turn_rate_typical",
    "turn_rate_max",
    "manoeuvre_time",
    "straight_time",
    "turn_onset_time",
    "p_max_accel",
)


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
# The four classes
# ---------------------------------------------------------------------------
_IMO = "IMO MSC.137(76) (tactical diameter <= 5 L, advance <= 4.5 L)"
_COCKCROFT = "Cockcroft & Lameijer, Guide to the Collision Avoidance Rules, manoeuvring information"
_SINGER = "Singer 1970 / Li & Jilkov 2003 sec. IV (tau_m ~ 60 s lazy turn, 10-20 s evasive)"
_ASSUMED = "assumption (no published figure found); see seatrack.models.targets"

SHIP = TargetClass(
    name="ship",
    speed_typical=12 * _KN,
    speed_max=30 * _KN,
    accel_steady=0.01,
    accel_typical=0.05,
    accel_max=0.5,
    accel_tangential=0.05,
    turn_rate_typical=0.5 * _DEG,
    turn_rate_max=3.0 * _DEG,
    manoeuvre_time=180.0,
    straight_time=900.0,
    turn_onset_time=30.0,
    p_max_accel=0.05,
    sources={
        "speed_typical": "merchant service speed 10-15 kn (bundled AIS samples: "
        "median SOG 6-14 kn of the moving vessels, seatrack/data/ais/README.md)",
        "speed_max": "fast ferries / HSC / naval vessels ~30 kn (AIS sample: HSC at 15 kn "
        "median, 22 kn peak)",
        "accel_steady": _ASSUMED + ": course kept within ~1 deg and speed within ~0.2 kn "
        "over a minute at 12 kn",
        "accel_typical": "turn_rate_typical x speed_typical = 0.0087 rad/s x 6.2 m/s",
        "accel_tangential": _ASSUMED + ": a change of 3 kn in 30 s (engine orders)",
        "accel_max": "speed change and turn of a small fast craft: 3 deg/s at 10 m/s = "
        "0.52 m/s^2; merchant ships stay below 0.2 m/s^2 (" + _IMO + ")",
        "turn_rate_typical": _COCKCROFT + ": 90 deg in 2-3 min (0.5-0.75 deg/s)",
        "turn_rate_max": "small craft / pilot boats: the AIS sample's port tender turns "
        "671 deg in 5 min (2.2 deg/s); " + _IMO + " gives 1.7 deg/s for L = 100 m at 15 kn",
        "manoeuvre_time": _COCKCROFT + ": 90 deg in 2-3 min",
        "straight_time": _ASSUMED + ": coastal legs of 10-20 min between alterations",
        "turn_onset_time": _IMO + ": 10 deg heading change within 2.5 L of 10 deg rudder "
        "(about 30 s for L = 100 m at 8 m/s)",
        "p_max_accel": _ASSUMED,
    },
)

SUBMARINE = TargetClass(
    name="submarine",
    speed_typical=8 * _KN,
    speed_max=33 * _KN,
    accel_steady=0.005,
    accel_typical=0.04,
    accel_max=0.3,
    accel_tangential=0.03,
    turn_rate_typical=0.5 * _DEG,
    turn_rate_max=2.0 * _DEG,
    manoeuvre_time=120.0,
    straight_time=1200.0,
    turn_onset_time=30.0,
    p_max_accel=0.05,
    sources={
        "speed_typical": "tactical speed 8-13 kn of nuclear submarines "
        "(Wikipedia, 'Tactical speed')",
        "speed_max": "USS Scranton (SSN-756): 33 kn submerged (Wikipedia, 'Tactical speed')",
        "accel_steady": _ASSUMED + ": submerged, no sea-state forcing (half the ship's)",
        "accel_typical": "turn_rate_typical x speed_typical = 0.0087 rad/s x 4.1 m/s",
        "accel_max": _ASSUMED + ": 2 deg/s at 8 m/s (0.28 m/s^2)",
        "accel_tangential": _ASSUMED + ": a change of 2 kn in 30 s",
        "turn_rate_typical": _ASSUMED + ": as a ship of the same length (" + _COCKCROFT + ")",
        "turn_rate_max": _ASSUMED + ": tactical diameter ~4 L, L = 100 m, at 8 kn (" + _IMO + ")",
        "manoeuvre_time": _SINGER,
        "straight_time": _ASSUMED + ": long quiet legs of 20 min and more",
        "turn_onset_time": _IMO + " (as the ship)",
        "p_max_accel": _ASSUMED,
    },
)

AIRCRAFT = TargetClass(
    name="aircraft",
    speed_typical=120.0,
    speed_max=250.0,
    accel_steady=0.1,
    accel_typical=5.0,
    accel_max=G0 * math.tan(30 * _DEG),
    accel_tangential=1.0,
    turn_rate_typical=3.0 * _DEG,
    turn_rate_max=3.0 * _DEG,
    manoeuvre_time=60.0,
    straight_time=240.0,
    turn_onset_time=5.0,
    p_max_accel=0.1,
    sources={
        "speed_typical": "approach / terminal-area speeds 90-150 m/s (175-290 kn)",
        "speed_max": "cruise ~250 m/s (Mach 0.8 at altitude)",
        "accel_steady": _ASSUMED + ": light turbulence and autopilot corrections",
        "accel_typical": "standard-rate turn at 100 m/s: 0.052 rad/s x 100 m/s = 5.2 m/s^2 "
        "(28 deg bank)",
        "accel_max": "ICAO: holding turns at 25 deg bank or rate one; 30 deg bank "
        "(g tan 30 = 5.7 m/s^2) is the usual airliner limit",
        "accel_tangential": _ASSUMED + ": terminal-area speed changes of about 2 kn/s",
        "turn_rate_typical": "SKYbrary 'Standard Rate Turn': 3 deg/s",
        "turn_rate_max": "SKYbrary: rate one (3 deg/s) at low speed, rate half (1.5 deg/s) "
        "above 250 kn",
        "manoeuvre_time": _SINGER + "; a standard-rate 180 deg turn takes 60 s",
        "straight_time": _ASSUMED + ": terminal-area legs of a few minutes",
        "turn_onset_time": _ASSUMED + ": roll-in to 25-30 deg bank in about 5 s",
        "p_max_accel": _ASSUMED,
    },
)

FIGHTER = TargetClass(
    name="fighter",
    speed_typical=250.0,
    speed_max=600.0,
    accel_steady=0.5,
    accel_typical=4.0 * G0,
    accel_max=9.0 * G0,
    accel_tangential=G0,
    turn_rate_typical=4.0 * G0 / 250.0,
    turn_rate_max=9.0 * G0 / 250.0,
    manoeuvre_time=15.0,
    straight_time=30.0,
    turn_onset_time=1.0,
    p_max_accel=0.1,
    sources={
        "speed_typical": "air-combat speeds 200-300 m/s",
        "speed_max": "Mach 2 at altitude (~600 m/s), F-16 class",
        "accel_steady": _ASSUMED + ": between manoeuvres of an air-combat engagement",
        "accel_typical": "3-6 g turns (the issue's fighter scenario), 4 g typical",
        "accel_max": "F-16: first fighter built to sustain 9 g turns (7 g with a centreline tank)",
        "accel_tangential": _ASSUMED + ": 1 g along track (afterburner / speed brake)",
        "turn_rate_typical": "accel_typical / speed_typical (4 g at 250 m/s = 9 deg/s)",
        "turn_rate_max": "accel_max / speed_typical (9 g at 250 m/s = 20 deg/s)",
        "manoeuvre_time": _SINGER + ": evasive manoeuvre 10-20 s",
        "straight_time": _ASSUMED + ": tens of seconds between manoeuvres in combat",
        "turn_onset_time": _ASSUMED + ": fly-by-wire g onset within about 1 s",
        "p_max_accel": _ASSUMED,
    },
)

#: name -> class
TARGET_CLASSES: MappingProxyType[str, TargetClass] = MappingProxyType(
    {c.name: c for c in (SHIP, SUBMARINE, AIRCRAFT, FIGHTER)}
)


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
