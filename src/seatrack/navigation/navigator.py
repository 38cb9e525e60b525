"""The navigation loop: predictor ticks, active window, scheduler, echo trap and updates.

Spec ``landmark_nav.md`` end to end. The predictor runs at a fixed rate (every 1/16 of an
antenna turn). One landmark at a time is *armed*: when the antenna has swept past its gate
the echo points inside the gate are taken from the log (a slice of the log sorted by
antenna angle, no loop over pulses), weighted, reduced to the landmark measurement and
used to update the filter at the time the antenna crossed the gate centre; then the
scheduler arms the next landmark. The active window is revised once per revolution. The
gyro turn rate (and, optionally, GNSS position, log speed and compass heading) are fused
at the predictor ticks.

Antenna angle
-------------
The echo log gives the antenna angle relative to the bow of each echo point. The antenna
turns at a constant rate (``antenna_period``); its phase is estimated from the log as the
circular mean of ``angle - 2 pi t / T`` and every echo gets an unwrapped angle. A log whose
angles do not follow a constant rotation at that period raises ``ValueError``.
"""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import field
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.errors import InputError
from seatrack.geometry import TWO_PI
from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.navigation.echoes import GateConfig
from seatrack.navigation.echoes import adaptive_half_angle
from seatrack.navigation.echoes import echo_weights
from seatrack.navigation.echoes import local_offsets
from seatrack.navigation.echoes import weighted_measurement
from seatrack.navigation.filter import KalmanNav
from seatrack.navigation.filter import NavFilter
from seatrack.navigation.filter import ProcessNoise
from seatrack.navigation.filter import SRIFNav
from seatrack.navigation.filter import antenna_position
from seatrack.navigation.filter import compass_row
from seatrack.navigation.filter import contour_row
from seatrack.navigation.filter import gnss_rows
from seatrack.navigation.filter import gyro_row
from seatrack.navigation.filter import landmark_geometry
from seatrack.navigation.filter import log_speed
from seatrack.navigation.filter import point_rows
from seatrack.navigation.landmarks import LandmarkMap
from seatrack.navigation.schedule import ScheduleConfig
from seatrack.navigation.schedule import next_landmark
from seatrack.navigation.window import Window
from seatrack.navigation.window import in_range
from seatrack.navigation.window import settle_window
from seatrack.navigation.window import step_window
from seatrack.progress import Progress

FloatArray = NDArray[np.float64]

__all__ = ["NavigatorConfig", "Echoes", "AuxData", "SurveyRecords", "NavResult", "navigate"]


@dataclass(frozen=True)
class NavigatorConfig:
    """Navigator settings (spec defaults).

    Attributes
    ----------
    antenna_period : s per revolution (2.5).
    steps_per_rev : predictor ticks per revolution (16).
    range_limit : m, radar range used by the active window.
    antenna_offset : m, antenna aft of the reference point F (a).
    method : "ekf" (Kalman, Joseph form) or "srif" (square-root information).
    noise : ProcessNoise (the spec's B) when a gyro log is given.
    q_turn_without_gyro : rad^2/s^3, turn-acceleration PSD used instead of ``noise.q_turn``
        when there is no gyro: the turn rate then has to follow rudder manoeuvres from the
        landmark bearings alone.
    gyro_sigma : rad/s, noise of one gyro sample.
    gate : GateConfig
    schedule : ScheduleConfig
    init_std : (6,) standard deviations of the initial state (m, m, rad, m/s, m/s, rad/s).
    gnss_sigma, log_sigma, compass_sigma : m, m/s, rad, noise of the optional sensors.
    map_sigma : m, standard deviation of the landmark coordinates, added to the variance of
        every landmark measurement (0: the map is taken as exact, as in the patent).
    phase_tolerance : rad, largest allowed deviation of an echo's antenna angle from the
        constant-rotation model.
    """

    antenna_period: float = 2.5
    steps_per_rev: int = 16
    range_limit: float = 3000.0
    antenna_offset: float = 0.0
    method: str = "ekf"
    noise: ProcessNoise = field(default_factory=ProcessNoise)
    q_turn_without_gyro: float = 2e-5
    gyro_sigma: float = float(np.radians(0.05))
    gate: GateConfig = field(default_factory=GateConfig)
    schedule: ScheduleConfig = field(default_factory=ScheduleConfig)
    init_std: tuple[float, ...] = (
        20.0,
        20.0,
        float(np.radians(3.0)),
        1.0,
        1.0,
        float(np.radians(0.5)),
    )
    gnss_sigma: float = 5.0
    log_sigma: float = 0.1
    compass_sigma: float = float(np.radians(1.0))
    map_sigma: float = 0.0
    phase_tolerance: float = float(np.radians(20.0))

    def __post_init__(self) -> None:
        if self.method not in ("ekf", "srif"):
            raise ValueError(f"method must be 'ekf' or 'srif', got {self.method!r}")
        if not self.antenna_period > 0 or self.steps_per_rev < 1:
            raise ValueError("antenna_period must be positive and steps_per_rev >= 1")


