"""Navigation filter: state, prediction, landmark measurement rows, Kalman and SRIF forms.

Spec ``landmark_nav.md``, "Inputs and state", "Prediction", "Gating ... and the measurement".

State ``x = [X, Y, alpha, Xdot, Ydot, alphadot]`` of the reference point F: East, North (m),
heading ``alpha`` (rad, clockwise from North), velocity (m/s) and turn rate (rad/s,
clockwise positive). The radar antenna E is ``a`` metres aft of F:
``E = (X - a sin alpha, Y - a cos alpha)``. (Positions first, then velocities, as everywhere
in seatrack: the heading is the third "position" and the turn rate its "velocity".)

Landmark measurements are *linearised innovations* (measured minus predicted, metres):
for a point reflector the range offset ``dr`` and the cross-range offset
``dtheta = r_c (phi - phi_c)``; for a contour element with normal ``beta`` the normal offset
``z = cos(theta - beta) dr - sin(theta - beta) dtheta``. Their Jacobians are the spec's
derived rows (the patent's G13 has a sign slip):

* ``h_r = [-sin th, -cos th, a sin(th - alpha), 0, 0, 0]``
* ``h_t = [-cos th,  sin th, a cos(th - alpha) - r, 0, 0, 0]``
* ``h_z = [-sin beta, -cos beta, a sin(beta - alpha) + r sin(th - beta), 0, 0, 0]``

Two interchangeable filters take the same calls: :class:`KalmanNav` (covariance form,
Joseph update through :mod:`seatrack.kalman`) and :class:`SRIFNav` (square-root information
form: ``[R | zeta]`` re-triangularised by Householder QR for both the time and measurement
updates). Given the same data they give the same estimate to round-off. Both follow the
state contract of :mod:`seatrack.filters.base`: configuration in the object, the state
(:class:`~seatrack.filters.base.TrackState`, a batch of one ship) in and out of
``initiate``, ``predict(state, t)`` and ``update(state, y, H, R)`` -- the update takes a
linearised measurement (innovation, rows, noise), because the navigation measurements
(landmark echoes, gyro, GNSS, log, compass) are not target plots.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any
from typing import Protocol

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.filters.base import TrackState
from seatrack.filters.base import finish_update
from seatrack.filters.base import predicted
from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.kalman import extended_predict
from seatrack.kalman import extended_update
from seatrack.kalman import nis_log_likelihood

FloatArray = NDArray[np.float64]

__all__ = [
    "NX",
    "STATE_NAMES",
    "ProcessNoise",
    "antenna_position",
    "landmark_geometry",
    "nav_transition",
    "nav_noise",
    "point_rows",
    "contour_row",
    "point_measurement",
    "contour_measurement",
    "gyro_row",
    "gnss_rows",
    "log_speed",
    "compass_row",
    "NavFilter",
    "KalmanNav",
    "SRIFNav",
]

NX = 6  #: state size
#: component names of the navigation state (positions first, as everywhere in seatrack)
STATE_NAMES = ("x", "y", "heading", "vx", "vy", "turn_rate")


@dataclass(frozen=True)
class ProcessNoise:
    """Continuous white-noise power spectral densities of the spec's constant matrix B.

    The spec leaves B unspecified [reading]; seatrack uses the continuous white-noise
    model on each (position, rate) pair: (X, Xdot), (Y, Ydot), (alpha, alphadot).

    Attributes
    ----------
    q_vel : m^2/s^3, acceleration PSD on each horizontal axis.
    q_turn : rad^2/s^3, turn-acceleration PSD.
    """

    q_vel: float = 0.02
    q_turn: float = 1e-6


# ---------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------
def antenna_position(x: ArrayLike, a: float = 0.0) -> FloatArray:
    """Antenna E (East, North; m) for state ``x``, ``a`` metres aft of F."""
    s = np.asarray(x, float)
    return np.array([s[0] - a * np.sin(s[2]), s[1] - a * np.cos(s[2])])


def landmark_geometry(
    x: ArrayLike, landmark: ArrayLike, a: float = 0.0
) -> tuple[float, float, float]:
    """Predicted range ``r_c`` (m), true bearing ``theta_c`` (rad, [0, 2 pi)) and antenna
    angle ``phi_c = theta_c - alpha`` (rad, (-pi, pi]) of a landmark (spec "Prediction")."""
    e = antenna_position(x, a)
    d = np.asarray(landmark, float)[:2] - e
    th = float(bearing(d[0], d[1]))
    return float(np.hypot(d[0], d[1])), th, float(wrap_pi(th - float(np.asarray(x)[2])))


# ---------------------------------------------------------------------------
# Prediction
# ---------------------------------------------------------------------------
def nav_transition(x: ArrayLike, dt: float) -> tuple[FloatArray, FloatArray]:
    """Spec prediction over ``dt`` s and its Jacobian.

    ``X += Xdot dt, Y += Ydot dt, alpha += alphadot dt, Xdot += Ydot alphadot dt,
    Ydot -= Xdot alphadot dt`` (the velocity turns with the turn rate), ``alphadot``
    constant. Returns ``(f(x), F)`` with ``F = df/dx``.
    """
    s = np.asarray(x, float)
    vx, vy, w = s[3], s[4], s[5]
    fx = s + dt * np.array([vx, vy, w, vy * w, -vx * w, 0.0])
    F = np.eye(NX)
    F[0, 3] = F[1, 4] = F[2, 5] = dt
    F[3, 4] = w * dt
    F[3, 5] = vy * dt
    F[4, 3] = -w * dt
    F[4, 5] = -vx * dt
    return fx, F


_POS = np.arange(3)


def nav_noise(dt: float, noise: ProcessNoise) -> FloatArray:
    """Process noise ``B`` over ``dt``: continuous white noise on each (position, rate) pair.

    Per pair with PSD ``q``: ``q [[dt^3/3, dt^2/2], [dt^2/2, dt]]`` (BLK 6.2.2), i.e.
    :func:`seatrack.models.motion.cv_noise` with ``d = 3`` and a PSD per axis (written
    out here because it runs at every predictor tick; the tests check the two agree).
    """
    q = np.array([noise.q_vel, noise.q_vel, noise.q_turn])
    Q = np.zeros((NX, NX))
    Q[_POS, _POS] = q * (dt**3 / 3.0)
    Q[_POS, _POS + 3] = Q[_POS + 3, _POS] = q * (dt**2 / 2.0)
    Q[_POS + 3, _POS + 3] = q * dt
    return Q


# ---------------------------------------------------------------------------
# Landmark measurement rows (spec "Linearisation")
# ---------------------------------------------------------------------------
def point_rows(x: ArrayLike, landmark: ArrayLike, a: float = 0.0) -> FloatArray:
    """Jacobian rows ``[h_r; h_t]`` (2, 6) of range and cross-range of a point reflector."""
    s = np.asarray(x, float)
    r, th, _ = landmark_geometry(s, landmark, a)
    al = s[2]
    H = np.zeros((2, NX))
    H[0, :3] = [-np.sin(th), -np.cos(th), a * np.sin(th - al)]
    H[1, :3] = [-np.cos(th), np.sin(th), a * np.cos(th - al) - r]
    return H


def contour_row(x: ArrayLike, landmark: ArrayLike, beta: float, a: float = 0.0) -> FloatArray:
    """Jacobian row ``h_z`` (6,) of the normal offset of a contour element (normal ``beta``)."""
    s = np.asarray(x, float)
    r, th, _ = landmark_geometry(s, landmark, a)
    h = np.zeros(NX)
    h[:3] = [-np.sin(beta), -np.cos(beta), a * np.sin(beta - s[2]) + r * np.sin(th - beta)]
    return h


def point_measurement(
    x: ArrayLike, landmark: ArrayLike, a: float, r_c: float, phi_c: float
) -> FloatArray:
    """Nonlinear point-reflector measurement ``[r(x), r_c wrap(phi(x) - phi_c)]`` (m).

    ``r_c``, ``phi_c`` are the predicted range and antenna angle at the linearisation
    point (they scale and offset the cross-range). Used to check :func:`point_rows`.
    """
    r, _, phi = landmark_geometry(x, landmark, a)
    return np.array([r, r_c * float(wrap_pi(phi - phi_c))])


def contour_measurement(
    x: ArrayLike,
    landmark: ArrayLike,
    beta: float,
    a: float,
    r_c: float,
    theta_c: float,
    phi_c: float,
) -> float:
    """Nonlinear contour measurement (m).

    ``cos(th_c - beta) r(x) - sin(th_c - beta) r_c (phi(x) - phi_c)``; checks :func:`contour_row`.
    """
    m = point_measurement(x, landmark, a, r_c, phi_c)
    return float(np.cos(theta_c - beta) * m[0] - np.sin(theta_c - beta) * m[1])


# ---------------------------------------------------------------------------
# Other sensors
# ---------------------------------------------------------------------------
def gyro_row() -> FloatArray:
    """Gyro turn rate measures ``alphadot`` directly [reading]: ``H = e_6``."""
    h = np.zeros(NX)
    h[5] = 1.0
    return h


def gnss_rows() -> FloatArray:
    """GNSS position of F (East, North): ``H`` (2, 6)."""
    H = np.zeros((2, NX))
    H[0, 0] = H[1, 1] = 1.0
    return H


def log_speed(x: ArrayLike) -> tuple[float, FloatArray]:
    """Log speed (m/s) along the bow ``Xdot sin alpha + Ydot cos alpha`` and its row (6,)."""
    s = np.asarray(x, float)
    sa, ca = np.sin(s[2]), np.cos(s[2])
    h = np.zeros(NX)
    h[2] = s[3] * ca - s[4] * sa
    h[3], h[4] = sa, ca
    return float(s[3] * sa + s[4] * ca), h


def compass_row() -> FloatArray:
    """Compass heading measures ``alpha``: ``H = e_3`` (innovation wrapped to (-pi, pi])."""
    h = np.zeros(NX)
    h[2] = 1.0
    return h


# ---------------------------------------------------------------------------
# Filters
# ---------------------------------------------------------------------------
class NavFilter(Protocol):
    """Common interface of :class:`KalmanNav` and :class:`SRIFNav`: the state contract of
    :mod:`seatrack.filters.base` (:class:`TrackState`, ``initiate``, ``predict(state, t)``)
    with an update that takes a *linearised measurement* -- the innovation ``y``, its rows
    ``H`` and noise ``R`` -- rather than target plots: landmark echoes, gyro, GNSS, log and
    compass each linearise their own measurement (:func:`point_measurement`, ...).
    The navigation state is one ship: a batch of one track.
    """

    state_names: tuple[str, ...]

    def initiate(self, t: float, x: ArrayLike, P: ArrayLike) -> TrackState: ...

    def predict(self, state: TrackState, t: float) -> TrackState: ...

    def update(self, state: TrackState, y: ArrayLike, H: ArrayLike, R: ArrayLike) -> TrackState: ...


def _tri_inv(T: NDArray[Any], lower: bool) -> FloatArray:
    """Inverse of a triangular matrix (LAPACK ``dtrtri``; unthreaded, fast for 6 x 6)."""
    inv, info = scipy.linalg.lapack.dtrtri(T, lower=int(lower))
    if info != 0:
        raise np.linalg.LinAlgError(f"singular triangular factor (dtrtri info {info})")
    return np.asarray(inv)


def _tri_solve(R: NDArray[Any], b: NDArray[Any]) -> FloatArray:
    """Solve ``R x = b`` for upper-triangular ``R`` (LAPACK ``dtrtrs``)."""
    x, info = scipy.linalg.lapack.dtrtrs(R, b, lower=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"singular square-root information matrix (dtrtrs info {info})")
    return np.asarray(x)


def _measurement(
    y: ArrayLike, H: ArrayLike, R: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    return (
        np.atleast_1d(np.asarray(y, float)),
        np.atleast_2d(np.asarray(H, float)),
        np.atleast_2d(np.asarray(R, float)),
    )


class KalmanNav:
    """Extended Kalman filter in covariance form (Joseph update via :mod:`seatrack.kalman`).

    Parameters
    ----------
    noise : ProcessNoise
    """

    state_names: tuple[str, ...] = STATE_NAMES

    def __init__(self, noise: ProcessNoise | None = None) -> None:
        self.noise = noise or ProcessNoise()

    def initiate(self, t: float, x: ArrayLike, P: ArrayLike) -> TrackState:
        """The state at ``t`` from mean ``x (6,)`` and covariance ``P (6, 6)``."""
        return TrackState.new([t], np.asarray(x, float)[None], np.asarray(P, float)[None])

    def predict(self, state: TrackState, t: float) -> TrackState:
        """Spec prediction to ``t``: ``x <- f(x)``, ``A <- F A F^T + B`` (no change when
        ``t`` is not later than the state)."""
        dt = float(t) - float(state.t[0])
        if dt <= 0:
            return state
        fx, F = nav_transition(state.x[0], dt)
        x, P = extended_predict(fx, state.P[0], F, nav_noise(dt, self.noise))
        return predicted(state, np.array([float(t)]), x[None], P[None])

    def update(self, state: TrackState, y: ArrayLike, H: ArrayLike, R: ArrayLike) -> TrackState:
        """Update with the linearised innovation ``y = z - h(x)`` (m,), rows ``H`` (m, 6)
        and noise ``R`` (m, m). A measurement whose innovation covariance is not positive
        definite, or that would give a non-finite state, is rejected (status REJECTED)."""
        yy, HH, RR = _measurement(y, H, R)
        x = state.x[0]
        res = extended_update(x, state.P[0], yy, np.zeros_like(yy), HH, RR, check=False)
        return finish_update(
            state, res.x[None], res.P[None], np.atleast_1d(res.nis),
            np.atleast_1d(res.log_likelihood), state.t,
        )  # fmt: skip


class SRIFNav:
    """Square-root information filter: ``R x = zeta`` with ``R^T R = P^-1``.

    Time update (linearised about the current estimate ``x``, ``u = f(x) - F x``): the
    stacked system ``[[-W F, W | W u], [R, 0 | zeta]]`` with ``W = chol(B)^-1`` is
    re-triangularised by Householder QR; the lower-right block is the new ``[R | zeta]``.
    Measurement update: append the whitened rows ``[W_R H | W_R (y + H x)]`` to
    ``[R | zeta]`` and re-triangularise (spec "Update"; Bierman 1977, ch. V-VI).
    ``TrackState.aux`` holds ``R (1, 6, 6)`` and ``zeta (1, 6)``; ``x`` and ``P`` are
    derived from them.
    """

    state_names: tuple[str, ...] = STATE_NAMES

    def __init__(self, noise: ProcessNoise | None = None) -> None:
        self.noise = noise or ProcessNoise()

    @staticmethod
    def _state(t: FloatArray, Rm: FloatArray, zeta: FloatArray, prior: TrackState | None) -> Any:
        x = _tri_solve(Rm, zeta)
        Ri = _tri_inv(Rm, lower=False)
        P = Ri @ Ri.T
        P = 0.5 * (P + P.T)
        aux = {"R": Rm[None], "zeta": zeta[None]}
        if prior is None:
            return TrackState.new(t, x[None], P[None], aux)
        return x, P, aux

    def initiate(self, t: float, x: ArrayLike, P: ArrayLike) -> TrackState:
        L = np.linalg.cholesky(np.asarray(P, float))
        R0 = _tri_inv(L, lower=True)
        T = _qr_r(np.column_stack([R0, R0 @ np.asarray(x, float)]))
        return self._state(np.array([float(t)]), T[:NX, :NX], T[:NX, NX], None)  # type: ignore[no-any-return]

    def predict(self, state: TrackState, t: float) -> TrackState:
        dt = float(t) - float(state.t[0])
        if dt <= 0:
            return state
        Rm, zeta, x0 = state.aux["R"][0], state.aux["zeta"][0], state.x[0]
        fx, F = nav_transition(x0, dt)
        Lq = np.linalg.cholesky(nav_noise(dt, self.noise))
        W = _tri_inv(Lq, lower=True)
        u = fx - F @ x0
        top = np.column_stack([-W @ F, W, W @ u])
        bot = np.column_stack([Rm, np.zeros((NX, NX)), zeta])
        T = _qr_r(np.vstack([top, bot]))
        x, P, aux = self._state(state.t, T[NX : 2 * NX, NX : 2 * NX], T[NX : 2 * NX, 2 * NX], state)
        return predicted(state, np.array([float(t)]), x[None], P[None], aux)

    def update(self, state: TrackState, y: ArrayLike, H: ArrayLike, R: ArrayLike) -> TrackState:
        yy, HH, RR = _measurement(y, H, R)
        Rm, zeta, x0 = state.aux["R"][0], state.aux["zeta"][0], state.x[0]
        try:
            nis, ll = nis_log_likelihood(yy, HH @ state.P[0] @ HH.T + RR)
            Wr = _tri_inv(np.linalg.cholesky(RR), lower=True)
            rows = np.column_stack([Wr @ HH, Wr @ (yy + HH @ x0)])
            T = _qr_r(np.vstack([np.column_stack([Rm, zeta]), rows]))
            x, P, aux = self._state(state.t, T[:NX, :NX], T[:NX, NX], state)
        except np.linalg.LinAlgError:  # an unusable measurement: rejected below
            x, P, aux, nis, ll = x0, state.P[0], {}, np.nan, np.nan
        return finish_update(
            state, x[None], P[None], np.atleast_1d(nis), np.atleast_1d(ll), state.t, aux
        )


def _qr_r(A: FloatArray) -> FloatArray:
    """The triangular factor of a Householder QR."""
    return np.asarray(np.linalg.qr(A, mode="r"), dtype=np.float64)
