import numpy as np
import pytest
from filterpy.kalman import IMMEstimator
from filterpy.kalman import KalmanFilter

from seatrack import kalman
from seatrack.filters.imm import IMM
from seatrack.models import ConstantVelocity
from seatrack.models import CoordinatedTurn
from seatrack.models import Position
from seatrack.models import RangeBearing
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory

PI = np.array([[0.97, 0.03], [0.05, 0.95]])  # [i, j] = P(j | i); FilterPy's M is the same


def _filterpy_imm(models, x0, P0, R, dt):
    fs = []
    for m in models:
        kf = KalmanFilter(4, 2)
        kf.F = m.transition(x0, dt)[1]
        kf.Q = m.noise(dt)
        kf.H = Position(n=4).matrix()
        kf.R = R.copy()
        kf.x = x0.copy()
        kf.P = P0.copy()
        fs.append(kf)
    return IMMEstimator(fs, np.array([0.5, 0.5]), PI)


@pytest.mark.parametrize("seed", range(4))
def test_matches_filterpy_imm_two_cv_models(seed):
    rng = np.random.default_rng(seed)
    dt = 2.0
    models = [ConstantVelocity(q=0.01), ConstantVelocity(q=4.0)]
    R = np.diag([30.0, 20.0])
    x0 = np.array([0.0, 0.0, 10.0, 5.0])
    P0 = np.diag([100.0, 100.0, 25.0, 25.0])
    imm = IMM(models, PI, Position(n=4))
    st = imm.initial_state(x0, P0)
    fimm = _filterpy_imm(models, x0, P0, R, dt)
    tr = trajectory(
        [0, 0], 1.1, 11.0, [Leg.straight(60), Leg.turn(2.0, 0.1), Leg.straight(60)], dt=dt
    )
    for k in range(1, len(tr.t)):
        z = tr.pos[k, :2] + rng.normal(size=2) * 5
        r = imm.step(st, z, dt, R)
        st = r.state
        fimm.predict()
        fimm.update(z)
        np.testing.assert_allclose(r.x, fimm.x, rtol=1e-9, atol=1e-8)
        np.testing.assert_allclose(r.P, fimm.P, rtol=1e-9, atol=1e-8)
        np.testing.assert_allclose(st.mu, fimm.mu, rtol=1e-9, atol=1e-12)
        for j in range(2):
            np.testing.assert_allclose(st.X[j], fimm.filters[j].x, rtol=1e-9, atol=1e-8)


def test_single_model_imm_is_the_kalman_filter():
    rng = np.random.default_rng(0)
    m = ConstantVelocity(q=0.5)
    imm = IMM([m], [[1.0]], Position(n=4))
    x0, P0 = np.array([0.0, 0, 1, 1]), np.eye(4) * 10
    st = imm.initial_state(x0, P0)
    x, P = x0, P0
    R = np.eye(2)
    for _ in range(20):
        z = rng.normal(size=2)
        r = imm.step(st, z, 1.0, R)
        st = r.state
        F = m.transition(x, 1.0)[1]
        x, P = kalman.predict(x, P, F, m.noise(1.0))
        u = kalman.update(x, P, z, Position(n=4).matrix(), R)
        x, P = u.x, u.P
        np.testing.assert_allclose(r.x, x, atol=1e-10)
        np.testing.assert_allclose(r.P, P, atol=1e-10)
        assert r.log_likelihood == pytest.approx(u.log_likelihood)


