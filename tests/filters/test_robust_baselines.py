"""Tests of the baselines of the robust sonar tracker (EKF, clairvoyant, Huber, Student-t)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from seatrack.evaluate.metrics import position_error
from seatrack.filters.robust import SonarModel
from seatrack.filters.robust import robust_filter
from seatrack.filters.robust_baselines import HuberConfig
from seatrack.filters.robust_baselines import StudentTConfig
from seatrack.filters.robust_baselines import clairvoyant_filter
from seatrack.filters.robust_baselines import ekf_filter
from seatrack.filters.robust_baselines import huber_filter
from seatrack.filters.robust_baselines import huber_minimax_threshold
from seatrack.filters.robust_baselines import minimax_threshold_table
from seatrack.filters.robust_baselines import student_t_dof
from seatrack.filters.robust_baselines import student_t_filter
from seatrack.simulate.marine import MarineScenario
from seatrack.simulate.marine import SonarRuns
from seatrack.simulate.marine import simulate_runs


def _rmse(est, runs: SonarRuns, skip: int = 10) -> float:
    return float(np.sqrt(np.mean(position_error(est.x, runs.truth)[:, skip:] ** 2)))


@pytest.fixture(scope="module")
def clean() -> SonarRuns:
    return simulate_runs(MarineScenario(steps=80), 100, 0.0, np.random.default_rng(21))


@pytest.fixture(scope="module")
def dirty() -> SonarRuns:
    return simulate_runs(MarineScenario(steps=80), 100, 0.2, np.random.default_rng(22))


def test_batch_equals_run_by_run(dirty: SonarRuns) -> None:
    r = dirty
    batch = ekf_filter(r.t, r.z[:3], r.sensor[:3])
    for b in range(3):
        one = ekf_filter(r.t, r.z[b], r.sensor[b])
        np.testing.assert_allclose(one.x[0], batch.x[b], rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(one.P[0], batch.P[b], rtol=1e-12, atol=1e-9)


def test_ekf_matches_an_independent_numpy_ekf(dirty: SonarRuns) -> None:
    """Textbook EKF written out with numpy (standard-form update) on one run."""
    r = dirty
    m = SonarModel()
    est = ekf_filter(r.t, r.z[0], r.sensor[0], m)
    x, P = est.x[0, 0].copy(), est.P[0, 0].copy()
    dt = r.t[1] - r.t[0]
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    g = np.array([dt**2 / 2, dt])
    Q = np.kron(np.outer(g, g), np.eye(2)) * m.sigma_a**2
    Rm = np.diag([m.sigma_range**2, m.sigma_bearing**2])
    for n in range(1, 20):
        x = F @ x
        P = F @ P @ F.T + Q
        d = x[:2] - r.sensor[0, n]
        rho = np.hypot(*d)
        h = np.array([rho, np.arctan2(d[0], d[1])])
        H = np.zeros((2, 4))
        H[0, :2] = d / rho
        H[1, :2] = [d[1] / rho**2, -d[0] / rho**2]
        y = r.z[0, n] - h
        y[1] = (y[1] + np.pi) % (2 * np.pi) - np.pi
        S = H @ P @ H.T + Rm
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ y
        P = (np.eye(4) - K @ H) @ P
        np.testing.assert_allclose(est.x[0, n], x, rtol=1e-8, atol=1e-6)
        np.testing.assert_allclose(est.P[0, n], P, rtol=1e-6, atol=1e-8)


def test_clairvoyant_without_outliers_is_the_ekf(clean: SonarRuns) -> None:
    r = clean
    a = ekf_filter(r.t, r.z[:5], r.sensor[:5])
    c = clairvoyant_filter(r.t, r.z[:5], r.sensor[:5], r.outlier[:5], (10.0, 25.0))
    np.testing.assert_allclose(a.x, c.x, atol=1e-9)
    assert not r.outlier.any()


def test_clairvoyant_uses_the_true_outlier_variance_and_manoeuvre_noise() -> None:
    sc = MarineScenario(manoeuvre=True)
    r = simulate_runs(sc, 60, 0.2, np.random.default_rng(23))
    ekf = _rmse(ekf_filter(r.t, r.z, r.sensor), r)
    told_outliers = _rmse(clairvoyant_filter(r.t, r.z, r.sensor, r.outlier, sc.outlier_scale), r)
    sa = np.maximum(np.maximum(r.accel, np.roll(r.accel, 1, axis=1)), 0.02)
    told_all = _rmse(clairvoyant_filter(r.t, r.z, r.sensor, r.outlier, sc.outlier_scale, sa), r)
    # in a manoeuvre the lag dominates: knowing the outliers alone does not help much,
    # knowing the manoeuvre intensity too does
    assert told_all < 0.3 * told_outliers
    assert told_all < 0.3 * ekf


def test_huber_with_infinite_threshold_is_the_ekf(dirty: SonarRuns) -> None:
    r = dirty
    a = ekf_filter(r.t, r.z[:5], r.sensor[:5])
    h = huber_filter(r.t, r.z[:5], r.sensor[:5], config=HuberConfig(c=1e12))
    np.testing.assert_allclose(a.x, h.x, atol=1e-8)
    assert not h.outlier.any()


def test_student_t_with_huge_nu_is_the_ekf(dirty: SonarRuns) -> None:
    r = dirty
    a = ekf_filter(r.t, r.z[:5], r.sensor[:5])
    s = student_t_filter(r.t, r.z[:5], r.sensor[:5], config=StudentTConfig(nu=1e12))
    np.testing.assert_allclose(a.x, s.x, atol=1e-5)


def _last_estimate(filt, r: SonarRuns, jump: float) -> np.ndarray:
    """Last position estimate of run 0 with ``jump`` m added to its last range."""
    z = r.z[:1].copy()
    z[0, -1, 0] += jump
    return filt(r.t, z, r.sensor[:1]).x[0, -1, :2]


def test_influence_of_one_outlier(clean: SonarRuns) -> None:
    r = clean
    jumps = (0.0, 100.0, 1000.0, 1e6)

    def moves(filt) -> list[float]:
        est = [_last_estimate(filt, r, j) for j in jumps]
        # move caused by jumps 100 and 1000 relative to the clean plot, and relative to a
        # 1e6 m jump (which a redescending filter ignores completely)
        return [float(np.hypot(*(est[i] - est[0]))) for i in (1, 2)] + [
            float(np.hypot(*(est[i] - est[3]))) for i in (1, 2)
        ]

    ekf, hub, stt, rob = (
        moves(f) for f in (ekf_filter, huber_filter, student_t_filter, robust_filter)
    )
    assert ekf[1] == pytest.approx(10 * ekf[0], rel=1e-6)  # linear: unbounded influence
    assert hub[1] == pytest.approx(hub[0], rel=1e-3)  # Huber: bounded, saturates
    assert hub[0] < 0.05 * ekf[0]
    assert hub[2] < 1e-6  # ... at the same value for any size of outlier
    # redescending (Student-t, Ramazanov R): the influence of the outlier decays like 1/z
    for red in (stt, rob):
        assert red[3] == pytest.approx(0.1 * red[2], rel=0.05)
        assert red[2] < 0.05 * ekf[0]


def test_student_t_efficiency_without_outliers(clean: SonarRuns) -> None:
    r = clean
    ekf = _rmse(ekf_filter(r.t, r.z, r.sensor), r)
    heavy = _rmse(student_t_filter(r.t, r.z, r.sensor), r) / ekf
    light = _rmse(student_t_filter(r.t, r.z, r.sensor, config=StudentTConfig(nu=30.0)), r) / ekf
    assert heavy > light  # nu = 3 pays for its heavy tails at the Gaussian
    assert abs(light - 1.0) < 0.02


def test_huber_costs_little_without_outliers(clean: SonarRuns) -> None:
    r = clean
    ekf = _rmse(ekf_filter(r.t, r.z, r.sensor), r)
    assert abs(_rmse(huber_filter(r.t, r.z, r.sensor), r) / ekf - 1.0) < 0.04


def test_robust_baselines_beat_the_ekf_with_outliers(dirty: SonarRuns) -> None:
    r = dirty

    def med(est) -> float:
        return float(np.median(position_error(est.x, r.truth)[:, 10:]))

    ekf = ekf_filter(r.t, r.z, r.sensor)
    hub = huber_filter(r.t, r.z, r.sensor)
    stt = student_t_filter(r.t, r.z, r.sensor)
    assert med(hub) < 0.8 * med(ekf)
    assert med(stt) < 0.8 * med(ekf)
    clair = clairvoyant_filter(r.t, r.z, r.sensor, r.outlier, (10.0, 25.0))
    assert _rmse(clair, r) < 0.6 * _rmse(ekf, r)
    # and Ramazanov's adaptive-robust filter beats both generic robust filters here
    ada = _rmse(robust_filter(r.t, r.z, r.sensor, adaptive=True), r)
    assert ada < min(_rmse(hub, r), _rmse(stt, r))


@pytest.mark.parametrize(
    "filt",
    [
        ekf_filter,
        huber_filter,
        student_t_filter,
        lambda t, z, s: student_t_filter(t, z, s, config=StudentTConfig(per_component=False)),
        lambda t, z, s: ekf_filter(t, z, s, SonarModel(acceleration=True)),
    ],
)
def test_covariances_stay_symmetric_positive_definite(filt) -> None:
    r = simulate_runs(MarineScenario(manoeuvre=True, steps=100), 10, 0.3, np.random.default_rng(24))
    est = filt(r.t, r.z, r.sensor)
    np.testing.assert_allclose(est.P, np.swapaxes(est.P, -1, -2), atol=1e-9)
    assert np.linalg.eigvalsh(est.P).min() > 0


def test_bad_configs_raise() -> None:
    with pytest.raises(ValueError, match="c must"):
        HuberConfig(c=0.0)
    with pytest.raises(ValueError, match="nu must"):
        StudentTConfig(nu=-1.0)
    with pytest.raises(ValueError, match="iterations"):
        StudentTConfig(iterations=0)


def test_huber_minimax_threshold_solves_huber_equation():
    """Huber (1964): 2 phi(c) / c - 2 Phi(-c) = eps / (1 - eps); his table's values."""
    eps = np.array([1e-3, 0.01, 0.05, 0.1, 0.2, 0.4])
    c = huber_minimax_threshold(eps)
    lhs = 2 * stats.norm.pdf(c) / c - 2 * stats.norm.cdf(-c)
    np.testing.assert_allclose(lhs, eps / (1 - eps), rtol=1e-9)
    np.testing.assert_allclose(c[1:5], [1.945, 1.398, 1.140, 0.862], atol=1e-3)
    assert np.all(np.diff(c) < 0)
    assert huber_minimax_threshold(np.full((2, 3), 0.1)).shape == (2, 3)