@dataclass(frozen=True)
class Echoes:
    """Echo points: time (s), antenna angle relative to the bow (rad), range (m).

    ``source`` (e.g. ``"ECHOES.csv"``) and ``lines`` (file line of each row), when given,
    make errors name the file line.
    """

    t: FloatArray
    antenna: FloatArray
    range: FloatArray
    source: str = "echo log"
    lines: NDArray[np.int64] | None = None


@dataclass(frozen=True)
class AuxData:
    """Optional extra sensors, each ``(t, values)`` or None.

    gnss : values (K, 2) East, North of F (m); log : (K,) speed along the bow (m/s);
    compass : (K,) heading (rad).
    """

    gnss: tuple[FloatArray, FloatArray] | None = None
    log: tuple[FloatArray, FloatArray] | None = None
    compass: tuple[FloatArray, FloatArray] | None = None


@dataclass(frozen=True)
class SurveyRecords:
    """Landmark corrections recorded during a passage (input of the survey).

    One row per scalar landmark measurement used: ``landmark`` (order number), ``t`` (s),
    ``direction`` (M, 2) world unit vector the measurement projects on, ``z`` (m, measured
    minus predicted, i.e. the correction the landmark needs along ``direction`` if the
    own-ship estimate is right), ``var`` (m^2).
    """

    landmark: NDArray[np.int64]
    t: FloatArray
    direction: FloatArray
    z: FloatArray
    var: FloatArray


@dataclass(frozen=True)
class NavResult:
    """Filter output, one row per predictor tick.

    Attributes
    ----------
    t : (K,) s
    x : (K, 6) state ``[X, Y, alpha, Xdot, Ydot, alphadot]`` (alpha unwrapped)
    std : (K, 6) square roots of the covariance diagonal
    attempts, hits : (N,) landmark passes served / that gave an update
    records : SurveyRecords
    n_updates : number of landmark updates
    """

    t: FloatArray
    x: FloatArray
    std: FloatArray
    attempts: NDArray[np.int64]
    hits: NDArray[np.int64]
    records: SurveyRecords
    n_updates: int


def _antenna_unwrap(
    t: FloatArray, ang: FloatArray, T: float, t0: float, tol: float, where: Echoes
) -> tuple[float, FloatArray]:
    """Phase ``phi0`` and unwrapped angles of echoes under constant rotation."""
    base = TWO_PI * (t - t0) / T
    d = ang - base
    phi0 = float(np.arctan2(np.mean(np.sin(d)), np.mean(np.cos(d))))
    res = wrap_pi(d - phi0)
    worst = int(np.argmax(np.abs(res)))
    if abs(res[worst]) > tol:
        loc = f"line {where.lines[worst]}" if where.lines is not None else f"row {worst + 1}"
        raise InputError(
            f"{where.source}, {loc}: antenna angle deviates {np.degrees(abs(res[worst])):.1f} deg "
            f"from a constant rotation of period {T:g} s; set the antenna period"
        )
    return phi0, base + phi0 + res


