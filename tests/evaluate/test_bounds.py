"""Tests of seatrack.evaluate.bounds: batch Fisher CRB, linear PCRB (= Kalman covariance),
and the Tichavsky-Muravchik-Nehorai recursion for nonlinear measurements/dynamics."""

import numpy as np
import pytest

from seatrack import kalman
from seatrack.evaluate.bounds import crb_deterministic
from seatrack.evaluate.bounds import fisher_crb
from seatrack.evaluate.bounds import fisher_information
from seatrack.evaluate.bounds import pcrb
from seatrack.evaluate.bounds import pcrb_linear
from seatrack.information import SingularMatrixError
from seatrack.models.measurement import Bearing
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition


def test_fisher_crb_by_hand():
    J = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    W = np.array([1.0, 2.0, 4.0])
    # J^T W J = [[1 + 4, 4], [4, 2 + 4]] = [[5, 4], [4, 6]], det 14
    np.testing.assert_allclose(fisher_information(J, W), [[5.0, 4.0], [4.0, 6.0]])
    expected = np.array([[6.0, -4.0], [-4.0, 5.0]]) / 14.0
    np.testing.assert_allclose(fisher_crb(J, W), expected, rtol=1e-14)
    np.testing.assert_allclose(fisher_crb(J, np.diag(W)), expected, rtol=1e-14)
    np.testing.assert_allclose(fisher_crb(J, 2.0), np.linalg.inv(2.0 * J.T @ J), rtol=1e-14)


def test_fisher_crb_singular_is_a_clear_error():
    J = np.array([[1.0, 2.0], [2.0, 4.0], [3.0, 6.0]])  # rank 1
    with pytest.raises(np.linalg.LinAlgError, match="not observable"):
        fisher_crb(J, np.ones(3))
    with pytest.raises(ValueError, match="weight"):
        fisher_crb(np.eye(2), np.ones(3))


def _kalman_covariances(P0, Fs, Qs, Hs, Rs, measure_first):
    """Kalman covariances of steps 0..K; Hs/Rs indexed by step (length K + 1)."""
    x = np.zeros(P0.shape[0])
    P = P0.copy()
    out = []
    if measure_first and Hs[0] is not None:
        P = kalman.update(x, P, np.zeros(Hs[0].shape[0]), Hs[0], Rs[0]).P
    out.append(P)
    for k in range(len(Fs)):
        x, P = kalman.predict(x, P, Fs[k], Qs[k])
        H, R = Hs[k + 1], Rs[k + 1]
        if H is not None:
            P = kalman.update(x, P, np.zeros(H.shape[0]), H, R).P
        out.append(P)
    return np.stack(out)


@pytest.mark.parametrize("measure_first", [False, True])
def test_pcrb_linear_equals_kalman_covariance_constant(measure_first):
    dt, K = 2.0, 30
    F, Q = cv_transition(dt), cv_noise(dt, 0.3)
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    R = np.diag([25.0**2, 40.0**2])
    P0 = np.diag([1e4, 1e4, 100.0, 100.0])
    bound = pcrb_linear(P0, F, Q, H, R, n_steps=K, measure_first=measure_first)
    ref = _kalman_covariances(P0, [F] * K, [Q] * K, [H] * (K + 1), [R] * (K + 1), measure_first)
    assert bound.shape == (K + 1, 4, 4)
    np.testing.assert_allclose(bound, ref, rtol=1e-9, atol=1e-9)


def test_pcrb_linear_per_step_sequences_and_missed_measurements():
    rng = np.random.default_rng(5)
    K = 12
    dts = rng.uniform(0.5, 3.0, K)
    Fs = [cv_transition(d) for d in dts]
    Qs = [cv_noise(d, 0.7) for d in dts]
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    Hs = [None if k in (3, 4, 9) else H for k in range(K)]
    Rs = [np.diag(rng.uniform(10, 50, 2) ** 2) for _ in range(K)]
    P0 = np.diag([400.0, 400.0, 25.0, 25.0])
    bound = pcrb_linear(P0, Fs, Qs, Hs, Rs)
    ref = _kalman_covariances(P0, Fs, Qs, [None, *Hs], [None, *Rs], False)
    np.testing.assert_allclose(bound, ref, rtol=1e-9, atol=1e-9)
    # covariance grows across the missed measurements
    assert np.trace(bound[5]) > np.trace(bound[4]) > np.trace(bound[3])


def test_pcrb_linear_rejects_inconsistent_lengths():
    F = np.eye(2)
    with pytest.raises(ValueError, match="n_steps"):
        pcrb_linear(np.eye(2), F, np.eye(2), np.eye(2), np.eye(2))
    with pytest.raises(ValueError, match="different numbers of steps"):
        pcrb_linear(np.eye(2), [F] * 3, [F] * 4, np.eye(2), np.eye(2))