def test_unequal_state_sizes_mix_by_name():
    cv, ct = ConstantVelocity(q=0.1), CoordinatedTurn(q=0.1, q_omega=1e-4)
    imm = IMM([cv, ct], PI, [RangeBearing(n=4), RangeBearing(n=5)])
    assert imm.union_names == ("x", "y", "vx", "vy", "w")
    assert imm.output_names == ("x", "y", "vx", "vy")
    st = imm.initial_state(
        np.array([1000.0, 2000, 5, 0]), np.eye(4) * 100, extra={"w": (0.02, 1e-4)}
    )
    # CV has no turn rate: mixing into CT takes w from CT's own estimate
    pred = imm.predict(st, 1.0)
    xct, Pct = imm.model_state(pred, 1)
    assert xct.shape == (5,) and Pct.shape == (5, 5)
    assert xct[4] == pytest.approx(0.02)
    assert Pct[4, 4] == pytest.approx(1e-4 + 1e-4 * 1.0)  # own variance + q_omega * dt
    xcv, Pcv = imm.model_state(pred, 0)
    assert xcv.shape == (4,)
    assert np.all(np.linalg.eigvalsh(Pct) > 0)


@pytest.mark.parametrize("batch", [(), (7,)])
def test_shared_measurement_update_is_the_per_model_update(batch):
    """CV, CT and an agile CV with range bearing and range rate: the one batched extended
    update over the model axis (padded layout) equals the model-by-model update."""
    from seatrack.models import RangeRate
    from seatrack.models import Stacked

    def meas(n):
        return Stacked([RangeBearing(n=n), RangeRate(n=n, pos=(0, 1), vel=(2, 3))])

    models = [
        ConstantVelocity(q=0.1),
        CoordinatedTurn(q=10.0, q_omega=1e-3),
        ConstantVelocity(q=300.0),
    ]
    PI3 = np.full((3, 3), 0.02) + np.eye(3) * 0.94
    fused = IMM(models, PI3, [meas(4), meas(5), meas(4)])
    loop = IMM(models, PI3, [meas(4), meas(5), meas(4)])
    loop._shared = None  # the model-by-model path
    assert fused._shared is not None
    rng = np.random.default_rng(3)
    x0 = np.array([3000.0, 4000.0, -150.0, 80.0])
    st = fused.initial_state(
        np.broadcast_to(x0, batch + (4,)),
        np.broadcast_to(np.diag([1e4, 1e4, 400, 400.0]), batch + (4, 4)),
        extra={"w": (0.0, 0.01)},
    )
    for _ in range(4):
        pred = fused.predict(st, 2.0)
        z = np.stack(
            [
                np.hypot(*x0[:2]) + rng.normal(0, 20, batch),
                np.arctan2(x0[0], x0[1]) + rng.normal(0, 0.004, batch),
                rng.normal(-20, 5, batch),
            ],
            -1,
        )
        R = np.broadcast_to(np.diag([400.0, 0.004**2, 1.0]), batch + (3, 3))
        sensor = np.broadcast_to(np.array([10.0, 20.0, 0.5, -0.5]), batch + (4,))
        a = fused.update(pred, z, R, sensor)
        b = loop.update(pred, z, R, sensor)
        for u, v in zip(
            (a.x, a.P, a.log_likelihood, a.model_log_likelihood, a.nis, a.state.mu),
            (b.x, b.P, b.log_likelihood, b.model_log_likelihood, b.nis, b.state.mu),
            strict=True,
        ):
            np.testing.assert_allclose(u, v, rtol=1e-12, atol=1e-12)
        for j, n in enumerate((4, 5, 4)):  # each model's own layout
            np.testing.assert_allclose(a.state.X[..., j, :n], b.state.X[..., j, :n], rtol=1e-12)
        st = a.state