#: most predictor ticks one navigate() call runs (about 18 days at 2.5 s / 16 ticks)
MAX_TICKS = 10_000_000


def _tick_count(et: FloatArray, start: float, dt: float, where: Echoes) -> int:
    """Number of predictor ticks from ``start`` to the last echo, bounded before any work."""
    span = float(et[-1]) - start
    n = span / dt
    last = int(et.size - 1)
    loc = f"line {where.lines[last]}" if where.lines is not None else f"row {last + 1}"
    if not (np.isfinite(n) and n <= MAX_TICKS):
        raise InputError(
            f"{where.source}, {loc}: the echo log spans {span:g} s, {n:.3g} filter cycles of "
            f"{dt:g} s; at most {MAX_TICKS} are run (split the log)"
        )
    if n < 1:
        raise InputError(
            f"{where.source}, {loc}: the echo log spans {span:g} s, less than one filter "
            f"cycle ({dt:g} s)"
        )
    return int(np.floor(n))


def _per_tick(ticks: NDArray[Any], t: NDArray[Any]) -> NDArray[np.int64]:
    """Tick index of each sample: sample in (ticks[k-1], ticks[k]] goes to tick k."""
    return np.searchsorted(ticks, t, side="left").astype(np.int64)


@dataclass(frozen=True)
class _Sweep:
    """The echo log sorted by unwrapped antenna angle, and the antenna timing."""

    start: float
    phi0: float
    period: float
    Phi: FloatArray  # sorted unwrapped antenna angles
    range: FloatArray
    antenna: FloatArray

    @classmethod
    def of(cls, echoes: Echoes, start: float, cfg: NavigatorConfig) -> _Sweep:
        et = np.asarray(echoes.t, float)
        ang = np.asarray(echoes.antenna, float)
        T = cfg.antenna_period
        phi0, Phi = _antenna_unwrap(et, ang, T, start, cfg.phase_tolerance, echoes)
        order = np.argsort(Phi, kind="stable")
        rng = np.asarray(echoes.range, float)
        return cls(start, phi0, T, Phi[order], rng[order], ang[order])

    def Phi_of(self, t: float) -> float:
        return TWO_PI * (t - self.start) / self.period + self.phi0

    def t_of(self, P: float) -> float:
        return self.start + (P - self.phi0) * self.period / TWO_PI

    def rel_rate(self, x: FloatArray) -> float:
        """Antenna angle (relative to the bow) turned per radian of true bearing."""
        omega = TWO_PI / self.period
        return omega / max(omega + float(x[5]), 0.5 * omega)


@dataclass(frozen=True)
class _Gate:
    """A landmark's measurement rows, innovation covariance and echo gate at a state."""

    H: FloatArray
    S: FloatArray
    half: float  # half angle of the gate, rad
    proj: FloatArray | None  # contour: projection of (dr, dtheta) on the normal
    w_half: FloatArray
    clutter: float
    dirs: FloatArray  # world directions of the measurement components (survey)