def _bearing_truth(K, dt, runs=1, seed=0, q=0.0):
    """Target CV truth (runs, K+1, 4), observer fixed at the origin."""
    rng = np.random.default_rng(seed)
    F = cv_transition(dt)
    Q = cv_noise(dt, q) if q > 0 else np.zeros((4, 4))
    x = np.tile([3000.0, 8000.0, -6.0, -2.0], (runs, 1))
    out = [x]
    L = np.linalg.cholesky(Q + 1e-300 * np.eye(4)) if q > 0 else np.zeros((4, 4))
    for _ in range(K):
        x = x @ F.T + rng.standard_normal((runs, 4)) @ L.T
        out.append(x)
    return np.stack(out, 1), F, Q


def test_pcrb_nonlinear_deterministic_equals_batch_fisher_crb():
    # Q = 0: the PCRB of x_K equals the batch CRB of x_0 (prior + all bearings) mapped by F^K.
    # Observer moves (known), so range is observable.
    K, dt, sigma = 40, 10.0, np.radians(1.0)
    X, F, Q = _bearing_truth(K, dt)
    obs = np.stack([np.array([-5.0 * k * dt, 3.0 * (k * dt) ** 1.0]) for k in range(K + 1)])
    model = Bearing(n=4, pos=(0, 1))
    R = np.array([[sigma**2]])
    P0 = np.diag([2000.0**2, 2000.0**2, 10.0**2, 10.0**2])

    def hjac(x, k):
        return model.jacobian(x, obs[k])

    bound = pcrb(P0, X, Q, hjac, R, transition_jacobian=F, measure_first=True)
    Fk = [np.linalg.matrix_power(F, k) for k in range(K + 1)]
    J = np.vstack([hjac(X[0, k], k) @ Fk[k] for k in range(K + 1)])
    info = np.linalg.inv(P0) + J.T @ J / sigma**2
    crb0 = np.linalg.inv(info)
    np.testing.assert_allclose(
        bound[0], np.linalg.inv(np.linalg.inv(P0) + J[:1].T @ J[:1] / sigma**2), rtol=1e-9
    )
    np.testing.assert_allclose(bound[K], Fk[K] @ crb0 @ Fk[K].T, rtol=1e-7)
    # the same CRB without the prior through fisher_crb plus the prior as pseudo-measurements
    Jp = np.vstack([J, np.eye(4)])
    Wp = np.concatenate([np.full(K + 1, 1 / sigma**2), 1 / np.diag(P0)])
    np.testing.assert_allclose(fisher_crb(Jp, Wp), crb0, rtol=1e-9)


def test_pcrb_nonlinear_dynamics_branch_matches_linear_branch():
    # with f linear, the general D11/D12/D22 recursion must equal the linear form
    K, dt = 25, 5.0
    X, F, Q = _bearing_truth(K, dt, runs=20, q=0.05)
    model = Bearing(n=4, pos=(0, 1))
    R = np.array([[np.radians(2.0) ** 2]])
    P0 = np.diag([1000.0**2, 1000.0**2, 5.0**2, 5.0**2])
    obs = np.zeros((K + 1, 2))
    obs[:, 0] = np.linspace(0.0, 2000.0, K + 1)

    def hjac(x, k):
        return model.jacobian(x, obs[k])

    lin = pcrb(P0, X, Q, hjac, R, transition_jacobian=F)
    gen = pcrb(P0, X, Q, hjac, R, transition_jacobian=lambda x, k: F)
    # Algebraically identical. Eq. (21) forms J_{k+1} as Q^-1 - D21 (J + D11)^-1 D12, a
    # difference of O(|Q^-1|) terms giving an information ~1e-4 |Q^-1| here, so ~4 digits
    # cancel and the bound covariance (entries spanning 1e-1..1e6) agrees to ~5e-9
    # norm-wise; the linear branch avoids Q^-1 altogether.
    rel = np.linalg.norm(gen - lin, axis=(1, 2)) / np.linalg.norm(lin, axis=(1, 2))
    assert rel.max() < 1e-7
    # a linear measurement gives back pcrb_linear
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    R2 = np.diag([30.0**2, 30.0**2])
    a = pcrb(P0, X, Q, lambda x, k: H, R2, transition_jacobian=F)
    b = pcrb_linear(P0, F, Q, H, R2, n_steps=K)
    np.testing.assert_allclose(a, b, rtol=1e-10)


def test_pcrb_expectation_is_average_over_runs():
    # the measurement information is averaged over truth samples
    K, dt = 5, 5.0
    X, F, Q = _bearing_truth(K, dt, runs=2, q=0.5, seed=3)
    model = Bearing(n=4, pos=(0, 1))
    R = np.array([[np.radians(1.0) ** 2]])
    P0 = np.eye(4) * 1e6
    hj = lambda x, k: model.jacobian(x, np.zeros(2))
    both = pcrb(P0, X, Q, hj, R, transition_jacobian=F)
    J0 = np.linalg.inv(P0)
    P1 = F @ np.linalg.inv(J0) @ F.T + Q
    info = sum(hj(X[r, 1], 1).T @ np.linalg.inv(R) @ hj(X[r, 1], 1) for r in range(2)) / 2
    np.testing.assert_allclose(both[1], np.linalg.inv(np.linalg.inv(P1) + info), rtol=1e-9)


