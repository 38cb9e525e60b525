"""The compiled S2-S5 of the turning filter equals the spec's pure functions step by step."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seatrack.filters import heading as Hd
from seatrack.filters import turning as T
from seatrack.filters.turning_kernel import turn_logic


def _reference(xs, Ps, ts, cfg, d, v_threshold):
    """S2-S5 for one track with the pure functions (the spec's order)."""
    hs = hP = ht = None
    queue: tuple[float, ...] = ()
    out = []
    for x, P, t in zip(xs, Ps, ts, strict=True):
        v, var_v = x[d:], np.diag(P)[d:]
        d_t = float(Hd.velocity_significance(v, var_v))
        d_w, state, gain = math.nan, 0, 1.0
        if d_t > v_threshold:
            b = float(Hd.heading(v))
            cov = P[d : d + 2, d : d + 2] if cfg.heading_cross_covariance else var_v[:2]
            var_b = float(Hd.heading_variance(v[:2], cov))
            if hs is None:
                hs, hP = Hd.heading_filter_init(b, var_b, cfg.sigma_omega0)
            else:
                est = Hd.heading_filter_step(
                    hs, hP, b, var_b, t - ht, cfg.q_heading, cfg.heading_noise
                )
                hs, hP = est.s, est.P
            ht = t
            d_w = float(T.turn_rate_significance(hs[1], hP[1, 1]))
            if d_w > cfg.turn_rate_threshold:
                queue, ready = T.push_turn_rate(queue, hs[1], cfg.queue_length)
                if ready:
                    st, delta = T.fuzzy_vote(queue, cfg.count, cfg.delta_omega_threshold)
                    state = int(st)
                    if state:
                        gain = float(
                            T.noise_gain(delta, cfg.gain_reference, cfg.gain_power, cfg.gain_max)
                        )
        out.append((d_t, d_w, state, gain, None if hs is None else hs.copy()))
    return out


@pytest.mark.parametrize(
    "kw", [{}, {"heading_cross_covariance": True}, {"heading_noise": "diagonal"}]
)
def test_kernel_equals_the_pure_functions(kw):
    rng = np.random.default_rng(4)
    d = 2
    cfg = T.TurningConfig(delta_omega_threshold=0.002, gain_reference=0.005, **kw)
    K = 120
    ts = np.cumsum(rng.uniform(1.0, 3.0, K))
    course = 0.4 + np.cumsum(np.where((ts > 60) & (ts < 180), 0.03, -0.002) * 2.0)
    speed = np.where(ts < 20, 0.3, 12.0)
    xs = np.zeros((K, 4))
    xs[:, 2], xs[:, 3] = speed * np.sin(course), speed * np.cos(course)
    A = rng.normal(size=(K, 4, 4)) * 0.3
    Ps = A @ np.swapaxes(A, 1, 2) + np.eye(4)
    ref = _reference(xs, Ps, ts, cfg, d, 2.0)
    hs, hP, ht = np.zeros((1, 2)), np.zeros((1, 2, 2)), np.full(1, np.nan)
    queue, qn = np.full((1, cfg.queue_length), np.nan), np.zeros(1, np.int64)
    fired = 0
    for k in range(K):
        d_t, d_w, gain = np.empty(1), np.empty(1), np.empty(1)
        state = np.empty(1, np.int8)
        turn_logic(
            xs[k : k + 1], Ps[k : k + 1], ts[k : k + 1], d, hs, hP, ht, queue, qn, 2.0,
            cfg.heading_cross_covariance, cfg.sigma_omega0, cfg.q_heading,
            cfg.heading_noise == "diagonal", cfg.turn_rate_threshold, cfg.count,
            cfg.delta_omega_threshold, cfg.gain_reference, cfg.gain_power, cfg.gain_max,
            d_t, d_w, state, gain,
        )  # fmt: skip
        r_dt, r_dw, r_state, r_gain, r_hs = ref[k]
        assert d_t[0] == pytest.approx(r_dt, rel=1e-12)
        np.testing.assert_allclose(d_w[0], r_dw, rtol=1e-9)
        assert state[0] == r_state and gain[0] == pytest.approx(r_gain, rel=1e-9)
        if r_hs is not None:
            np.testing.assert_allclose(hs[0], r_hs, rtol=1e-9, atol=1e-12)
        fired += r_state != 0
    assert fired > 0  # the vote fired in this sequence: the comparison covers S4-S5