def _gate(lm: LandmarkMap, j: int, x: FloatArray, P: FloatArray, cfg: NavigatorConfig) -> _Gate:
    gc, a = cfg.gate, cfg.antenna_offset
    r_c, th_c, _ = landmark_geometry(x, lm.xy[j], a)
    var_r = gc.sigma_range**2
    var_t = (r_c * gc.sigma_angle) ** 2
    if not lm.is_contour[j]:
        H = point_rows(x, lm.xy[j], a)
        S = H @ P @ H.T + np.diag([var_r, var_t])
        half = adaptive_half_angle(r_c, S, [0.0, 1.0], gc)
        dirs = np.array([[np.sin(th_c), np.cos(th_c)], [np.cos(th_c), -np.sin(th_c)]])
        w_half = np.array([gc.range_half_width, r_c * half])
        return _Gate(H, S, half, None, w_half, gc.clutter_density, dirs)
    b_j = float(lm.normal[j])
    c, s = np.cos(th_c - b_j), np.sin(th_c - b_j)
    H = contour_row(x, lm.xy[j], b_j, a)[None, :]
    S = H @ P @ H.T + (c * c * var_r + s * s * var_t)
    half = adaptive_half_angle(r_c, S, [-s], gc)
    seg = min(
        2 * r_c * gc.max_half_angle / max(abs(s), 1e-6),
        2 * gc.range_half_width / max(abs(c), 1e-6),
    )
    w_half = np.array([abs(c) * gc.range_half_width + abs(s) * r_c * half])
    dirs = np.array([[np.sin(b_j), np.cos(b_j)]])
    return _Gate(H, S, half, np.array([c, -s]), w_half, gc.clutter_density * seg, dirs)


def _aux_per_tick(
    ticks: FloatArray, aux: AuxData | None
) -> dict[str, tuple[NDArray[np.int64], FloatArray]]:
    """Per optional sensor: index of its last sample in each tick (-1: none), values."""
    out: dict[str, tuple[NDArray[np.int64], FloatArray]] = {}
    if aux is None:
        return out
    for name in ("gnss", "log", "compass"):
        v = getattr(aux, name)
        if v is not None:
            at = np.asarray(v[0], float)
            kk = _per_tick(ticks, at)
            last = np.full(ticks.size + 1, -1, np.int64)
            np.maximum.at(last, kk, np.arange(at.size))  # the last sample in each tick
            out[name] = (last, np.asarray(v[1], float))
    return out


