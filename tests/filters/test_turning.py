"""Tests of the turning-target filter (CN 104407337, docs/turning.md): each step alone,
then the whole filter on (near) noiseless turns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seatrack import kalman
from seatrack.filters import heading as Hd
from seatrack.filters import turning as T
from seatrack.filters.base import SensorNoise
from seatrack.geometry import spherical_to_cart
from seatrack.geometry import wrap_pi
from seatrack.models import numerical_jacobian
from seatrack.models.motion import cv_noise
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory

DEG = math.pi / 180


# ---------------------------------------------------------------------------
# S2: velocity significance
# ---------------------------------------------------------------------------
def test_velocity_significance_value_and_broadcast():
    v = np.array([[3.0, 4.0], [1.0, -2.0]])
    var = np.array([[1.0, 4.0], [0.25, 1.0]])
    d = Hd.velocity_significance(v, var)
    np.testing.assert_allclose(d, [9.0 + 4.0, 4.0 + 4.0])
    assert Hd.velocity_significance([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]) == 0.0


def test_velocity_significance_is_chi_square_under_zero_velocity():
    """For v ~ N(0, diag(sigma^2)) the statistic has mean N and variance 2N (chi^2_N),
    which is why the spec's threshold is N."""
    rng = np.random.default_rng(1)
    for n in (2, 3):
        sig = np.array([2.0, 0.5, 3.0])[:n]
        d = Hd.velocity_significance(rng.normal(0, sig, (40_000, n)), sig**2)
        assert abs(d.mean() - n) < 4 * math.sqrt(2 * n / d.size)
        assert abs(d.var() - 2 * n) < 0.1 * 2 * n


# ---------------------------------------------------------------------------
# S2: heading and its variance
# ---------------------------------------------------------------------------
def test_heading_convention_and_wrap():
    assert Hd.heading([0.0, 5.0]) == pytest.approx(0.0)  # North
    assert Hd.heading([5.0, 0.0]) == pytest.approx(math.pi / 2)  # East
    assert Hd.heading([-5.0, 0.0]) == pytest.approx(-math.pi / 2)  # West -> wrapped
    assert Hd.heading([0.0, -5.0]) == pytest.approx(math.pi)  # South: +pi, in (-pi, pi]
    b = Hd.heading(np.array([[1.0, 1.0], [-1.0, -1.0]]))
    np.testing.assert_allclose(b, [math.pi / 4, -3 * math.pi / 4])


