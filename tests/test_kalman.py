"""The Kalman core against FilterPy, batch == single, Joseph-form PD, error handling."""

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter
from filterpy.kalman import KalmanFilter

from seatrack import kalman
from seatrack.models import RangeBearing


def _random_system(rng, n, m):
    F = np.eye(n) + 0.1 * rng.normal(size=(n, n))
    A = rng.normal(size=(n, n))
    Q = A @ A.T * 0.01 + 1e-3 * np.eye(n)
    H = rng.normal(size=(m, n))
    B = rng.normal(size=(m, m))
    R = B @ B.T + 0.1 * np.eye(m)
    C = rng.normal(size=(n, n))
    P0 = C @ C.T + np.eye(n)
    return F, Q, H, R, rng.normal(size=n), P0


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("n,m", [(4, 2), (6, 3), (2, 1), (5, 4)])
def test_matches_filterpy_kalman_filter(seed, n, m):
    rng = np.random.default_rng(seed)
    F, Q, H, R, x0, P0 = _random_system(rng, n, m)
    kf = KalmanFilter(dim_x=n, dim_z=m)
    kf.F, kf.Q, kf.H, kf.R, kf.x, kf.P = F, Q, H, R, x0.copy(), P0.copy()
    x, P = x0.copy(), P0.copy()
    for _ in range(25):
        z = rng.normal(size=m)
        kf.predict()
        kf.update(z)
        x, P = kalman.predict(x, P, F, Q)
        res = kalman.update(x, P, z, H, R)
        x, P = res.x, res.P
        np.testing.assert_allclose(x, kf.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(P, kf.P, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.y, kf.y, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.S, kf.S, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.K, kf.K, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.log_likelihood, kf.log_likelihood, rtol=1e-9)
        np.testing.assert_allclose(res.nis, kf.mahalanobis**2, rtol=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_matches_filterpy_ekf_range_bearing(seed):
    rng = np.random.default_rng(seed)
    model = RangeBearing(n=4)
    F = np.eye(4)
    F[0, 2] = F[1, 3] = 2.0
    Q = np.diag([1.0, 1.0, 0.1, 0.1])
    R = np.diag([25.0, np.radians(0.5) ** 2])
    x0 = np.array([3000.0, -200.0, -5.0, 12.0]) + rng.normal(size=4)
    P0 = np.diag([400.0, 400.0, 25.0, 25.0])
    ekf = ExtendedKalmanFilter(dim_x=4, dim_z=2)
    ekf.x, ekf.P, ekf.F, ekf.Q, ekf.R = x0.copy(), P0.copy(), F, Q, R
    x, P = x0.copy(), P0.copy()
    truth = x0.copy()

    def residual(a, b):  # angle-aware residual for FilterPy
        d = a - b
        d[1] = (d[1] + np.pi) % (2 * np.pi) - np.pi
        return d

    for _ in range(30):
        truth = F @ truth
        z = model.h(truth) + rng.normal(size=2) * np.sqrt(np.diag(R))
        z[1] %= 2 * np.pi
        ekf.predict()
        ekf.update(z, lambda s: model.jacobian(s), lambda s: model.h(s), residual=residual)
        x, P = kalman.predict(x, P, F, Q)
        res = kalman.extended_update(x, P, z, model.h(x), model.jacobian(x), R, model.angular)
        x, P = res.x, res.P
        np.testing.assert_allclose(x, ekf.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(P, ekf.P, rtol=1e-9, atol=1e-9)


def test_angle_innovation_wraps_across_north():
    x = np.array([0.0, 1000.0, 0.0, 0.0])
    P = np.eye(4) * 100.0
    model = RangeBearing(n=4)
    z = np.array([1000.0, np.radians(359.0)])
    x_left = x.copy()
    x_left[:2] = 1000 * np.array([np.sin(np.radians(1.0)), np.cos(np.radians(1.0))])
    res = kalman.extended_update(
        x_left, P, z, model.h(x_left), model.jacobian(x_left), np.diag([1, 1e-6]), model.angular
    )
    assert res.y[1] == pytest.approx(np.radians(-2.0), abs=1e-9)
    assert res.x[0] < x_left[0]  # pulled west, not swung round through 358 degrees


def test_batch_equals_single_same_code_path():
    rng = np.random.default_rng(3)
    F, Q, H, R, x0, P0 = _random_system(rng, 4, 2)
    B = 50
    xb = x0 + rng.normal(size=(B, 4))
    Pb = np.broadcast_to(P0, (B, 4, 4)).copy()
    zb = rng.normal(size=(B, 2))
    xp, Pp = kalman.predict(xb, Pb, F, Q)
    rb = kalman.update(xp, Pp, zb, H, R)
    for i in (0, 17, 49):
        xs, Ps = kalman.predict(xb[i], Pb[i], F, Q)
        rs = kalman.update(xs, Ps, zb[i], H, R)
        np.testing.assert_array_equal(rb.x[i], rs.x)
        np.testing.assert_array_equal(rb.P[i], rs.P)
        assert rb.nis[i] == rs.nis and rb.log_likelihood[i] == rs.log_likelihood
    # two leading dimensions, and broadcasting a per-track F
    x2, P2 = kalman.predict(
        xb.reshape(5, 10, 4), Pb.reshape(5, 10, 4, 4), np.broadcast_to(F, (10, 4, 4)), Q
    )
    np.testing.assert_allclose(x2.reshape(B, 4), xp, rtol=1e-14)
    # lists are accepted (converted by the gufunc)
    xl, _ = kalman.predict(x0.tolist(), P0.tolist(), F.tolist(), Q.tolist())
    np.testing.assert_allclose(xl, F @ x0)


def test_joseph_form_keeps_covariance_spd_under_tiny_noise():
    rng = np.random.default_rng(1)
    F = np.eye(4)
    F[0, 2] = F[1, 3] = 1.0
    Q = np.eye(4) * 1e-12
    H = np.eye(2, 4)
    R = np.eye(2) * 1e-10
    x, P = np.zeros(4), np.eye(4) * 1e6
    for _ in range(500):
        x, P = kalman.predict(x, P, F, Q)
        r = kalman.update(x, P, rng.normal(size=2) * 1e-5, H, R)
        x, P = r.x, r.P
        np.testing.assert_array_equal(P, P.T)
        assert np.linalg.eigvalsh(P).min() > 0


def test_non_pd_innovation_covariance_raises():
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        kalman.update(
            np.zeros(2), np.eye(2), np.zeros(1), np.array([[1.0, 0.0]]), np.array([[-5.0]])
        )
    with pytest.raises(np.linalg.LinAlgError, match="batch element"):
        kalman.update(
            np.zeros((3, 2)),
            np.eye(2),
            np.zeros((3, 1)),
            np.array([[1.0, 0.0]]),
            np.array([[[1.0]], [[-5.0]], [[1.0]]]),
        )


def test_nis_log_likelihood_helper_matches_update():
    rng = np.random.default_rng(4)
    F, Q, H, R, x0, P0 = _random_system(rng, 4, 2)
    z = rng.normal(size=2)
    r = kalman.update(x0, P0, z, H, R)
    nis, ll = kalman.nis_log_likelihood(r.y, r.S)
    assert nis == pytest.approx(r.nis, rel=1e-12)
    assert ll == pytest.approx(r.log_likelihood, rel=1e-12)


def test_log_likelihood_finite_for_huge_innovation():
    r = kalman.update(np.zeros(2), np.eye(2), np.array([1e8]), np.array([[1.0, 0.0]]), np.eye(1))
    assert np.isfinite(r.log_likelihood) and r.log_likelihood < -1e15


def test_matmul_cores_match_numpy_and_sym_matmul_is_exactly_symmetric():
    rng = np.random.default_rng(3)
    A, B = rng.normal(size=(4, 3)), rng.normal(size=(3, 5))
    out = np.empty((4, 5))
    kalman.matmul_core(A, B, out)
    np.testing.assert_allclose(out, A @ B, rtol=1e-14, atol=1e-14)
    C = rng.normal(size=(4, 4))
    S = np.empty((4, 4))
    kalman.sym_matmul_core(A, A.T, C, S)
    np.testing.assert_allclose(S, A @ A.T + 0.5 * (C + C.T), rtol=1e-13, atol=1e-13)
    assert np.array_equal(S, S.T)
    before = S.copy()
    kalman.sym_matmul_core(A, A.T, S, S)  # in place: S += A A^T
    np.testing.assert_allclose(S, before + A @ A.T, rtol=1e-13, atol=1e-13)
    assert np.array_equal(S, S.T)