class _Passage:
    """The mutable state of one passage (filter state, active window, armed landmark,
    counters, survey records) and the steps of the navigation loop."""

    def __init__(
        self, lm: LandmarkMap, sweep: _Sweep, cfg: NavigatorConfig, flt: NavFilter, state: Any
    ) -> None:
        self.lm, self.sweep, self.cfg, self.flt, self.state = lm, sweep, cfg, flt, state
        self.t = sweep.start
        N = len(lm)
        self.jump = np.zeros(N, np.int64)
        self.attempts = np.zeros(N, np.int64)
        self.hits = np.zeros(N, np.int64)
        self.records: list[tuple[int, float, FloatArray, float, float]] = []
        self.n_updates = 0
        self.armed, self.armed_Phi = -1, 0.0
        self.window = settle_window(Window(0, -1), self.visible(self.x))

    @property
    def x(self) -> FloatArray:
        return np.asarray(self.state.x[0])

    def advance(self, t: float) -> None:
        """Predict to ``t`` (no change unless later than the current time)."""
        if t > self.t:
            self.state = self.flt.predict(self.state, t)
            self.t = t

    def update(self, y: ArrayLike, H: ArrayLike, R: ArrayLike) -> None:
        self.state = self.flt.update(self.state, y, H, R)

    def visible(self, x: FloatArray) -> NDArray[np.bool_]:
        return in_range(
            self.lm.xy, antenna_position(x, self.cfg.antenna_offset), self.cfg.range_limit
        )

    def eligible(self, x: FloatArray) -> NDArray[np.bool_]:
        m = np.zeros(len(self.lm), bool)
        idx = self.window.indices()
        m[idx[(idx >= 0) & (idx < len(self.lm))]] = True
        return m & self.visible(x)

    def bearings(self, x: FloatArray) -> FloatArray:
        e = antenna_position(x, self.cfg.antenna_offset)
        xy = self.lm.xy
        return np.asarray(bearing(xy[:, 0] - e[0], xy[:, 1] - e[1]))

    def serve(self, j: int, Phi_plan: float, t_g: float) -> None:
        """Take the echoes in landmark ``j``'s gate and update (spec "Gating")."""
        gc, sw = self.cfg.gate, self.sweep
        x, P = self.x, self.state.P[0]
        r_c, th_c, phi_c = landmark_geometry(x, self.lm.xy[j], self.cfg.antenna_offset)
        Pc = Phi_plan + float(wrap_pi(phi_c - Phi_plan))
        self.attempts[j] += 1
        g = _gate(self.lm, j, x, P, self.cfg)
        i0 = int(np.searchsorted(sw.Phi, Pc - g.half, side="left"))
        i1 = int(np.searchsorted(sw.Phi, Pc + g.half, side="right"))
        rr = sw.range[i0:i1]
        inr = np.abs(rr - r_c) <= gc.range_half_width
        if not inr.any():
            return
        off = local_offsets(
            rr[inr], sw.antenna[i0:i1][inr], r_c, th_c, phi_c, x[2], gc.polar_offsets
        )
        z = off if g.proj is None else (off @ g.proj)[:, None]
        p = echo_weights(z, g.S, g.clutter, gc.expected_echoes)
        st = weighted_measurement(z, p, g.w_half, gc)
        if not st.updated:
            return
        self.update(st.z, g.H, np.diag(st.var + self.cfg.map_sigma**2))
        self.hits[j] += 1
        self.n_updates += 1
        for k in range(st.z.size):  # survey: measurement noise only
            self.records.append((j, t_g, g.dirs[k], float(st.z[k]), float(st.var[k])))

    def serve_swept(self, tk: float, pad: float) -> None:
        """Serve every armed gate the antenna has fully swept by ``tk``, arming the next."""
        sw = self.sweep
        while self.armed >= 0 and sw.t_of(self.armed_Phi + pad) <= tk:
            self.advance(max(sw.t_of(self.armed_Phi), self.t))
            # the gate centre at the predicted state (the plan assumed a constant turn rate)
            _, _, phi_c = landmark_geometry(self.x, self.lm.xy[self.armed], self.cfg.antenna_offset)
            Pc = self.armed_Phi + float(wrap_pi(phi_c - self.armed_Phi))
            self.advance(sw.t_of(Pc))
            self.serve(self.armed, Pc, self.t)
            x = self.x
            ch = next_landmark(
                self.bearings(x), self.eligible(x), self.jump, self.armed, 0.0, self.cfg.schedule
            )
            self.jump = ch.jump
            if ch.index < 0:
                self.armed = -1
            else:
                self.armed, self.armed_Phi = ch.index, Pc + ch.gap * sw.rel_rate(x)

    def arm(self, tk: float) -> None:
        """Arm the next landmark when none is armed."""
        if self.armed >= 0:
            return
        x = self.x
        ant = self.sweep.Phi_of(tk)
        sc = self.cfg.schedule
        ch = next_landmark(self.bearings(x), self.eligible(x), self.jump, None, ant + x[2], sc)
        self.jump = ch.jump
        if ch.index >= 0:
            self.armed = ch.index
            self.armed_Phi = ant + (sc.start_margin + ch.gap) * self.sweep.rel_rate(x)

    def fuse(self, k: int, gyro: Any, aux: dict[str, tuple[NDArray[np.int64], FloatArray]]) -> None:
        """Gyro, GNSS, log and compass samples of tick ``k``."""
        cfg = self.cfg
        if gyro is not None and gyro[1][k] > 0:
            g_sum, g_cnt = gyro
            y = [g_sum[k] / g_cnt[k] - self.x[5]]
            self.update(y, gyro_row()[None, :], [[cfg.gyro_sigma**2 / g_cnt[k]]])
        if "gnss" in aux and aux["gnss"][0][k] >= 0:
            zi = aux["gnss"][1][aux["gnss"][0][k]]
            self.update(zi - self.x[:2], gnss_rows(), np.eye(2) * cfg.gnss_sigma**2)
        if "log" in aux and aux["log"][0][k] >= 0:
            zi = aux["log"][1][aux["log"][0][k]]
            hx, h = log_speed(self.x)
            self.update([zi - hx], h[None, :], [[cfg.log_sigma**2]])
        if "compass" in aux and aux["compass"][0][k] >= 0:
            zi = aux["compass"][1][aux["compass"][0][k]]
            y = [wrap_pi(zi - self.x[2])]
            self.update(y, compass_row()[None, :], [[cfg.compass_sigma**2]])

    def survey_records(self) -> SurveyRecords:
        r = self.records
        return SurveyRecords(
            np.array([v[0] for v in r], np.int64),
            np.array([v[1] for v in r], float),
            np.array([v[2] for v in r], float).reshape(-1, 2),
            np.array([v[3] for v in r], float),
            np.array([v[4] for v in r], float),
        )


