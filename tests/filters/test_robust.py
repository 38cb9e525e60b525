"""Tests of Ramazanov's robust (R) and adaptive-robust (A) beam-frame filter."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st

from seatrack.evaluate.metrics import position_error
from seatrack.filters.robust import BeamState
from seatrack.filters.robust import RobustConfig
from seatrack.filters.robust import SonarModel
from seatrack.filters.robust import axis_noise
from seatrack.filters.robust import axis_transition
from seatrack.filters.robust import beam_innovations
from seatrack.filters.robust import beam_to_cartesian_cov
from seatrack.filters.robust import cartesian_to_beam_state
from seatrack.filters.robust import initial_state
from seatrack.filters.robust import per_axis_to_flat
from seatrack.filters.robust import robust_filter
from seatrack.filters.robust import robust_step
from seatrack.filters.robust import robust_variance
from seatrack.filters.robust import rotate_blocks
from seatrack.filters.robust_baselines import ekf_filter
from seatrack.geometry import bearing
from seatrack.geometry import polar_to_cart
from seatrack.geometry import rotation_to_beam
from seatrack.models.motion import ca_transition
from seatrack.models.motion import cv_noise_discrete
from seatrack.models.motion import cv_transition
from seatrack.simulate.marine import MarineScenario
from seatrack.simulate.marine import simulate_runs

angles = st.floats(-10.0, 10.0, allow_nan=False)


# ---------------------------------------------------------------------------
# beam frame
# ---------------------------------------------------------------------------
@given(psi=angles, e=st.floats(-1e4, 1e4), n=st.floats(-1e4, 1e4))
def test_beam_rotation_round_trips(psi: float, e: float, n: float) -> None:
    R = rotation_to_beam(psi)
    np.testing.assert_allclose(R.T @ R, np.eye(2), atol=1e-12)
    v = np.array([e, n])
    np.testing.assert_allclose(R.T @ (R @ v), v, atol=1e-9)
    X = np.array([[e, 1.0], [n, -2.0]])  # rows East, North; columns position, velocity
    Xb = cartesian_to_beam_state(X, psi)
    np.testing.assert_allclose(np.einsum("ca,ci->ai", R, Xb), X, atol=1e-9)


@given(psi=st.floats(0.0, 2 * np.pi), r=st.floats(10.0, 1e4))
def test_predicted_target_sits_on_the_beam(psi: float, r: float) -> None:
    """In the beam frame of the predicted bearing the target is at (R', 0)."""
    sensor = np.array([120.0, -40.0])
    pos = sensor + polar_to_cart(r, psi)
    b, r_pred, innov = beam_innovations(pos, sensor, r + 3.0, psi + 0.01)
    xb = cartesian_to_beam_state(np.stack([pos - sensor, [0.0, 0.0]], -1), b)[:, 0]
    np.testing.assert_allclose(xb, [r, 0.0], atol=1e-7 * r)
    assert r_pred == pytest.approx(r)
    np.testing.assert_allclose(innov, [3.0, 0.01 * r], rtol=1e-9)


@settings(max_examples=30)
@given(psi=angles)
def test_block_covariance_round_trips(psi: float) -> None:
    rng = np.random.default_rng(3)
    A = rng.normal(size=(2, 3, 3))
    Pc = A @ np.swapaxes(A, -1, -2) + np.eye(3)
    C = beam_to_cartesian_cov(Pc, psi)  # (6, 6) in [x, y, vx, vy, ax, ay]
    R = rotation_to_beam(psi)
    Cb = np.einsum("ca,db,iajb->cidj", R, R, C.reshape(3, 2, 3, 2))
    np.testing.assert_allclose(Cb[0, :, 0], Pc[0], atol=1e-12)
    np.testing.assert_allclose(Cb[1, :, 1], Pc[1], atol=1e-12)
    np.testing.assert_allclose(Cb[0, :, 1], 0.0, atol=1e-12)
    assert np.trace(C) == pytest.approx(np.trace(Pc[0]) + np.trace(Pc[1]))


def test_rotate_blocks_keeps_trace_and_swaps_at_right_angle() -> None:
    Pc = np.stack([np.diag([4.0, 1.0]), np.diag([900.0, 2.0])])
    np.testing.assert_allclose(rotate_blocks(Pc, 0.0), Pc)
    np.testing.assert_allclose(rotate_blocks(Pc, np.pi / 2), Pc[::-1], atol=1e-12)
    r = rotate_blocks(Pc, 0.3)
    assert np.trace(r.sum(0)) == pytest.approx(np.trace(Pc.sum(0)))
    # and the re-blocked matrix is the diagonal block of the rotated block-diagonal one
    C = beam_to_cartesian_cov(Pc, 1.0)
    Cb = np.einsum(
        "ca,db,iajb->cidj", rotation_to_beam(1.3), rotation_to_beam(1.3), C.reshape(2, 2, 2, 2)
    )
    np.testing.assert_allclose(rotate_blocks(Pc, 0.3)[0], Cb[0, :, 0], atol=1e-9)
    np.testing.assert_allclose(rotate_blocks(Pc, 0.3)[1], Cb[1, :, 1], atol=1e-9)


def test_per_axis_model_matches_the_motion_module() -> None:
    dt = 2.5
    np.testing.assert_allclose(per_axis_to_flat(axis_transition(dt, 2)), cv_transition(dt))
    np.testing.assert_allclose(per_axis_to_flat(axis_transition(dt, 3)), ca_transition(dt))
    np.testing.assert_allclose(per_axis_to_flat(axis_noise(dt, 0.3, 2)), cv_noise_discrete(dt, 0.3))


# ---------------------------------------------------------------------------
# measurement channels
# ---------------------------------------------------------------------------
def _one_step(z1: np.ndarray, config: RobustConfig, model: SonarModel | None = None):
    """Init at a known plot, then one robust step with plot ``z1`` 2 s later."""
    m = model or SonarModel()
    z0 = np.array([[[920.0, np.deg2rad(40.0)]]])
    sensor = np.array([[50.0, -30.0]])
    X, Pc, psi = initial_state(z0, sensor, SonarModel(init_plots=1))
    state = BeamState(X, Pc, psi, np.zeros((1, 2, config.window)))
    new, info = robust_step(state, z1[None], sensor, 2.0, m, config, adaptive=False)
    return state, new, info


def test_eta_channel_variance_is_range_squared_sigma_squared_in_radians() -> None:
    m = SonarModel()
    cfg = RobustConfig(delta_range=1e12, delta_bearing=1e12)  # plain Kalman gain
    z1 = np.array([925.0, np.deg2rad(40.5)])
    state, new, info = _one_step(z1, cfg, m)
    # predicted position is the initial one (zero velocity): R' = 920 m
    r_pred = 920.0
    assert info.q0[0, 1] == pytest.approx(r_pred**2 * np.deg2rad(2.0) ** 2)
    assert info.q0[0, 0] == pytest.approx(1.5**2)
    assert info.innov[0, 1] == pytest.approx(r_pred * np.deg2rad(0.5))
    # the cross-range posterior variance is the scalar Kalman result with that variance
    p = info.P_pred[0, 1, 0, 0]
    q = r_pred**2 * np.deg2rad(2.0) ** 2
    assert new.Pc[0, 1, 0, 0] == pytest.approx(p * q / (p + q))
    # and one step of the beam-frame filter equals the Cartesian range/bearing EKF step
    t = np.array([0.0, 2.0])
    z = np.stack([np.array([920.0, np.deg2rad(40.0)]), z1])[None]
    sensor = np.array([[50.0, -30.0], [50.0, -30.0]])
    one = SonarModel(init_plots=1)
    rb = robust_filter(t, z, sensor, one, cfg)
    ek = ekf_filter(t, z, sensor, one)
    np.testing.assert_allclose(rb.x[0, 1], ek.x[0, 1], rtol=0, atol=1e-3)
    np.testing.assert_allclose(rb.P[0, 1], ek.P[0, 1], rtol=2e-3, atol=1e-6)


def test_robust_variance_is_the_huber_innovation_variance() -> None:
    z = np.array([0.5, 3.0, -40.0])
    hph, q0, delta = 2.0, 1.0, 3.84
    q, gamma = robust_variance(z, hph, q0, delta)
    np.testing.assert_allclose(hph + q, np.maximum(hph + q0, z**2 / delta))
    np.testing.assert_array_equal(gamma, [False, False, True])
    assert np.all(q >= q0)


@pytest.mark.parametrize("channel, jump", [(0, 5000.0), (1, np.deg2rad(60.0))])
def test_single_huge_outlier_moves_estimate_less_than_the_threshold_bound(
    channel: int, jump: float
) -> None:
    cfg = RobustConfig()
    clean = np.array([921.0, np.deg2rad(40.1)])
    bad = clean.copy()
    bad[channel] += jump
    state, new_bad, info = _one_step(bad, cfg)
    _, new_clean, _ = _one_step(clean, cfg)
    assert info.outlier[0, channel]
    P = info.P_pred[0, channel]
    s0 = P[0, 0] + info.q0[0, channel]
    d = cfg.delta[channel]
    z = abs(info.innov[0, channel])
    # beam-frame correction of this channel = rotated state change from the prediction
    Xp = state.X @ axis_transition(2.0, 2).T
    dXb = cartesian_to_beam_state(new_bad.X - Xp, new_bad.psi)[0, channel]
    # |K z| = |P[:, 0]| |z| / max(S0, z^2/Delta) <= |P[:, 0]| sqrt(Delta / S0)   (Huber bound)
    bound = np.abs(P[:, 0]) * np.sqrt(d / s0)
    assert np.all(np.abs(dXb) <= bound * (1 + 1e-9))
    # redescending: for a huge outlier the move is |P[:, 0]| Delta / |z|, far below the bound
    np.testing.assert_allclose(np.abs(dXb), np.abs(P[:, 0]) * d / z, rtol=1e-9)
    # and the position moves by less than the bound away from where the clean plot puts it
    shift = np.hypot(*(new_bad.X[0, :, 0] - new_clean.X[0, :, 0]))
    clean_move = np.hypot(*(new_clean.X[0, :, 0] - Xp[0, :, 0]))
    assert shift <= bound[0] + clean_move
    # the plain Kalman gain would have moved it by P00 z / S0: more by the factor z^2/(Delta S0)
    plain = P[0, 0] * z / s0
    assert abs(dXb[0]) / plain == pytest.approx(d * s0 / z**2)
    assert abs(dXb[0]) < 0.05 * plain


def test_a_capped_single_outlier_does_not_trigger_adaptation() -> None:
    """Noise-free plots (J ~ 0) plus one huge outlier: capped, J_sum <= Delta < Delta_Sigma."""
    runs = simulate_runs(MarineScenario(steps=60), 5, 0.0, np.random.default_rng(11))
    d = runs.truth[..., :2] - runs.sensor
    z = np.stack([np.hypot(d[..., 0], d[..., 1]), bearing(d[..., 0], d[..., 1])], -1)
    z[:, 40, 0] += 3000.0  # one huge range outlier in every run
    capped = robust_filter(runs.t, z, runs.sensor, config=RobustConfig(), adaptive=True)
    assert capped.outlier[:, 40, 0].all()
    assert not capped.adapting[:, 30:].any()
    uncapped = robust_filter(
        runs.t, z, runs.sensor, config=RobustConfig(cap_j=False), adaptive=True
    )
    # without the cap one outlier is enough, for the n = 3 plots it stays in the window
    assert uncapped.adapting[:, 40:43, 0].all()
    assert not uncapped.adapting[:, 30:40].any()


# ---------------------------------------------------------------------------
# Monte-Carlo behaviour (seeded)
# ---------------------------------------------------------------------------
def _rmse(est, runs, skip: int = 10) -> float:
    return float(np.sqrt(np.mean(position_error(est.x, runs.truth)[:, skip:] ** 2)))


@pytest.fixture(scope="module")
def clean_runs():
    return simulate_runs(MarineScenario(steps=80), 100, 0.0, np.random.default_rng(5))


def test_without_outliers_or_manoeuvre_r_and_a_agree_with_the_ekf(clean_runs) -> None:
    r = clean_runs
    ekf = _rmse(ekf_filter(r.t, r.z, r.sensor), r)
    for adaptive in (False, True):
        rob = _rmse(robust_filter(r.t, r.z, r.sensor, adaptive=adaptive), r)
        assert abs(rob / ekf - 1.0) < 0.04, (adaptive, rob, ekf)


def test_with_outliers_r_and_a_beat_the_ekf() -> None:
    r = simulate_runs(MarineScenario(steps=80), 100, 0.2, np.random.default_rng(6))
    ekf_est = ekf_filter(r.t, r.z, r.sensor)
    ekf = _rmse(ekf_est, r)
    ekf_median = float(np.median(position_error(ekf_est.x, r.truth)[:, 10:]))
    for adaptive in (False, True):
        est = robust_filter(r.t, r.z, r.sensor, adaptive=adaptive)
        # R has no way back once it has lost lock (a few runs), so its RMSE is not always
        # below the EKF's; its median error is. A recovers through its injected noise.
        assert np.median(position_error(est.x, r.truth)[:, 10:]) < 0.7 * ekf_median
        if adaptive:
            assert _rmse(est, r) < 0.65 * ekf
        # most anomalous bearings are caught, few nominal ones are flagged
        hit = est.outlier[:, 1:, 1][r.outlier[:, 1:, 1]].mean()
        false = est.outlier[:, 1:, 1][~r.outlier[:, 1:, 1]].mean()
        assert hit > 0.6 and false < 0.1


def test_a_adapts_during_the_manoeuvre_and_tracks_it_better_than_r() -> None:
    sc = MarineScenario(manoeuvre=True)
    r = simulate_runs(sc, 60, 0.0, np.random.default_rng(8))
    rob = robust_filter(r.t, r.z, r.sensor)
    ada = robust_filter(r.t, r.z, r.sensor, adaptive=True)
    turn = (r.t > sc.turn_start) & (r.t < sc.turn_start + sc.turn_angle / sc.turn_rate)
    before = (r.t > 20.0) & (r.t < sc.turn_start)
    assert ada.adapting[:, turn].any(-1).mean() > 5 * ada.adapting[:, before].any(-1).mean()
    assert not rob.adapting.any()
    assert _rmse(ada, r) < 0.7 * _rmse(rob, r)
    full = robust_filter(r.t, r.z, r.sensor, SonarModel(acceleration=True, sigma_a=0.01))
    assert _rmse(full, r) < 0.5 * _rmse(rob, r)


@pytest.mark.parametrize("adaptive", [False, True])
@pytest.mark.parametrize("acceleration", [False, True])
@pytest.mark.parametrize("rotate", [False, True])
def test_covariances_stay_symmetric_positive_definite(
    adaptive: bool, acceleration: bool, rotate: bool
) -> None:
    sc = MarineScenario(manoeuvre=True, steps=120)
    r = simulate_runs(sc, 10, 0.3, np.random.default_rng(9))
    est = robust_filter(
        r.t,
        r.z,
        r.sensor,
        SonarModel(acceleration=acceleration),
        RobustConfig(rotate_covariance=rotate),
        adaptive=adaptive,
    )
    P = est.P
    np.testing.assert_allclose(P, np.swapaxes(P, -1, -2), atol=1e-9)
    assert np.linalg.eigvalsh(P).min() > 0
    assert np.isfinite(est.x).all()


def test_missing_components_skip_their_channel() -> None:
    r = simulate_runs(MarineScenario(steps=30), 3, 0.0, np.random.default_rng(2))
    z = r.z.copy()
    z[:, 10, 1] = np.nan
    est = robust_filter(r.t, z, r.sensor)
    assert np.isfinite(est.x).all()
    assert not est.outlier[:, 10, 1].any()


def test_bad_inputs_raise_clear_errors() -> None:
    with pytest.raises(ValueError, match="window"):
        RobustConfig(window=0)
    with pytest.raises(ValueError, match="delta_range"):
        RobustConfig(delta_range=-1.0)
    with pytest.raises(ValueError, match="sigma_range"):
        SonarModel(sigma_range=0.0)
    with pytest.raises(ValueError, match="increasing"):
        robust_filter([0.0, 0.0], np.ones((2, 2)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="expected t"):
        robust_filter([0.0, 1.0], np.ones((2, 3)), np.zeros((2, 2)))


# ---------------------------------------------------------------------------
# seatrack track runners
# ---------------------------------------------------------------------------


def test_robust_gain_switch_of_algorithm_a() -> None:
    """[reading] robust_gain=False: A uses the nominal q0 in its gain, so it follows outliers."""
    runs = simulate_runs(MarineScenario(steps=40), 3, 0.0, np.random.default_rng(12))
    z = runs.z.copy()
    z[:, -1, 0] += 500.0

    def move(cfg: RobustConfig) -> np.ndarray:
        a = robust_filter(runs.t, z, runs.sensor, config=cfg, adaptive=True).x[:, -1, :2]
        b = robust_filter(runs.t, runs.z, runs.sensor, config=cfg, adaptive=True).x[:, -1, :2]
        return np.hypot(*(a - b).T)

    plain = move(RobustConfig(robust_gain=False))
    robust = move(RobustConfig())
    assert np.all(robust < 0.05 * plain)