@pytest.mark.parametrize("v", [[120.0, -35.0], [-3.0, -7.5], [0.2, 9.0], [-80.0, 0.1]])
def test_heading_jacobian_matches_numerical_atan2(v):
    J = Hd.heading_jacobian(v)
    Jn = numerical_jacobian(lambda x: np.array([Hd.heading(x)]), v, angular=[True])
    np.testing.assert_allclose(J, Jn[0], rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("v", [[120.0, -35.0], [-3.0, -7.5], [0.2, 9.0]])
def test_heading_variance_is_spec_formula_and_jacobian_propagation(v):
    vE, vN = v
    var = np.array([4.0, 9.0])
    spec = (vN**2 * var[0] + vE**2 * var[1]) / (vE**2 + vN**2) ** 2
    assert Hd.heading_variance(v, var) == pytest.approx(spec, rel=1e-12)
    # same thing as J C J^T with J the numerical Jacobian of atan2(vE, vN)
    Jn = numerical_jacobian(lambda x: np.array([Hd.heading(x)]), v, angular=[True])
    assert Hd.heading_variance(v, var) == pytest.approx((Jn @ np.diag(var) @ Jn.T).item(), rel=1e-6)
    # full covariance: adds the cross term
    C = np.array([[4.0, 3.0], [3.0, 9.0]])
    assert Hd.heading_variance(v, C) == pytest.approx((Jn @ C @ Jn.T).item(), rel=1e-6)


def test_heading_variance_matches_monte_carlo_for_small_noise():
    rng = np.random.default_rng(7)
    v = np.array([6.0, -4.0])
    sig = np.array([0.05, 0.08])
    b = Hd.heading(v + rng.normal(0, sig, (50_000, 2)))
    sample = np.var(wrap_pi(b - Hd.heading(v)))
    assert sample == pytest.approx(Hd.heading_variance(v, sig**2), rel=0.03)


# ---------------------------------------------------------------------------
# S2: heading / turn-rate filter
# ---------------------------------------------------------------------------
def test_heading_filter_noise_forms():
    Q = Hd.heading_filter_noise(2.0, 1e-6)
    np.testing.assert_allclose(Q, 1e-6 * np.array([[8 / 3, 2.0], [2.0, 2.0]]))
    Qd = Hd.heading_filter_noise(2.0, 1e-6, "diagonal")
    np.testing.assert_allclose(Qd, 1e-6 * np.diag([8 / 3, 2.0]))
    with pytest.raises(ValueError, match="heading_noise"):
        Hd.heading_filter_noise(2.0, 1e-6, "other")


def test_heading_filter_init():
    s, P = Hd.heading_filter_init(3.5, 0.01, 0.1)
    np.testing.assert_allclose(s, [3.5 - 2 * math.pi, 0.0])
    np.testing.assert_allclose(P, np.diag([0.01, 0.01]))


def test_heading_filter_step_gains_are_the_spec_ones():
    s = np.array([0.3, 0.01])
    P = np.array([[0.02, 0.001], [0.001, 0.004]])
    dt, q, var_b = 4.0, 1e-6, 0.005
    F = np.array([[1.0, dt], [0.0, 1.0]])
    Pp = F @ P @ F.T + Hd.heading_filter_noise(dt, q)
    est = Hd.heading_filter_step(s, P, 0.42, var_b, dt, q)
    r_b = Pp[0, 0] / (Pp[0, 0] + var_b)
    r_w = Pp[1, 0] / (Pp[0, 0] + var_b)
    np.testing.assert_allclose(est.gain, [r_b, r_w], rtol=1e-12)
    e = 0.42 - (0.3 + 0.01 * dt)
    assert est.innovation == pytest.approx(e)
    np.testing.assert_allclose(est.s, [0.34 + r_b * e, 0.01 + r_w * e], rtol=1e-12)
    K = np.array([[r_b], [r_w]])
    H = np.array([[1.0, 0.0]])
    np.testing.assert_allclose(est.P, (np.eye(2) - K @ H) @ Pp, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("start, rate", [(math.pi - 0.3, 0.02), (-math.pi + 0.3, -0.02)])
def test_heading_filter_across_the_pi_wrap(start, rate):
    """A steady turn through South (+-pi): innovations stay small, the state stays in
    (-pi, pi] and the turn rate converges; without wrapping the innovation would jump 2 pi."""
    dt, var_b = 2.0, (0.2 * DEG) ** 2
    rng = np.random.default_rng(3)
    t = np.arange(60) * dt
    b_true = wrap_pi(start + rate * t)
    b_meas = wrap_pi(b_true + rng.normal(0, math.sqrt(var_b), t.size))
    assert np.abs(np.diff(b_meas)).max() > math.pi  # the measurements really wrap
    s, P = Hd.heading_filter_init(b_meas[0], var_b, 0.1)
    innov, heads = [], []
    for k in range(1, t.size):
        est = Hd.heading_filter_step(s, P, b_meas[k], var_b, dt)
        s, P = est.s, est.P
        innov.append(est.innovation)
        heads.append(s[0])
    assert np.max(np.abs(innov[5:])) < 10 * math.sqrt(var_b)
    assert all(-math.pi < h <= math.pi for h in heads)
    assert abs(wrap_pi(heads[-1] - b_true[-1])) < 5 * math.sqrt(var_b)
    assert s[1] == pytest.approx(rate, abs=5 * math.sqrt(P[1, 1]))
    assert math.sqrt(P[1, 1]) < 0.1 / 20  # learnt: far below the initial sigma_omega0


# ---------------------------------------------------------------------------
# S3 - S5
# ---------------------------------------------------------------------------
def test_turn_rate_significance():
    np.testing.assert_allclose(T.turn_rate_significance([-0.02, 0.01], [1e-4, 4e-4]), [2.0, 0.5])


def test_queue_fifo_and_ready_only_when_length_exceeds_M():
    M = 4
    q: tuple[float, ...] = ()
    readies = []
    for k in range(7):
        q, ready = T.push_turn_rate(q, float(k), M)
        readies.append(ready)
        assert len(q) == min(k + 1, M)
    assert readies == [False, False, False, False, True, True, True]
    assert q == (3.0, 4.0, 5.0, 6.0)  # oldest first, head dropped


def test_fuzzy_vote_rising_falling_and_tolerated_violation():
    M = 5
    K = M - 2
    rising = [0.00, 0.01, 0.02, 0.03, 0.04]
    assert T.fuzzy_vote(rising, K) == (T.TurnState.RISING, pytest.approx(0.04))
    # one violated comparison is tolerated by K = M - 2 ...
    one_bad = [0.00, 0.015, 0.01, 0.03, 0.04]
    assert T.fuzzy_vote(one_bad, K)[0] is T.TurnState.RISING
    # ... but not by the strict rule K = M - 1, nor two violations by K = M - 2
    assert T.fuzzy_vote(one_bad, M - 1)[0] is T.TurnState.STRAIGHT
    two_bad = [0.00, 0.015, 0.01, 0.035, 0.03]
    assert T.fuzzy_vote(two_bad, K)[0] is T.TurnState.STRAIGHT
    falling = [0.01, -0.005, -0.01, -0.02, -0.03]
    assert T.fuzzy_vote(falling, K) == (T.TurnState.FALLING, pytest.approx(0.04))
    # monotonic but |omega_M - omega_1| below the 0.02 rad/s threshold
    small = [0.000, 0.004, 0.008, 0.012, 0.016]
    state, delta = T.fuzzy_vote(small, K)
    assert state is T.TurnState.STRAIGHT and delta == pytest.approx(0.016)
    assert T.fuzzy_vote(small, K, delta_omega_threshold=0.01)[0] is T.TurnState.RISING


def test_noise_gain_clipped():
    assert T.noise_gain(0.04) == pytest.approx(4.0)  # (0.04 / 0.02)^2
    assert T.noise_gain(0.01) == 1.0  # never below 1
    assert T.noise_gain(1.0, gain_max=50.0) == 50.0  # cap
    np.testing.assert_allclose(T.noise_gain([0.0, 0.03, 0.1], 0.01, 1.0, 5.0), [1.0, 3.0, 5.0])


def test_config_validation():
    assert T.TurningConfig().count == 3  # K = M - 2 with M = 5
    assert T.TurningConfig(queue_length=7, count_min=6).count == 6
    with pytest.raises(ValueError, match="M must be an integer > 3"):
        T.TurningConfig(queue_length=3)
    with pytest.raises(ValueError, match="count_min"):
        T.TurningConfig(queue_length=5, count_min=5)
    with pytest.raises(ValueError, match="q_nominal"):
        T.TurningConfig(q_nominal=-1.0)
    with pytest.raises(ValueError, match="gain_max"):
        T.TurningConfig(gain_max=0.5)


# ---------------------------------------------------------------------------
# S1 pieces
# ---------------------------------------------------------------------------
def test_initial_state_converts_the_plot_and_its_covariance():
    z = np.array([20_000.0, 1.2, 0.05])
    sensor = np.array([100.0, -50.0, 10.0])
    R = T.plot_covariance(30.0, 0.002, 0.003, 3)
    x, P = T.initial_state(z, R, 250.0, sensor)
    np.testing.assert_allclose(x[:3], spherical_to_cart(*z) + sensor, rtol=1e-12)
    np.testing.assert_allclose(x[3:], 0.0)
    G = numerical_jacobian(lambda zz: spherical_to_cart(zz[0], zz[1], zz[2]), z)
    np.testing.assert_allclose(P[:3, :3], G @ R @ G.T, rtol=1e-5)
    np.testing.assert_allclose(P[3:, 3:], np.eye(3) * 250.0**2)


def test_ekf_step_batch_equals_single():
    rng = np.random.default_rng(5)
    R = T.plot_covariance(20.0, 0.003, 0.0, 2)
    xs = np.array([[5000.0, 8000.0, 10.0, -3.0], [-7000.0, 2000.0, -5.0, 6.0]])
    P = np.diag([400.0, 400.0, 25.0, 25.0])
    z = np.array([[9500.0, 0.56], [7300.0, 4.99]]) + rng.normal(0, 1e-3, (2, 2))
    Q = cv_noise(2.0, np.array([0.1, 3.0]), 2)
    batch = T.ekf_step(xs, np.broadcast_to(P, (2, 4, 4)), z, 2.0, Q, R)
    for i in range(2):
        single = T.ekf_step(xs[i], P, z[i], 2.0, Q[i], R)
        np.testing.assert_allclose(batch.x[i], single.x, rtol=1e-12)
        np.testing.assert_allclose(batch.P[i], single.P, rtol=1e-12)


# ---------------------------------------------------------------------------
# Whole filter
# ---------------------------------------------------------------------------
def _turn_scenario(d: int, rate: float, course: float = 0.0):
    legs = [Leg.straight(120.0), Leg(duration=240.0, turn_rate=rate)]
    start = [8000.0, 12000.0, 1500.0][:d] if d == 3 else [8000.0, 12000.0]
    return trajectory(start, course, 120.0, legs, dt=2.0)


@pytest.mark.parametrize("d, rate", [(2, 3 * DEG), (3, -3 * DEG), (2, -1 * DEG)])
def test_noiseless_turn_recovers_the_turn_rate(d, rate):
    """Noiseless plots of a steady turn (through North for the left turns): after the
    filters settle the estimated turn rate equals the true one."""
    tr = _turn_scenario(d, rate, course=10 * DEG)
    comps = ("range", "azimuth", "elevation")[:d]
    m = observe(tr, None, comps, NoiseModel([0.0] * d), np.random.default_rng(11))
    cfg = T.TurningConfig(q_nominal=1.0)
    res = T.TurningFilter(cfg, d, SensorNoise(0.01, 1e-6, 1e-6)).run(m.t, m.z)
    late = m.t > 240.0  # last 2 minutes of the 4-minute turn
    np.testing.assert_allclose(res.turn_rate[late], rate, atol=0.01 * DEG)
    assert np.all(res.turn_rate_std[late] < cfg.sigma_omega0 / 10)
    straight = (m.t > 40.0) & (m.t < 120.0)
    np.testing.assert_allclose(res.turn_rate[straight], 0.0, atol=0.01 * DEG)
    # the track itself is accurate; the heading output is the course on the straight leg
    # and, in the turn, lags it by less than one scan's worth of turning (CV model)
    pos_err = np.linalg.norm(res.x[:, :d] - tr.pos[:, :d], axis=1)
    assert pos_err[late].max() < 1.0
    hdg_err = np.abs(wrap_pi(res.heading - tr.course))
    assert hdg_err[straight].max() < 0.01 * DEG
    assert hdg_err[late].max() < abs(rate) * 2.0
    np.testing.assert_allclose(res.speed[late], 120.0, rtol=1e-3)
    assert np.all(res.state[straight] == T.TurnState.STRAIGHT)
    entry = (m.t >= 120.0) & (m.t < 200.0)
    if abs(rate) > cfg.delta_omega_threshold:
        # the turn entry is declared (rising for a right turn, falling for a left turn)
        expect = T.TurnState.RISING if rate > 0 else T.TurnState.FALLING
        assert np.any(res.state[entry] == expect)
        assert np.any(res.q_gain[entry] > 1.0)
    else:
        # a turn-rate change below the 0.02 rad/s threshold never fires S4/S5
        assert np.all(res.state == T.TurnState.STRAIGHT)
        assert np.all(res.q_gain == 1.0)


def test_gain_applies_to_the_next_scan_only_and_resets():
    """The gain decided at scan k is applied to the prediction of scan k+1 and is 1 on the
    scan after any scan where S5 did not fire (no compounding); re-running a plain EKF
    with exactly those gains reproduces the track."""
    tr = trajectory(
        [5000.0, 20000.0],
        0.5,
        150.0,
        [Leg.straight(100.0), Leg.turn(math.pi, 3 * DEG), Leg.straight(100.0)],
        dt=4.0,
    )
    m = observe(
        tr, None, ("range", "azimuth"), NoiseModel([30.0, 0.1 * DEG]), np.random.default_rng(2)
    )
    cfg = T.TurningConfig(q_nominal=0.5, gain_reference=0.005, delta_omega_threshold=0.01)
    res = T.TurningFilter(cfg, 2, SensorNoise(30.0, 0.1 * DEG)).run(m.t, m.z)
    fired = res.state != T.TurnState.STRAIGHT
    assert fired.any() and (res.q_gain > 1.0).any()  # the decision does fire in this turn
    np.testing.assert_array_equal(res.next_q_gain[~fired], 1.0)
    np.testing.assert_array_equal(res.q_gain[1:], res.next_q_gain[:-1])
    assert res.q_gain[0] == 1.0
    after_fire = np.flatnonzero(fired[:-1] & ~fired[1:]) + 2  # two scans after the last fire
    after_fire = after_fire[after_fire < m.t.size]
    assert after_fire.size and np.all(res.q_gain[after_fire] == 1.0)
    # replay with a plain CV-EKF and the recorded gains
    R = T.plot_covariance(30.0, 0.1 * DEG, 0.1 * DEG, 2)
    x, P = T.initial_state(m.z[0], R, cfg.sigma_velocity0)
    for k in range(1, m.t.size):
        dt = m.t[k] - m.t[k - 1]
        u = T.ekf_step(x, P, m.z[k], dt, res.q_gain[k] * cv_noise(dt, 0.5, 2), R)
        x, P = u.x, u.P
        np.testing.assert_allclose(x, res.x[k], rtol=1e-10, atol=1e-8)


def test_step_rejects_bad_plots_and_times():
    f = T.TurningFilter(T.TurningConfig(), 2)
    with pytest.raises(ValueError, match="2 finite values"):
        f.step(0.0, [1000.0, np.nan])
    f.step(0.0, [1000.0, 0.1])
    with pytest.raises(ValueError, match="times must increase"):
        f.step(0.0, [1000.0, 0.1])
    with pytest.raises(ValueError, match="dimension must be 2 or 3"):
        T.TurningFilter(T.TurningConfig(), 4)


def test_covariances_stay_symmetric_positive_definite():
    tr = _turn_scenario(3, 3 * DEG)
    m = observe(
        tr,
        None,
        ("range", "azimuth", "elevation"),
        NoiseModel([30.0, 0.1 * DEG, 0.1 * DEG]),
        np.random.default_rng(4),
    )
    cfg = T.TurningConfig(gain_reference=0.002, delta_omega_threshold=0.005)
    res = T.TurningFilter(cfg, 3).run(m.t, m.z)
    np.testing.assert_array_equal(res.P, np.swapaxes(res.P, -1, -2))
    assert np.all(np.linalg.eigvalsh(res.P) > 0)
    assert np.all(np.isfinite(res.turn_rate[1:]))


# ---------------------------------------------------------------------------
# CLI runner
# ---------------------------------------------------------------------------


def test_kalman_core_used_for_heading_update():
    """The heading update is the core's angular EKF update (same numbers)."""
    s, P = np.array([3.1, 0.01]), np.diag([0.01, 1e-4])
    est = Hd.heading_filter_step(s, P, -3.1, 0.004, 1.0)
    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    xp, Pp = kalman.predict(s, P, F, Hd.heading_filter_noise(1.0, 1e-6))
    u = kalman.extended_update(xp, Pp, [-3.1], [xp[0]], [[1.0, 0.0]], [[0.004]], [True])
    assert est.innovation == pytest.approx(float(u.y[0]))
    assert abs(est.innovation) < 0.2
    np.testing.assert_allclose(est.s[1], u.x[1])


def test_velocity_threshold_defaults_to_number_of_components():
    """S2: the heading filter starts only once d_t > N (N = 2 or 3 by default)."""
    for d in (2, 3):
        f = T.TurningFilter(T.TurningConfig(), d)
        assert f.filter.v_threshold == float(d)
    f = T.TurningFilter(T.TurningConfig(velocity_threshold=1e12), 2)
    tr = _turn_scenario(2, 3 * DEG)
    m = observe(
        tr, None, ("range", "azimuth"), NoiseModel([30.0, 0.1 * DEG]), np.random.default_rng(1)
    )
    res = f.run(m.t, m.z)
    assert np.all(np.isnan(res.turn_rate))  # never usable: heading filter never starts
    assert np.all(res.state == T.TurnState.STRAIGHT) and np.all(res.q_gain == 1.0)
    started = T.TurningFilter(T.TurningConfig(), 2).run(m.t, m.z)
    first = int(np.argmax(np.isfinite(started.turn_rate)))
    assert started.d_velocity[first] > 2.0
    assert np.all(~(started.d_velocity[:first] > 2.0))


@pytest.mark.parametrize("kw", [{"heading_cross_covariance": True}, {"heading_noise": "diagonal"}])
def test_heading_options_run_and_recover_the_turn_rate(kw):
    tr = _turn_scenario(2, 3 * DEG)
    m = observe(tr, None, ("range", "azimuth"), NoiseModel([0.0, 0.0]), np.random.default_rng(1))
    cfg = T.TurningConfig(q_nominal=1.0, **kw)
    res = T.TurningFilter(cfg, 2, SensorNoise(0.01, 1e-6)).run(m.t, m.z)
    np.testing.assert_allclose(res.turn_rate[m.t > 240.0], 3 * DEG, atol=0.01 * DEG)