def test_crb_deterministic_equals_batch_fisher_crb_per_step():
    # range-bearing radar on a CV target; the bound of x_k from plots 0..k must equal the
    # batch Fisher CRB with Jacobians H_i Phi(t_i - t_k)
    from seatrack.models.measurement import RangeBearing

    K, dt = 15, 3.0
    X, F, _ = _bearing_truth(K, dt)
    model = RangeBearing(n=4, pos=(0, 1))
    R = np.diag([20.0**2, np.radians(0.5) ** 2])
    Ri = np.linalg.inv(R)
    H = model.jacobian(X[0])  # (K+1, 2, 4), sensor at the origin
    info = np.einsum("kji,jl,klm->kim", H, Ri, H)
    bound = crb_deterministic(info, F)
    assert np.all(np.isnan(bound[0]))  # one plot: velocity unobservable
    for k in (1, 5, K):
        J = np.vstack([H[i] @ np.linalg.matrix_power(F, i - k) for i in range(k + 1)])
        W = np.tile(1 / np.diag(R), k + 1)
        np.testing.assert_allclose(bound[k], fisher_crb(J, W), rtol=1e-8)
    # more plots, smaller bound
    assert np.trace(bound[K][:2, :2]) < np.trace(bound[2][:2, :2])


def test_crb_deterministic_observability_does_not_depend_on_units():
    """The same information in metres and in kilometres (velocity in km/s): the same steps
    are observable. The old unscaled eigenvalue test mixed m^-2 and (m/s)^-2."""
    from seatrack.models.measurement import RangeBearing

    K, dt = 6, 3.0
    X, F, _ = _bearing_truth(K, dt)
    H = RangeBearing(n=4, pos=(0, 1)).jacobian(X[0])
    Ri = np.linalg.inv(np.diag([20.0**2, np.radians(0.5) ** 2]))
    info = np.einsum("kji,jl,klm->kim", H, Ri, H)
    T = np.diag([1e3, 1e3, 1e3, 1e3])  # x_m = T x_km: information in km is T I T
    km = crb_deterministic(T @ info @ T, F)
    m = crb_deterministic(info, F)
    assert np.array_equal(np.isnan(km[:, 0, 0]), np.isnan(m[:, 0, 0]))
    np.testing.assert_allclose(km[1:] * 1e6, m[1:], rtol=1e-8)


def test_singular_prior_and_measurement_noise_are_named_errors():
    F, Q = cv_transition(1.0), cv_noise(1.0, 0.1)
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    R = np.eye(2)
    with pytest.raises(SingularMatrixError, match="prior covariance P0"):
        pcrb_linear(np.diag([1.0, 1.0, 1.0, 0.0]), F, Q, H, R, n_steps=3)
    with pytest.raises(SingularMatrixError, match="measurement covariance R"):
        pcrb_linear(np.eye(4), F, Q, H, np.array([[1.0, 1.0], [1.0, 1.0]]), n_steps=3)
    b = pcrb_linear(np.diag([1e4, 1e4, 100.0, 100.0]), F, Q, H, R, n_steps=3)
    assert np.all(np.isfinite(b))


def test_crb_deterministic_with_prior_is_the_posterior_crb():
    """With a prior the recursion is the linear PCRB with Q = 0 and P0 = prior^-1; a
    velocity-only (singular) prior lowers the bound and fixes the first step."""
    from seatrack.models.measurement import RangeBearing

    K, dt = 10, 2.0
    X, F, _ = _bearing_truth(K, dt)
    model = RangeBearing(n=4, pos=(0, 1))
    R = np.diag([20.0**2, np.radians(0.5) ** 2])
    H = model.jacobian(X[0])
    info = np.einsum("kji,jl,klm->kim", H, np.linalg.inv(R), H)
    P0 = np.diag([500.0**2, 400.0**2, 30.0**2, 20.0**2])
    got = crb_deterministic(info, F, prior=np.linalg.inv(P0))
    want = pcrb_linear(P0, F, np.zeros((4, 4)), list(H), [R] * (K + 1), measure_first=True)
    np.testing.assert_allclose(got, want, rtol=1e-8)
    vel = np.diag([0.0, 0.0, 1 / 50.0**2, 1 / 50.0**2])
    with_v = crb_deterministic(info, F, prior=vel)
    without = crb_deterministic(info, F)
    assert np.all(np.isfinite(with_v[0])) and np.all(np.isnan(without[0]))
    assert np.all(np.trace(with_v[1:, :2, :2], axis1=1, axis2=2)
                  < np.trace(without[1:, :2, :2], axis1=1, axis2=2))  # fmt: skip
    with pytest.raises(ValueError, match="positive semi-definite"):
        crb_deterministic(info, F, prior=-vel)