def test_minimax_threshold_table_is_the_bisection():
    eps = np.exp(np.random.default_rng(3).uniform(np.log(1e-4), np.log(0.5), 5000))
    err = np.abs(minimax_threshold_table(eps) - huber_minimax_threshold(eps))
    assert err.max() < 2e-6
    assert minimax_threshold_table(np.full((2, 3), 0.1)).shape == (2, 3)
    ends = minimax_threshold_table([1e-4, 0.5])
    np.testing.assert_array_equal(minimax_threshold_table([1e-9, 0.9]), ends)  # clipped
    assert ends[0] > ends[1]


def test_student_t_dof_halves_the_weight_where_huber_does():
    """The Student-t weight (nu + 1) / (nu + u^2) and Huber's c / |u| are 1/2 at the same
    residual, the degrees of freedom never below the floor."""
    eps = np.array([1e-3, 0.01, 0.1, 0.2])
    nu = student_t_dof(eps, 0.5)
    c = minimax_threshold_table(eps)
    u = 2 * c  # Huber's weight is 1/2 there
    np.testing.assert_allclose((nu + 1) / (nu + u**2), 0.5, rtol=1e-12)
    assert student_t_dof(np.array([0.2]), 3.0)[0] == 3.0
    assert student_t_dof(np.array([1e-3]), 3.0)[0] == pytest.approx(25.73, abs=0.01)
