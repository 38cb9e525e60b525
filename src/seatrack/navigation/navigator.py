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

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seatrack.geometry import TWO_PI, bearing, wrap_pi
from seatrack.navigation.echoes import (
    GateConfig,
    adaptive_half_angle,
    echo_weights,
    local_offsets,
    weighted_measurement,
)
from seatrack.navigation.filter import (
    KalmanNav,
    NavFilter,
    ProcessNoise,
    SRIFNav,
    antenna_position,
    compass_row,
    contour_row,
    gnss_rows,
    gyro_row,
    landmark_geometry,
    log_speed,
    point_rows,
)
from seatrack.navigation.landmarks import LandmarkMap
from seatrack.navigation.schedule import ScheduleConfig, next_landmark
from seatrack.navigation.window import Window, in_range, settle_window, step_window

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
        raise ValueError(
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
        raise ValueError(
            f"{where.source}, {loc}: the echo log spans {span:g} s, {n:.3g} filter cycles of "
            f"{dt:g} s; at most {MAX_TICKS} are run (split the log)"
        )
    if n < 1:
        raise ValueError(
            f"{where.source}, {loc}: the echo log spans {span:g} s, less than one filter "
            f"cycle ({dt:g} s)"
        )
    return int(np.floor(n))


def _per_tick(ticks: NDArray[Any], t: NDArray[Any]) -> NDArray[np.int64]:
    """Tick index of each sample: sample in (ticks[k-1], ticks[k]] goes to tick k."""
    return np.searchsorted(ticks, t, side="left").astype(np.int64)


def navigate(
    landmarks: LandmarkMap,
    echoes: Echoes,
    x0: ArrayLike,
    config: NavigatorConfig | None = None,
    gyro: tuple[ArrayLike, ArrayLike] | None = None,
    aux: AuxData | None = None,
    t0: float | None = None,
) -> NavResult:
    """Run the landmark navigator over an echo log.

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
    gc = cfg.gate
    a = cfg.antenna_offset
    T = cfg.antenna_period
    et = np.asarray(echoes.t, float)
    if et.size == 0:
        raise ValueError("the echo log is empty")
    start = float(et[0] if t0 is None else t0)
    phi0, Phi = _antenna_unwrap(
        et, np.asarray(echoes.antenna, float), T, start, cfg.phase_tolerance, echoes
    )
    order = np.argsort(Phi, kind="stable")
    Phi_s = Phi[order]
    r_s = np.asarray(echoes.range, float)[order]
    ang_s = np.asarray(echoes.antenna, float)[order]

    def Phi_of(t: float) -> float:
        return TWO_PI * (t - start) / T + phi0

    def t_of(P: float) -> float:
        return start + (P - phi0) * T / TWO_PI

    P0 = np.diag(np.asarray(cfg.init_std, float) ** 2)
    noise = cfg.noise if gyro is not None else replace(cfg.noise, q_turn=cfg.q_turn_without_gyro)
    filt: NavFilter = (KalmanNav if cfg.method == "ekf" else SRIFNav)(x0, P0, noise)
    dt = T / cfg.steps_per_rev
    n_ticks = _tick_count(et, start, dt, echoes)
    ticks = np.asarray(start + dt * np.arange(1, n_ticks + 1), dtype=np.float64)

    g_k = g_sum = g_cnt = None
    if gyro is not None:
        gt, gw = (np.asarray(v, float) for v in gyro)
        g_k = _per_tick(ticks, gt)
        g_sum = np.bincount(g_k, gw, minlength=n_ticks + 1)
        g_cnt = np.bincount(g_k, minlength=n_ticks + 1)
    aux_last: dict[str, tuple[NDArray[np.int64], FloatArray]] = {}
    if aux is not None:
        for name in ("gnss", "log", "compass"):
            v = getattr(aux, name)
            if v is not None:
                at = np.asarray(v[0], float)
                kk = _per_tick(ticks, at)
                last = np.full(n_ticks + 1, -1, np.int64)
                np.maximum.at(last, kk, np.arange(at.size))  # the last sample in each tick
                aux_last[name] = (last, np.asarray(v[1], float))

    N = len(landmarks)
    xy = landmarks.xy
    beta = landmarks.normal
    jump = np.zeros(N, np.int64)
    attempts = np.zeros(N, np.int64)
    hits = np.zeros(N, np.int64)
    rec_l: list[int] = []
    rec_t: list[float] = []
    rec_d: list[FloatArray] = []
    rec_z: list[float] = []
    rec_v: list[float] = []
    n_updates = 0

    def visible(x: FloatArray) -> NDArray[np.bool_]:
        return in_range(xy, antenna_position(x, a), cfg.range_limit)

    window = settle_window(Window(0, -1), visible(filt.x))

    def eligible(x: FloatArray) -> NDArray[np.bool_]:
        m = np.zeros(N, bool)
        idx = window.indices()
        m[idx[(idx >= 0) & (idx < N)]] = True
        return m & visible(x)

    def bearings(x: FloatArray) -> FloatArray:
        e = antenna_position(x, a)
        return np.asarray(bearing(xy[:, 0] - e[0], xy[:, 1] - e[1]))

    def rel_rate(x: FloatArray) -> float:
        """Antenna angle (relative to the bow) turned per radian of true bearing."""
        omega = TWO_PI / T
        return omega / max(omega + float(x[5]), 0.5 * omega)

    def serve(j: int, Phi_plan: float, t_g: float) -> None:
        nonlocal n_updates
        x, P = filt.x, filt.P
        r_c, th_c, phi_c = landmark_geometry(x, xy[j], a)
        Pc = Phi_plan + float(wrap_pi(phi_c - Phi_plan))
        attempts[j] += 1
        var_r = gc.sigma_range**2
        var_t = (r_c * gc.sigma_angle) ** 2
        if landmarks.is_contour[j]:
            b_j = float(beta[j])
            c, s = np.cos(th_c - b_j), np.sin(th_c - b_j)
            H = contour_row(x, xy[j], b_j, a)[None, :]
            S = H @ P @ H.T + (c * c * var_r + s * s * var_t)
            half = adaptive_half_angle(r_c, S, [-s], gc)
            proj = np.array([c, -s])
            w_half = np.array([abs(c) * gc.range_half_width + abs(s) * r_c * half])
            seg = min(
                2 * r_c * gc.max_half_angle / max(abs(s), 1e-6),
                2 * gc.range_half_width / max(abs(c), 1e-6),
            )
            b = gc.clutter_density * seg
            dirs = np.array([[np.sin(b_j), np.cos(b_j)]])
        else:
            H = point_rows(x, xy[j], a)
            S = H @ P @ H.T + np.diag([var_r, var_t])
            half = adaptive_half_angle(r_c, S, [0.0, 1.0], gc)
            proj = None
            w_half = np.array([gc.range_half_width, r_c * half])
            b = gc.clutter_density
            dirs = np.array([[np.sin(th_c), np.cos(th_c)], [np.cos(th_c), -np.sin(th_c)]])
        i0 = int(np.searchsorted(Phi_s, Pc - half, side="left"))
        i1 = int(np.searchsorted(Phi_s, Pc + half, side="right"))
        rr = r_s[i0:i1]
        inr = np.abs(rr - r_c) <= gc.range_half_width
        if not inr.any():
            return
        off = local_offsets(rr[inr], ang_s[i0:i1][inr], r_c, th_c, phi_c, x[2], gc.polar_offsets)
        z = off if proj is None else (off @ proj)[:, None]
        p = echo_weights(z, S, b, gc.expected_echoes)
        st = weighted_measurement(z, p, w_half, gc)
        if not st.updated:
            return
        filt.update(st.z, H, np.diag(st.var + cfg.map_sigma**2))
        hits[j] += 1
        n_updates += 1
        for k in range(st.z.size):
            rec_l.append(j)
            rec_t.append(t_g)
            rec_d.append(dirs[k])
            rec_z.append(float(st.z[k]))
            rec_v.append(float(st.var[k]))  # survey: measurement noise only

    t_f = start
    armed = -1
    armed_Phi = 0.0
    out_x = np.empty((n_ticks, 6))
    out_s = np.empty((n_ticks, 6))
    pad = gc.max_half_angle + np.radians(1.0)
    last_rev = int(np.floor(Phi_of(start) / TWO_PI))
    for k in range(n_ticks):
        tk = float(ticks[k])
        # serve every armed gate the antenna has fully swept by this tick
        while armed >= 0 and t_of(armed_Phi + pad) <= tk:
            t_g = max(t_of(armed_Phi), t_f)
            filt.predict(t_g - t_f)
            t_f = t_g
            # the gate centre at the predicted state (the plan assumed a constant turn rate)
            _, _, phi_c = landmark_geometry(filt.x, xy[armed], a)
            Pc = armed_Phi + float(wrap_pi(phi_c - armed_Phi))
            if t_of(Pc) > t_f:
                filt.predict(t_of(Pc) - t_f)
                t_f = t_of(Pc)
            serve(armed, Pc, t_f)
            x = filt.x
            ch = next_landmark(bearings(x), eligible(x), jump, armed, 0.0, cfg.schedule)
            jump = ch.jump
            if ch.index < 0:
                armed = -1
            else:
                armed, armed_Phi = ch.index, Pc + ch.gap * rel_rate(x)
        filt.predict(tk - t_f)
        t_f = tk
        if g_sum is not None and g_cnt is not None and g_cnt[k] > 0:
            filt.update(
                [g_sum[k] / g_cnt[k] - filt.x[5]],
                gyro_row()[None, :],
                [[cfg.gyro_sigma**2 / g_cnt[k]]],
            )
        if "gnss" in aux_last and aux_last["gnss"][0][k] >= 0:
            zi = aux_last["gnss"][1][aux_last["gnss"][0][k]]
            filt.update(zi - filt.x[:2], gnss_rows(), np.eye(2) * cfg.gnss_sigma**2)
        if "log" in aux_last and aux_last["log"][0][k] >= 0:
            zi = aux_last["log"][1][aux_last["log"][0][k]]
            hx, h = log_speed(filt.x)
            filt.update([zi - hx], h[None, :], [[cfg.log_sigma**2]])
        if "compass" in aux_last and aux_last["compass"][0][k] >= 0:
            zi = aux_last["compass"][1][aux_last["compass"][0][k]]
            filt.update([wrap_pi(zi - filt.x[2])], compass_row()[None, :], [[cfg.compass_sigma**2]])
        rev = int(np.floor(Phi_of(tk) / TWO_PI))
        if rev != last_rev:
            window = step_window(window, visible(filt.x))
            last_rev = rev
        if armed < 0:
            x = filt.x
            ant = Phi_of(tk)
            ch = next_landmark(bearings(x), eligible(x), jump, None, ant + x[2], cfg.schedule)
            jump = ch.jump
            if ch.index >= 0:
                armed = ch.index
                armed_Phi = ant + (cfg.schedule.start_margin + ch.gap) * rel_rate(x)
        out_x[k] = filt.x
        out_s[k] = np.sqrt(np.diag(filt.P))
    records = SurveyRecords(
        np.array(rec_l, np.int64),
        np.array(rec_t, float),
        np.array(rec_d, float).reshape(-1, 2),
        np.array(rec_z, float),
        np.array(rec_v, float),
    )
    return NavResult(ticks, out_x, out_s, attempts, hits, records, n_updates)
