"""EXPERIMENTAL prototypes of issue 16 that are NOT library methods, measured beside them.

What the measurements made the library's defaults (the level IMM with the contaminated
update, :mod:`seatrack.filters.levels`; the IMM with range rate) runs from the library here
(rows ``label=method``: configurations of registered methods). What remains are batched
prototypes (all runs of a set at once) of the ideas the measurements did NOT adopt, kept so
that the numbers in ``docs/defaults.md`` ("Research: what else was measured") can be
reproduced. Each prototype gets only what a user gives -- the sensor's nominal noise --
unless its label says ``+class`` (the target class of the set,
:mod:`seatrack.models.targets`); ``ORACLE`` rows know the truth.

Prototypes:

* ``turn-centripetal`` -- the turning method's idea, kept on through a steady turn: a CV
  EKF whose white-noise acceleration PSD is ``q = q_nom + kappa (w v)^2 T`` while the
  heading filter's turn rate is significant (``|w| > sig sigma_w``), with ``w`` from a
  (heading, turn rate) Kalman filter on the EKF's velocity (spec steps S2/S3).
* ``turn-ct`` -- the same detector, a coordinated-turn prediction at its turn rate.
* ``cm-ekf`` -- self-tuning CV EKF: ``q`` by innovation covariance matching (Mehra 1972;
  Sage-Husa-type fading memory ``b``): ``q_k = clip(EWMA_b(qhat_k))`` with
  ``qhat_k = sum_c (y_c^2 - S0_cc) / sum_c (H Q1 H^T)_cc``, ``S0 = H F P F^T H^T + R``.
* ``robust-cm`` -- algorithm R's robust variance (``R_c <- max(R_c, y_c^2/Delta -
  (H P H^T)_cc)``) plus covariance matching on the CAPPED innovations
  (``y_c^2 -> min(y_c^2, Delta S_cc)``).
* ``mode-q`` -- ONE CV EKF whose ``q`` is mixed by the mode probabilities of process-noise
  levels (a Bayesian "raise Q" decision without a state per level).
* ``ct-ekf`` -- a single coordinated-turn EKF (turn rate in the state).
* ``ORACLE q`` / ``ORACLE ct`` -- the true centripetal Q schedule / a CT prediction at the
  true turn rate: the head-room of any Q schedule and of a perfect turn-rate estimate.

``--model-bounds`` asks what ANY single motion model could reach on a set (default the two
weaving sets) with its noise chosen in hindsight: grids of a CV EKF (white acceleration),
a CA EKF (white jerk), Singer EKFs (acceleration time constants 10 and 30 s) and a CT-EKF
(white acceleration and turn-rate random walk), each printed as its best RMSE over the best
CV q and over ``min(narrow, wide)`` (the ``turning`` target is <= 0.95 of the latter).

``--range-rate-levels`` runs ``turning`` on ``weave-fighter`` with and without the plots'
range rate, with isotropic levels on the old ladder and with the along-track shape, and
prints the level probabilities and the errors along / across the line of sight over the
weave (why range rate hurt the level IMM there: docs/defaults.md).

``--onsets`` runs the level methods on ``fighter`` with and without range rate and prints
the error and the agile levels' probability around the manoeuvre onsets (why ``robust``,
``huber`` and ``student-t`` lagged there: docs/defaults.md).

``--gross-outliers`` runs the two contaminated sets with their outliers at 10 sigma
(variance x 100 instead of Ramazanov's x 10 range, x 25 azimuth) through the level-IMM
methods with their default outlier scale (100) and with Ramazanov's (10, 25).

Run: ``python benchmarks/defaults_experiments.py --runs 20`` (TUNING seeds),
``--headline`` (HEADLINE seeds), ``--sets``, ``--consistency`` (multiple-model methods),
``--model-bounds [--sets ...]``, ``--gross-outliers``, ``--range-rate-levels``, ``--onsets``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from collections.abc import Callable
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from seatrack import kalman
from seatrack.filters.base import measurement_model
from seatrack.filters.base import plot_gaussian
from seatrack.filters.base import two_point_gaussian
from seatrack.geometry import wrap_pi
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition
from seatrack.models.targets import TargetClass
from seatrack.simulate.families import Scenario

sys.path.insert(0, str(Path(__file__).parent))
from defaults import SETS  # noqa: E402
from defaults import anchor_rows  # noqa: E402
from defaults import method_rows  # noqa: E402
from defaults import polar_setup  # noqa: E402
from defaults import print_set  # noqa: E402
from defaults import rmse  # noqa: E402
from defaults import seeds  # noqa: E402
from defaults import stack_plots  # noqa: E402
from defaults import targets  # noqa: E402

Estimate = np.ndarray
SPEED_SIGMA = 300.0  # m/s initial velocity std when no class is given (the methods' 300)


def _start(scs: Sequence[Scenario], speed_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    first = [s.plots.take(np.zeros(1, int)) for s in scs]
    xs, Ps = zip(*(plot_gaussian(p, s.sensor, speed_sigma) for p, s in zip(first, scs)))
    return np.concatenate(xs), np.concatenate(Ps)


def _R(scs: Sequence[Scenario], m: int) -> np.ndarray:
    s = scs[0].sensor
    sig = np.array([s.sigma_range, s.sigma_azimuth, s.sigma_range_rate])[:m]
    return np.diag(sig**2)


def polar_cv_loop(
    scs: Sequence[Scenario],
    policy: Callable[[dict[str, Any]], None],
    speed_sigma: float = SPEED_SIGMA,
) -> Estimate:
    """A batched CV EKF on polar plots whose process noise and measurement variance are
    set each scan by ``policy(ctx)``: ``ctx`` holds ``k, dt, x, P, y, S0, HQ1H, R`` and the
    policy writes ``ctx["q"]`` (B,) before the prediction (called with ``stage='q'``) and
    may write ``ctx["R"]`` (B, m, m) before the update (``stage='R'``) and read the result
    after it (``stage='post'``)."""
    st = stack_plots(scs)
    z, sen, t = st["z"], st["sensor"], st["t"]
    B, N, m = z.shape
    model = measurement_model(2, 4, m == 3)
    ang = model.angular.astype(float)
    x, P = _start(scs, speed_sigma)
    R0 = _R(scs, m)
    out = np.empty((B, N, 4))
    out[:, 0] = x
    ctx: dict[str, Any] = {"B": B, "m": m, "R0": R0}
    for k in range(1, N):
        dt = float(t[k] - t[k - 1])
        F = cv_transition(dt, 2)
        ctx.update(k=k, dt=dt, x=x, P=P, stage="q")
        policy(ctx)
        Q1 = cv_noise(dt, 1.0, 2)
        if ctx.get("w") is not None:  # coordinated-turn prediction with a known turn rate
            F = ct_matrix(ctx["w"], dt)
        Pf = F @ P @ np.swapaxes(F, -1, -2)
        x = np.einsum("...ij,...j->...i", F, x)
        P = Pf + ctx["q"][:, None, None] * Q1
        s = sen[:, k]
        hx = model.h(x, s)
        H = model.jacobian(x, s)
        y = z[:, k] - hx
        y = np.where(ang > 0, wrap_pi(y), y)
        HPH = H @ P @ np.swapaxes(H, -1, -2)
        ctx.update(x=x, P=P, y=y, HPH=HPH, S0=H @ Pf @ np.swapaxes(H, -1, -2) + R0,
                   HQ1H=H @ Q1 @ np.swapaxes(H, -1, -2), R=np.broadcast_to(R0, (B, m, m)),
                   stage="R")  # fmt: skip
        policy(ctx)
        res = kalman.extended_update(x, P, z[:, k], hx, H, ctx["R"], ang, check=False)
        x, P = res.x, res.P
        ctx.update(x=x, P=P, stage="post")
        policy(ctx)
        out[:, k] = x
    return out


def ct_matrix(w: np.ndarray, dt: float) -> np.ndarray:
    """``(B, 4, 4)`` transition of ``[x, y, vx, vy]`` for a coordinated turn at known rate
    ``w`` (rad/s, clockwise positive): the velocity turns clockwise by ``w dt``."""
    th = w * dt
    small = np.abs(w) < 1e-9
    ws = np.where(small, 1.0, w)
    s = np.where(small, dt, np.sin(th) / ws)
    c = np.where(small, 0.0, (1 - np.cos(th)) / ws)
    F = np.zeros(w.shape + (4, 4))
    F[..., 0, 0] = F[..., 1, 1] = 1.0
    F[..., 0, 2], F[..., 0, 3], F[..., 1, 2], F[..., 1, 3] = s, c, -c, s
    co, si = np.cos(th), np.sin(th)
    F[..., 2, 2], F[..., 2, 3], F[..., 3, 2], F[..., 3, 3] = co, si, -si, co
    return F


# ---------------------------------------------------------------------------
# (d) self-tuning q by covariance matching
# ---------------------------------------------------------------------------
def cm_policy(q_min: float, q_max: float, b: float, robust_delta: float | None = None):
    """Covariance matching of the process-noise PSD (see the module docstring)."""
    state: dict[str, Any] = {}

    def policy(ctx: dict[str, Any]) -> None:
        B = ctx["B"]
        if ctx["stage"] == "q":
            ctx["q"] = state.get("q", np.full(B, q_min))
            return
        if ctx["stage"] != "R":
            return
        y, S0, HQ1H, HPH = ctx["y"], ctx["S0"], ctx["HQ1H"], ctx["HPH"]
        R0 = ctx["R0"]
        d = np.arange(2)  # range and azimuth channels (range rate not used for matching)
        y2 = y[:, d] ** 2
        if robust_delta is not None:
            S = HPH[:, d, d] + R0[d, d]
            y2 = np.minimum(y2, robust_delta * S)  # capped: one outlier moves q a little
            # algorithm R: robust variance for the update
            Rr = np.maximum(R0[d, d], y[:, d] ** 2 / robust_delta - HPH[:, d, d])
            R = np.broadcast_to(R0, HPH.shape).copy()
            R[:, d, d] = Rr
            ctx["R"] = R
        w = 1.0 / S0[:, d, d]  # normalise the channels
        qhat = np.sum(w * (y2 - S0[:, d, d]), -1) / np.sum(w * HQ1H[:, d, d], -1)
        n = state.get("n", 0) + 1
        state["n"] = n
        g = (1 - b) / (1 - b**n)  # Sage-Husa fading-memory weight
        avg = (1 - g) * state.get("avg", np.zeros(B)) + g * qhat
        state["avg"] = avg
        state["q"] = np.clip(avg, q_min, q_max)

    return policy


# ---------------------------------------------------------------------------
# (a) turning: Q raised by the centripetal acceleration while the target turns
# ---------------------------------------------------------------------------
def turning_policy(
    q_nom: float,
    kappa: float,
    q_heading: float,
    sig: float,
    omega0: float = 0.1,
    w_max: float = 0.35,
    ct: bool = False,
):
    """``q = q_nom + kappa (w v)^2 T`` while ``|w| > sig sigma_w`` (heading filter), ``w``
    clipped to ``w_max``; with ``ct`` the prediction is a coordinated turn at ``w`` then
    (and ``kappa`` multiplies ``(sigma_w v)^2 T`` instead: the turn-rate uncertainty)."""
    hs: dict[str, Any] = {}

    def policy(ctx: dict[str, Any]) -> None:
        B, dt = ctx["B"], ctx.get("dt", 1.0)
        if ctx["stage"] == "q":
            q = np.full(B, q_nom)
            ctx["w"] = None
            if "w" in hs:
                w, sw, v = np.clip(hs["w"], -w_max, w_max), np.sqrt(hs["P"][:, 1, 1]), hs["v"]
                on = hs["started"] & (np.abs(w) > sig * sw)
                a = np.minimum(sw, w_max) if ct else w
                q = q + np.where(on, kappa * (a * v) ** 2 * dt, 0.0)
                if ct:
                    ctx["w"] = np.where(on, w, 0.0)
            ctx["q"] = q
            return
        if ctx["stage"] != "post":
            return
        x, P = ctx["x"], ctx["P"]
        vx, vy = x[:, 2], x[:, 3]
        v2 = vx**2 + vy**2
        usable = v2 / np.maximum(P[:, 2, 2] + P[:, 3, 3], 1e-12) > 2.0
        b = np.arctan2(vx, vy)
        J = np.stack([vy, -vx], -1) / np.maximum(v2, 1e-12)[:, None]
        vb = np.einsum("bi,bij,bj->b", J, P[:, 2:4, 2:4], J)
        if "w" not in hs:
            hs.update(b=b, w=np.zeros(B), P=np.tile(np.diag([1.0, omega0**2]), (B, 1, 1)),
                      started=np.zeros(B, bool), v=np.sqrt(v2))  # fmt: skip
        Fh = np.array([[1.0, dt], [0.0, 1.0]])
        Qh = q_heading * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
        hb = hs["b"] + hs["w"] * dt
        Ph = Fh @ hs["P"] @ Fh.T + Qh
        e = wrap_pi(b - hb)
        Sb = Ph[:, 0, 0] + vb
        K = Ph[:, :, 0] / Sb[:, None]
        nb = hb + K[:, 0] * e
        nw = hs["w"] + K[:, 1] * e
        nP = Ph - K[:, :, None] * Ph[:, None, 0, :]
        fresh = usable & ~hs["started"]
        nb = np.where(fresh, b, nb)
        nw = np.where(fresh, 0.0, nw)
        P0 = np.zeros_like(nP)
        P0[:, 0, 0], P0[:, 1, 1] = vb, omega0**2
        nP = np.where(fresh[:, None, None], P0, nP)
        keep = ~usable & ~hs["started"]
        hs["b"] = np.where(keep, hs["b"], wrap_pi(nb))
        hs["w"] = np.where(keep, hs["w"], nw)
        hs["P"] = np.where(keep[:, None, None], hs["P"], nP)
        hs["started"] = hs["started"] | usable
        hs["v"] = np.sqrt(v2)

    return policy


def oracle_policy(scs: Sequence[Scenario], q_small: float, ct: bool):
    """ORACLE (knows the truth): ``q = ((w v)^2 + a_t^2) T + q_small`` from the true turn
    rate and along-track acceleration of the interval, or a CT prediction at the true turn
    rate (``ct``) with ``q = a_t^2 T + q_small``. Shows the head-room of any Q schedule /
    turn-rate estimate."""
    w = np.stack([s.turn_rate for s in scs])
    v = np.stack([np.hypot(s.truth[:, 2], s.truth[:, 3]) for s in scs])
    at = np.gradient(v, scs[0].plots.t, axis=1)

    def policy(ctx: dict[str, Any]) -> None:
        if ctx["stage"] != "q":
            return
        k, dt = ctx["k"], ctx["dt"]
        wk = 0.5 * (w[:, k - 1] + w[:, k])
        ak = np.maximum(np.abs(at[:, k - 1]), np.abs(at[:, k]))
        if ct:
            ctx["w"], ctx["q"] = wk, q_small + ak**2 * dt
        else:
            ctx["w"], ctx["q"] = None, q_small + ((wk * v[:, k]) ** 2 + ak**2) * dt

    return policy


def mode_q_policy(qs: Sequence[float], p_stay: Sequence[float]):
    """ONE CV EKF whose q is the mode-probability mixture ``sum_j mu_j^- q_j`` of a Markov
    chain over process-noise levels; ``mu`` is updated from the innovation likelihoods
    ``N(y; 0, H F P F^T H^T + q_j H Q1 H^T + R)`` of each level (a "raise Q on a Bayesian
    manoeuvre decision" filter: one state, one update, M likelihoods)."""
    q = np.asarray(qs, dtype=float)
    M = q.size
    ps = np.asarray(p_stay, dtype=float)
    PI = np.where(np.eye(M) > 0, ps[:, None], ((1 - ps) / max(M - 1, 1))[:, None])
    st: dict[str, Any] = {}

    def policy(ctx: dict[str, Any]) -> None:
        if ctx["stage"] == "q":
            mu = st.get("mu", np.full((ctx["B"], M), 1.0 / M))
            st["prior"] = mu @ PI
            ctx["q"] = st["prior"] @ q
            return
        if ctx["stage"] != "R":
            return
        y, S0, HQ = ctx["y"], ctx["S0"], ctx["HQ1H"]
        S = S0[:, None] + q[None, :, None, None] * HQ[:, None]  # (B, M, m, m)
        _, logdet = np.linalg.slogdet(S)
        maha = np.einsum("bi,bjik,bk->bj", y, np.linalg.inv(S), y)
        lw = np.log(np.maximum(st["prior"], 1e-300)) - 0.5 * (maha + logdet)
        lw -= lw.max(-1, keepdims=True)
        mu = np.exp(lw)
        st["mu"] = mu / mu.sum(-1, keepdims=True)

    return policy


def hybrid_policy(cm: Callable[[dict[str, Any]], None], turn: Callable[[dict[str, Any]], None]):
    """``q = max(q_cm, q_turn)``: covariance matching reacts at a turn's onset, the
    centripetal term keeps q up through a steady turn."""

    def policy(ctx: dict[str, Any]) -> None:
        if ctx["stage"] == "q":
            cm(ctx)
            q1 = ctx["q"]
            turn(ctx)
            ctx["q"] = np.maximum(q1, ctx["q"])
        else:
            cm(ctx)
            turn(ctx)

    return policy


def ct_ekf_batch(
    scs: Sequence[Scenario], q: float, q_omega: float, w_sigma: float, speed_sigma: float
) -> Estimate:
    """A single coordinated-turn EKF ``[x, y, vx, vy, w]`` (white acceleration ``q``,
    turn-rate random walk ``q_omega``), batched over the runs: the turn-rate estimate that
    a CT prediction would use, from the position innovations themselves."""
    from seatrack.models.motion import ct_jacobian
    from seatrack.models.motion import ct_noise
    from seatrack.models.motion import ct_transition

    st = stack_plots(scs)
    z, sen, t = st["z"], st["sensor"], st["t"]
    B, N, m = z.shape
    model = measurement_model(2, 5, m == 3)
    ang = model.angular.astype(float)
    out = np.empty((B, N, 4))
    out[:, 0] = _start(scs, speed_sigma)[0]
    # two-plot start: a CT-EKF started with a zero velocity turns its turn rate into garbage
    pairs = [two_point_gaussian(s.plots.take([0]), s.plots.take([1]), s.sensor) for s in scs]
    x = np.concatenate([np.concatenate([p[0] for p in pairs]), np.zeros((B, 1))], -1)
    P = np.zeros((B, 5, 5))
    P[:, :4, :4] = np.concatenate([p[1] for p in pairs])
    P[:, 4, 4] = w_sigma**2
    out[:, 1] = x[:, :4]
    R0 = _R(scs, m)
    for k in range(2, N):
        dt = float(t[k] - t[k - 1])
        F = ct_jacobian(x, dt)
        x, P = kalman.extended_predict(ct_transition(x, dt), P, F, ct_noise(dt, q, q_omega, 2))
        s = sen[:, k]
        res = kalman.extended_update(x, P, z[:, k], model.h(x, s), model.jacobian(x, s), R0, ang,
                                     check=False)  # fmt: skip
        x, P = res.x, res.P
        out[:, k] = x[:, :4]
    return out


# ---------------------------------------------------------------------------
# Experiments
# ---------------------------------------------------------------------------
def proto_rows(
    variants: dict[str, Callable[..., Callable[[dict[str, Any]], None]]],
    speed_sigma: Callable[[TargetClass], float] | None = None,
) -> Callable[[list[Scenario], TargetClass], list[dict[str, Any]]]:
    def rows(scs: list[Scenario], tc: TargetClass) -> list[dict[str, Any]]:
        out = []
        for label, make in variants.items():
            ss = SPEED_SIGMA if speed_sigma is None else speed_sigma(tc)
            est = polar_cv_loop(scs, make(scs) if "ORACLE" in label else make(), ss)
            pos, vel = rmse(est, scs)
            out.append({"filter": label, "pos": float(pos), "vel": float(vel), "note": "",
                        "kind": "proto"})  # fmt: skip
        return out

    return rows


def ct_rows(scs: list[Scenario], tc: TargetClass) -> list[dict[str, Any]]:
    """CT-EKF rows: generic defaults (no class) and class-derived noise."""
    dt = scs[0].dt
    out = []
    cfgs = {
        "ct-ekf q=1 qw=1e-3": (1.0, 1e-3, 0.1, SPEED_SIGMA),
        "ct-ekf+class": (tc.q_tangential(dt), tc.q_turn_rate, tc.turn_rate_max, tc.speed_max),
    }  # fmt: skip
    for label, (q, qw, ws, ss) in cfgs.items():
        pos, vel = rmse(ct_ekf_batch(scs, q, qw, ws, ss), scs)
        out.append({"filter": label, "pos": float(pos), "vel": float(vel), "note": "",
                    "kind": "proto"})  # fmt: skip
    return out


L5 = (1e-4, 1e-2, 1.0, 1e2, 1e4)  # m^2/s^3: the class-free ladder of the level IMM


def variants_for(set_name: str, dt: float, tc: TargetClass) -> dict[str, Callable[..., Any]]:
    """The CV-loop prototype variants measured on a set (fixed before the headline run)."""
    v: dict[str, Callable[..., Any]] = {
        # (d) self-tuning, sensor noise only
        "cm-ekf b=0.7": lambda: cm_policy(1e-4, 1e5, 0.7),
        # (a) turning: Q from the centripetal acceleration of the heading filter's turn rate
        "turn-centripetal k=3": lambda: turning_policy(0.5, 3.0, 1e-4, 1.0),
        "turn-ct (heading-filter w)": lambda: turning_policy(0.5, 1.0, 1e-4, 1.0, ct=True),
        "hybrid cm0.7+centripetal": lambda: hybrid_policy(
            cm_policy(1e-4, 1e5, 0.7), turning_policy(0.5, 1.0, 1e-4, 1.0)
        ),
        "mode-q L5": lambda: mode_q_policy(L5, [0.95] * 5),
        "mode-q+class": lambda: mode_q_policy((tc.q_steady(dt), tc.q_max(dt)), tc.p_stay(dt)),
        "ORACLE q=((wv)^2+at^2)T": lambda scs: oracle_policy(scs, tc.q_steady(dt), ct=False),
        "ORACLE ct(true w)": lambda scs: oracle_policy(scs, tc.q_steady(dt), ct=True),
    }
    if "c20" in set_name:
        v["robust-cm b=0.8 D=2.7"] = lambda: cm_policy(1e-4, 1e5, 0.8, robust_delta=2.7)
    return v


#: tuned configurations of the existing methods, measured beside their defaults
def extra_configs(dt: float, tc: TargetClass, range_rate: bool) -> dict[str, dict[str, Any]]:
    """Configurations of library methods measured beside their defaults: ``label=method``
    -> config keys added to the nominal noise. The level IMM of :mod:`seatrack.filters.
    levels` with the phase-A settings (Gaussian, ``epsilon = 0``; contaminated ``0.1``),
    and, with range rate, the variants of the IMM with range rate and of the patent's bank."""
    g, cls = {"outlier_probability": 0.0}, {"target": tc.name}
    out: dict[str, dict[str, Any]] = {
        "L5 gaussian=mm": g,
        "2 levels+class gaussian=mm": {**g, **cls},
        "L5 eps0.1=robust-adaptive": {"use_range_rate": False},
        "2 levels+class eps0.1=robust-adaptive": {"use_range_rate": False, **cls},
    }
    if range_rate:
        out |= {
            "g=5 sa=10=mm-rangerate-spec": {"accel_g": 5.0, "sigma_accel_mps2": 10.0},
            "+rr q_ct=100=mm-rangerate": {"q_ct": 100.0},
            "L5 +rr=turning": {},
        }  # fmt: skip
    return out


def consistency(n: int) -> None:
    """Fighter set, TUNING seeds: position consistency (mean of the squared errors over the
    reported variances, per axis; 1 = consistent) and how often the largest model
    probability exceeds 0.99, for the multiple-model methods."""
    from defaults import SKIP
    from defaults import nominal_config
    from seatrack.filters.registry import run

    scs = [SETS["fighter"].make(k) for k in seeds(n, True)]
    cfgs = {
        "mm-rangerate-spec": ("mm-rangerate-spec", {}),
        "mm-rangerate-spec g=5 sa=10": (
            "mm-rangerate-spec", {"accel_g": 5.0, "sigma_accel_mps2": 10.0}
        ),
        "mm-spec": ("mm-spec", {}),
        "imm": ("imm", {}),
        "mm-rangerate (IMM + rr, q_ct 1000)": (
            "mm-rangerate", {"q_agile": 0.0, "q_omega": 1e-3, "p_stay": 0.95}
        ),
        "mm-rangerate (default, + agile CV)": ("mm-rangerate", {}),
        "mm (level IMM)": ("mm", {}),
    }  # fmt: skip
    for label, (method, cfg) in cfgs.items():
        z2, pmax = [], []
        for sc in scs:
            plots = dataclasses.replace(sc.plots, elevation=None)
            cols = run(method, plots, {**nominal_config(sc), **cfg})
            ex = (cols["x_m"] - sc.truth[:, 0]) / cols["std_x_m"]
            ey = (cols["y_m"] - sc.truth[:, 1]) / cols["std_y_m"]
            z2.append(((ex**2 + ey**2) / 2)[SKIP:])
            probs = [cols[c] for c in cols if c.startswith("p_")]
            pmax.append(np.max(np.stack(probs), 0)[SKIP:])
        e2, pm = np.concatenate(z2), np.concatenate(pmax)
        print(f"{label:36s} squared error / variance {e2.mean():5.2f}  "
              f"max model probability > 0.99 on {np.mean(pm > 0.99):.2f} of scans")  # fmt: skip


def kinematic_matrices(dt: float, q: float, tau: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Transition and process noise of ``[x, y, vx, vy, ax, ay]``: white jerk of PSD ``q``
    (m^2/s^5; ``tau`` None, the CA model) or a Singer acceleration of time constant ``tau``
    (s) driven by white noise of PSD ``q`` (Van Loan discretisation)."""
    from scipy.linalg import expm

    a = 0.0 if tau is None else 1.0 / tau
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -a]])
    M = np.zeros((6, 6))
    M[:3, :3], M[:3, 3:], M[3:, 3:] = -A, np.diag([0.0, 0.0, q]), A.T
    E = expm(M * dt)
    F1 = E[3:, 3:].T
    Q1 = F1 @ E[:3, 3:]
    F, Q = np.kron(F1, np.eye(2)), np.kron(0.5 * (Q1 + Q1.T), np.eye(2))
    return F, Q


def kinematic_batch(
    scs: Sequence[Scenario], qs: np.ndarray, tau: float | None, tc: TargetClass
) -> Estimate:
    """CA / Singer EKFs on polar plots for every run and every PSD of ``qs`` at once,
    ``(G, B, N, 4)``; started from the first plot (class speed and acceleration maxima as
    the velocity and acceleration stds)."""
    z, sen, t, model, ang = polar_setup(scs)
    B, N, m = z.shape
    G = len(qs)
    x4, P4 = _start(scs, tc.speed_max)
    x = np.zeros((G, B, 6))
    x[..., :4] = x4
    P = np.zeros((G, B, 6, 6))
    P[..., :4, :4] = P4
    P[..., 4, 4] = P[..., 5, 5] = tc.accel_max**2
    R0 = _R(scs, m)
    out = np.empty((G, B, N, 4))
    out[:, :, 0] = x4
    for k in range(1, N):
        dt = float(t[k] - t[k - 1])
        pairs = [kinematic_matrices(dt, float(q), tau) for q in qs]
        Q = np.stack([p[1] for p in pairs])[:, None]
        x, P = kalman.predict(x, P, pairs[0][0], Q)
        xs = np.ascontiguousarray(x[..., :4])
        J = model.jacobian(xs, sen[:, k])
        H = np.concatenate([J, np.zeros(J.shape[:-1] + (2,))], -1)
        res = kalman.extended_update(x, P, z[:, k], model.h(xs, sen[:, k]), H, R0, ang,
                                     check=False)  # fmt: skip
        x, P = res.x, res.P
        out[:, :, k] = x[..., :4]
    return out


def model_bounds(set_names: Sequence[str], n: int, tuning: bool) -> None:
    """Best RMSE of every single motion model with hindsight noise (module docstring)."""
    from defaults import cv_ekf_batch
    from defaults import q_grid
    from seatrack.models.targets import target_class

    for name in set_names:
        ss = SETS[name]
        scs = [ss.make(k) for k in seeds(n, tuning)]
        tc = target_class(ss.target)
        dt = scs[0].dt
        R0 = _R(scs, 3 if scs[0].plots.has_range_rate else 2)
        grid = q_grid(tc, dt)
        cv = rmse(cv_ekf_batch(scs, grid, R0, tc.speed_max), scs)[0]
        nw = rmse(cv_ekf_batch(scs, np.array([tc.q_steady(dt), tc.q_max(dt)]), R0,
                               tc.speed_max), scs)[0]  # fmt: skip
        best, ref = float(np.min(cv)), float(np.min(nw))
        print(f"{name}: best CV q {grid[int(np.argmin(cv))]:.3g} m^2/s^3, RMSE {best:.1f} m; "
              f"min(narrow, wide) {ref:.1f} m; turning target {0.95 * ref:.1f} m")  # fmt: skip
        rows: list[tuple[str, float, str]] = []
        jerk = np.logspace(-3, 3, 19)
        for label, tau in (("CA (white jerk)", None), ("Singer tau=30 s", 30.0),
                           ("Singer tau=10 s", 10.0)):  # fmt: skip
            pos = rmse(kinematic_batch(scs, jerk, tau, tc), scs)[0]
            i = int(np.argmin(pos))
            rows.append((label, float(pos[i]), f"q={jerk[i]:.3g} m^2/s^5"))
        ct_best = (math.inf, "")
        for q in np.logspace(-1, 4, 11):
            for qw in np.logspace(-9, -3, 7):
                pos = float(rmse(ct_ekf_batch(scs, q, qw, tc.turn_rate_max, tc.speed_max),
                                 scs)[0])  # fmt: skip
                if pos < ct_best[0]:
                    ct_best = (pos, f"q={q:.3g} m^2/s^3, q_omega={qw:.3g} rad^2/s^3")
        rows.append(("CT-EKF", *ct_best))
        for label, pos, note in rows:
            print(f"  {label:18s} {pos:8.1f} m  / best CV q {pos / best:.3f}  "
                  f"/ min(narrow, wide) {pos / ref:.3f}  ({note})")  # fmt: skip
        sys.stdout.flush()


def gross_outliers(n: int, tuning: bool) -> None:
    """The contaminated sets with 10-sigma outliers (module docstring)."""
    from defaults import anchor_rows
    from defaults import nominal_config
    from defaults import run_method
    from seatrack.models.targets import target_class
    from seatrack.simulate import families

    families.OUTLIER_SCALE = (100.0, 100.0, 100.0)  # this process only
    ramazanov = {"outlier_scale_range": 10.0, "outlier_scale_azimuth": 25.0}
    for name in ("ais-sonar-c20", "submarine-c20"):
        ss = SETS[name]
        scs = [ss.make(k) for k in seeds(n, tuning)]
        ref = {r["filter"]: r["pos"] for r in anchor_rows(scs, target_class(ss.target))}
        mix = ref["cv mixture R (hindsight q)"]
        print(f"{name}, outliers at 10 sigma: mixture-R EKF {mix:.1f} m, clairvoyant "
              f"{ref['clairvoyant (hindsight q)']:.1f} m")  # fmt: skip
        for method in ("robust-adaptive", "robust", "huber", "student-t", "turning", "mm"):
            for label, extra in (("k = 100 (default)", {}), ("k = (10, 25)", ramazanov)):
                est = run_method(method, scs, {**nominal_config(scs[0]), **extra})
                pos, vel = rmse(est, scs)
                print(f"  {method:16s} {label:18s} pos {pos:7.1f} m  vel {vel:6.2f} m/s  "
                      f"/ mixture-R {pos / mix:.3f}")  # fmt: skip


def level_trace(
    scs: Sequence[Scenario], config: dict[str, Any], name: str = "turning"
) -> tuple[Estimate, np.ndarray]:
    """Level method ``name`` from the registry driven scan by scan over the runs of a set
    (one batch): the combined estimates ``(B, N, 4)`` and the level probabilities
    ``(B, N, M)``."""
    from defaults import nominal_config
    from seatrack.filters.registry import build
    from seatrack.simulate.families import labelled_runs

    plots = labelled_runs(scs)
    table = {**nominal_config(scs[0]), **config}
    method = build(name, table, range_rate=plots.has_range_rate)
    flt = method.filter
    B, N = len(scs), len(scs[0].plots)
    first = plots.take(np.arange(B) * N)
    state = flt.initiate(first.t, *method.initiate(first))
    est, mu = np.empty((B, N, 4)), np.empty((B, N, flt.M))
    est[:, 0], mu[:, 0] = state.x, state.aux["mu"]
    for k in range(1, N):
        pk = plots.take(np.arange(B) * N + k)
        state = flt.update(flt.predict(state, pk.t), pk)
        est[:, k], mu[:, k] = state.x, state.aux["mu"]
    return est, mu


def range_rate_levels(n: int, tuning: bool) -> None:
    """Why range rate hurt the level IMM on ``weave-fighter`` (docs/defaults.md): ``turning``
    with and without the plots' range rate, isotropic levels on the old ladder (top rung
    1e4) against the along-track shape and the default ladder; position RMSE (after the
    transient), and over the weave (after the straight first minute) the mean level
    probabilities and the RMS errors along / across the line of sight."""
    scs = [SETS["weave-fighter"].make(k) for k in seeds(n, tuning)]
    truth = np.stack([s.truth for s in scs])
    rel = truth[..., :2] - np.stack([s.plots.sensor[:, :2] for s in scs])
    los = rel / np.linalg.norm(rel, axis=-1, keepdims=True)
    across = np.stack([los[..., 1], -los[..., 0]], -1)
    weave = scs[0].plots.t >= 60.0
    from seatrack.filters.levels import LADDER
    from seatrack.filters.levels import LevelConfig

    old = {"q_levels": [1e-4, 1e-2, 1.0, 1e2, 1e4]}
    ratio = LevelConfig().along_track_ratio
    configs = {
        "isotropic, top 1e4 (before)": {**old, "along_track_ratio": 1.0},
        f"along-track {ratio:g}, top 1e4": old,
        f"default (along-track {ratio:g}, top {LADDER[-1]:g})": {},
    }
    print(f"weave-fighter, turning, {n} {'tuning' if tuning else 'headline'} runs")
    for label, cfg in configs.items():
        for rr in (True, False):
            est, mu = level_trace(scs, {**cfg, "use_range_rate": rr})
            e = est - truth

            def rms(u: np.ndarray, sl: slice) -> float:
                return float(np.sqrt(np.mean(np.sum(e[..., sl] * u, -1)[:, weave] ** 2)))

            probs = " ".join(f"{v:.2f}" for v in mu[:, weave].mean((0, 1)))
            print(f"  {label:36s} rr {'yes' if rr else 'no ':3s} pos {rmse(est, scs)[0]:6.1f} m | "
                  f"weave: levels {probs} | pos along / across LOS {rms(los, slice(0, 2)):5.1f} / "
                  f"{rms(across, slice(0, 2)):5.1f} m, vel {rms(los, slice(2, 4)):5.1f} / "
                  f"{rms(across, slice(2, 4)):5.1f} m/s")  # fmt: skip


def scans_since_onset(manoeuvring: np.ndarray) -> np.ndarray:
    """Scans since the start of the current manoeuvre ``(B, N)`` (a large number off one)."""
    since = np.full(manoeuvring.shape, 10**6)
    for b, row in enumerate(manoeuvring):
        for k in np.flatnonzero(row):
            since[b, k] = since[b, k - 1] + 1 if k > 0 and row[k - 1] else 0
    return since


def manoeuvre_onsets(n: int, tuning: bool) -> None:
    """Why the robust rules lagged on ``fighter`` (docs/defaults.md): the level methods
    scan by scan, with and without range rate (where the method has the key); position RMSE
    (after the transient), the RMS error over scans 0-2 and 3-5 after each manoeuvre onset
    of the truth and the mean probability of the agile levels (``q >= 1e2``) over scans
    0-2."""
    from seatrack.config import ConfigError

    scs = [SETS["fighter"].make(k) for k in seeds(n, tuning)]
    truth = np.stack([s.truth for s in scs])
    since = scans_since_onset(np.stack([s.manoeuvring for s in scs]))
    since[:, :10] = -1  # the transient
    print(f"fighter, {n} {'tuning' if tuning else 'headline'} runs")
    for name in ("mm", "robust-adaptive", "robust", "huber", "student-t"):
        for rr in (False, True):
            if name == "mm" and rr:
                continue
            try:
                est, mu = level_trace(scs, {"use_range_rate": rr}, name)
            except ConfigError:  # a version of the method without the key: no range rate
                if rr:
                    continue
                est, mu = level_trace(scs, {}, name)
            e2 = np.sum((est - truth)[..., :2] ** 2, -1)
            onset, later = (since >= 0) & (since < 3), (since >= 3) & (since < 6)
            agile = mu[..., 3:].sum(-1)[onset].mean()
            print(f"  {name:16s} rr {'yes' if rr else 'no ':3s} pos {rmse(est, scs)[0]:6.1f} m | "
                  f"error 0-2 / 3-5 scans after onset {np.sqrt(e2[onset].mean()):5.0f} / "
                  f"{np.sqrt(e2[later].mean()):5.0f} m | P(agile) 0-2 {agile:.2f}")  # fmt: skip


def main(argv: Sequence[str] | None = None) -> None:
    from seatrack.models.targets import target_class

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--sets", default=",".join(SETS))
    ap.add_argument("--methods", default="ekf,turning,robust-adaptive,mm-rangerate,imm")
    ap.add_argument("--headline", action="store_true", help="headline seeds (default tuning)")
    ap.add_argument("--consistency", action="store_true", help="multiple-model consistency")
    ap.add_argument("--model-bounds", action="store_true", help="hindsight single models")
    ap.add_argument("--gross-outliers", action="store_true", help="10-sigma outliers")
    ap.add_argument("--range-rate-levels", action="store_true", help="rr and the levels")
    ap.add_argument("--onsets", action="store_true", help="robust rules at manoeuvre onsets")
    a = ap.parse_args(argv)
    if a.onsets:
        manoeuvre_onsets(a.runs, not a.headline)
        return
    if a.range_rate_levels:
        range_rate_levels(a.runs, not a.headline)
        return
    if a.gross_outliers:
        gross_outliers(a.runs, not a.headline)
        return
    if a.consistency:
        consistency(a.runs)
        return
    if a.model_bounds:
        sets = a.sets if a.sets != ",".join(SETS) else "weave-aircraft,weave-fighter"
        model_bounds(sets.split(","), a.runs, not a.headline)
        return
    tuning = not a.headline
    print(f"seeds: {'TUNING' if tuning else 'HEADLINE'}")
    for name in a.sets.split(","):
        ss = SETS[name]
        scs = [ss.make(k) for k in seeds(a.runs, tuning)]
        tc = target_class(ss.target)
        extra = extra_configs(scs[0].dt, tc, scs[0].plots.has_range_rate)
        rows = method_rows(scs, a.methods.split(","), ss.target, extra) + anchor_rows(scs, tc)
        rows += proto_rows(variants_for(name, scs[0].dt, tc))(scs, tc)
        rows += ct_rows(scs, tc)
        print_set(ss, rows, targets(name, rows), a.runs)
        sys.stdout.flush()


if __name__ == "__main__":
    main()