def navigate(
    landmarks: LandmarkMap,
    echoes: Echoes,
    x0: ArrayLike,
    config: NavigatorConfig | None = None,
    gyro: tuple[ArrayLike, ArrayLike] | None = None,
    aux: AuxData | None = None,
    t0: float | None = None,
    progress: Progress | None = None,
) -> NavResult:
    """Run the landmark navigator over an echo log (``progress``: told of the filter
    cycles done).

    Parameters
    ----------
    landmarks : map in channel order.
    echoes : echo log (sorted by time).
    x0 : (6,) initial state at ``t0`` (default: time of the first echo).
    config : NavigatorConfig
    gyro : (t, turn rate rad/s), optional.
    aux : optional GNSS / log / compass.

    Returns
    -------
    NavResult
    """
    cfg = config or NavigatorConfig()
    et = np.asarray(echoes.t, float)
    if et.size == 0:
        raise InputError("the echo log is empty")
    start = float(et[0] if t0 is None else t0)
    sweep = _Sweep.of(echoes, start, cfg)
    P0 = np.diag(np.asarray(cfg.init_std, float) ** 2)
    noise = cfg.noise if gyro is not None else replace(cfg.noise, q_turn=cfg.q_turn_without_gyro)
    flt: NavFilter = (KalmanNav if cfg.method == "ekf" else SRIFNav)(noise)
    dt = cfg.antenna_period / cfg.steps_per_rev
    n_ticks = _tick_count(et, start, dt, echoes)
    ticks = np.asarray(start + dt * np.arange(1, n_ticks + 1), dtype=np.float64)
    g = None
    if gyro is not None:
        gt, gw = (np.asarray(v, float) for v in gyro)
        g_k = _per_tick(ticks, gt)
        g = (np.bincount(g_k, gw, minlength=n_ticks + 1), np.bincount(g_k, minlength=n_ticks + 1))
    aux_last = _aux_per_tick(ticks, aux)
    run = _Passage(landmarks, sweep, cfg, flt, flt.initiate(start, x0, P0))
    out_x = np.empty((n_ticks, 6))
    out_s = np.empty((n_ticks, 6))
    pad = cfg.gate.max_half_angle + np.radians(1.0)
    last_rev = int(np.floor(sweep.Phi_of(start) / TWO_PI))
    for k in range(n_ticks):
        if progress is not None:
            progress.update(k)
        tk = float(ticks[k])
        run.serve_swept(tk, pad)
        run.advance(tk)
        run.fuse(k, g, aux_last)
        rev = int(np.floor(sweep.Phi_of(tk) / TWO_PI))
        if rev != last_rev:
            run.window = step_window(run.window, run.visible(run.x))
            last_rev = rev
        run.arm(tk)
        out_x[k] = run.x
        out_s[k] = np.sqrt(np.diag(run.state.P[0]))
    records = run.survey_records()
    return NavResult(ticks, out_x, out_s, run.attempts, run.hits, records, run.n_updates)