def test_cv_ct_imm_tracks_turn_better_than_cv_and_is_consistent():
    dt = 2.0
    speed = 15.0
    tr = trajectory(
        [8000.0, 3000.0],
        np.radians(300.0),
        speed,
        [Leg.straight(120), Leg.turn(np.radians(180), np.radians(3.0)), Leg.straight(120)],
        dt=dt,
    )
    sig = np.array([15.0, np.radians(0.4)])
    R = np.diag(sig**2)
    runs = 40
    err_imm, err_cv, nees = [], [], []
    for seed in range(runs):
        rng = np.random.default_rng(seed)
        meas = observe(tr, None, ["range", "azimuth"], NoiseModel(sig), rng)
        imm = IMM(
            [ConstantVelocity(q=0.01), CoordinatedTurn(q=0.01, q_omega=1e-5)],
            PI,
            [RangeBearing(n=4), RangeBearing(n=5)],
        )
        x0 = np.concatenate([tr.pos[0, :2], tr.vel[0, :2]])
        P0 = np.diag([400.0, 400, 25, 25])
        st = imm.initial_state(x0, P0, extra={"w": (0.0, np.radians(4) ** 2)})
        cv = ConstantVelocity(q=0.01)
        x, P = x0.copy(), P0.copy()
        for k in range(1, len(tr.t)):
            r = imm.step(st, meas.z[k], dt, R)
            st = r.state
            F = cv.transition(x, dt)[1]
            x, P = kalman.predict(x, P, F, cv.noise(dt))
            m = RangeBearing(n=4)
            u = kalman.extended_update(x, P, meas.z[k], m.h(x), m.jacobian(x), R, m.angular)
            x, P = u.x, u.P
            truth = np.concatenate([tr.pos[k, :2], tr.vel[k, :2]])
            err_imm.append(np.linalg.norm(r.x[:2] - truth[:2]))
            err_cv.append(np.linalg.norm(x[:2] - truth[:2]))
            e = r.x - truth
            nees.append(e @ np.linalg.solve(r.P, e))
            assert np.isclose(st.mu.sum(), 1.0)
    rmse_imm = np.sqrt(np.mean(np.square(err_imm)))
    rmse_cv = np.sqrt(np.mean(np.square(err_cv)))
    assert rmse_imm < 0.7 * rmse_cv
    # IMM covariance is roughly honest through the turn (4 dof; loose two-sided sanity band)
    assert 2.0 < np.mean(nees) < 8.0


def test_batch_imm_equals_single_and_survives_underflow():
    models = [ConstantVelocity(q=0.01), ConstantVelocity(q=4.0)]
    imm = IMM(models, PI, Position(n=4))
    x0 = np.array([[0.0, 0, 1, 1], [10.0, 5, -1, 0]])
    st = imm.initial_state(x0, np.eye(4) * 10)
    z = np.array([[1.0, 2.0], [1e9, -1e9]])  # second track: likelihoods underflow
    r = imm.step(st, z, 1.0, np.eye(2))
    assert np.all(np.isfinite(r.state.mu)) and np.allclose(r.state.mu.sum(-1), 1.0)
    s0 = imm.initial_state(x0[0], np.eye(4) * 10)
    r0 = imm.step(s0, z[0], 1.0, np.eye(2))
    np.testing.assert_allclose(r.x[0], r0.x, rtol=1e-12)
    np.testing.assert_allclose(r.state.mu[0], r0.state.mu, rtol=1e-12)


def test_bad_transition_rejected():
    with pytest.raises(ValueError, match="summing to 1"):
        IMM([ConstantVelocity(), ConstantVelocity()], [[0.5, 0.4], [0.5, 0.5]], Position(n=4))
    with pytest.raises(ValueError, match="2x2"):
        IMM([ConstantVelocity(), ConstantVelocity()], [[1.0]], Position(n=4))


# ---------------------------------------------------------------------------
# FilterIMM: any filters honouring the contract as models
# ---------------------------------------------------------------------------
def _turn_plots(seed: int = 0):
    import math

    from seatrack.filters.base import Plots

    tr = trajectory(
        [6000.0, 9000.0], 2.0, 15.0,
        [Leg.straight(120), Leg.turn(math.pi / 2, math.radians(3)), Leg.straight(120)], dt=2.0,
    )  # fmt: skip
    m = observe(
        tr, None, ["range", "azimuth"], NoiseModel([10.0, 0.002]), np.random.default_rng(seed)
    )
    n = tr.t.size
    plots = Plots(tr.t, m.z[:, 0], m.z[:, 1], track=np.full(n, "A"))
    return tr, plots


def _run(flt, plots, speed=30.0):
    from seatrack.filters.base import SensorNoise
    from seatrack.filters.base import plot_gaussian
    from seatrack.filters.driver import run_tracks

    sensor = SensorNoise(10.0, 0.002)
    return run_tracks(
        flt, plots, np.zeros(len(plots), np.int64), lambda p: plot_gaussian(p, sensor, speed)
    )


def test_filter_imm_of_two_identical_filters_is_the_filter():
    """Mixing two copies of one filter must give that filter exactly."""
    from seatrack.filters.base import SensorNoise
    from seatrack.filters.ekf import EKF
    from seatrack.filters.ekf import EKFConfig
    from seatrack.filters.imm import FilterIMM

    _, plots = _turn_plots()
    ekf = EKF(EKFConfig(q=0.05), SensorNoise(10.0, 0.002))
    one = _run(ekf, plots)
    two = _run(FilterIMM([ekf, ekf], PI), plots)
    for c in ("x_m", "y_m", "vx_mps", "std_x_m", "std_y_m"):
        np.testing.assert_allclose(two[c], one[c], rtol=1e-9, atol=1e-9, err_msg=c)
    # equal likelihoods: the model probabilities follow the Markov chain alone
    mu = np.array([0.5, 0.5])
    for k in range(1, len(plots)):
        mu = mu @ PI
        np.testing.assert_allclose(two["p_m0"][k], mu[0], rtol=1e-9)


def test_filter_imm_of_turning_filter_and_cv_ekf():
    """Issue 14: an IMM whose models are the turning filter and a CV EKF."""
    from seatrack.filters.base import SensorNoise
    from seatrack.filters.ekf import EKF
    from seatrack.filters.ekf import EKFConfig
    from seatrack.filters.imm import FilterIMM
    from seatrack.filters.turning import Turning
    from seatrack.filters.turning import TurningConfig

    tr, plots = _turn_plots(1)
    sensor = SensorNoise(10.0, 0.002)
    turning = Turning(TurningConfig(q_nominal=0.05), sensor)
    cv = EKF(EKFConfig(q=0.01), sensor)
    imm = FilterIMM([turning, cv], PI, names=("turning", "cv"))
    out = _run(imm, plots)
    assert out["status"][0] == "initiated" and (out["status"][1:] == "updated").all()
    for c in ("x_m", "y_m", "vx_mps", "vy_mps", "std_x_m", "nis"):
        assert np.isfinite(out[c][1:]).all(), c
    np.testing.assert_allclose(out["p_turning"] + out["p_cv"], 1.0)
    err = np.hypot(out["x_m"] - tr.pos[:, 0], out["y_m"] - tr.pos[:, 1])
    late = slice(20, None)
    # better than either model alone would not be guaranteed; it must track (within the
    # plot noise) and weight the turning model up in the turn
    alone = _run(cv, plots)
    err_cv = np.hypot(alone["x_m"] - tr.pos[:, 0], alone["y_m"] - tr.pos[:, 1])
    assert np.sqrt(np.mean(err[late] ** 2)) < np.sqrt(np.mean(err_cv[late] ** 2))
    turn = (tr.t > 150) & (tr.t < 260)
    assert out["p_turning"][turn].mean() > out["p_turning"][tr.t < 100][10:].mean()


def test_markov_predict_core_is_transition_transpose_times_probabilities():
    from seatrack.filters.imm import markov_predict_core

    PI = np.array([[0.9, 0.1], [0.3, 0.7]])
    mu = np.array([0.25, 0.75])
    out = np.empty(2)
    markov_predict_core(PI, mu, out)
    np.testing.assert_allclose(out, PI.T @ mu, rtol=1e-15)
    markov_predict_core(PI.T.T, mu, out)  # any layout
    assert out.sum() == pytest.approx(1.0)
