"""Tests of seatrack.evaluate.metrics: RMSE, NEES/NIS, chi-square bounds, and the
linear-Gaussian consistency check (200 seeded Monte-Carlo runs of the seatrack.kalman CV
filter, batched through the broadcasting Kalman functions)."""

import numpy as np
import pytest
from scipy import stats

from seatrack import kalman
from seatrack.evaluate.bounds import pcrb_linear
from seatrack.evaluate.metrics import anees
from seatrack.evaluate.metrics import anis
from seatrack.evaluate.metrics import chi2_interval
from seatrack.evaluate.metrics import fraction_inside
from seatrack.evaluate.metrics import nees
from seatrack.evaluate.metrics import nis
from seatrack.evaluate.metrics import peak_error
from seatrack.evaluate.metrics import position_error
from seatrack.evaluate.metrics import rms_over_time
from seatrack.evaluate.metrics import rmse
from seatrack.evaluate.metrics import velocity_error
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition


def _spd(rng, n, batch=()):
    A = rng.standard_normal((*batch, n, n))
    return A @ np.swapaxes(A, -1, -2) + n * np.eye(n)


def test_rmse_by_hand_and_nan():
    e = np.array([[3.0, 1.0], [4.0, np.nan]])
    np.testing.assert_allclose(rmse(e, axis=0), [np.sqrt(12.5), 1.0])
    assert rmse(np.array([3.0, 4.0]), axis=None) == pytest.approx(np.sqrt(12.5))
    assert rms_over_time(np.array([[1.0, 100.0, 3.0]]), skip=0) == pytest.approx(np.sqrt(10010 / 3))
    assert rms_over_time(np.array([[100.0, 1.0, 1.0]]), skip=1) == pytest.approx(1.0)
    assert peak_error(np.array([1.0, -7.0, np.nan, 2.0])) == 7.0


def test_position_velocity_error():
    est = np.array([[3.0, 4.0, 1.0, 1.0]])
    truth = np.zeros((1, 4))
    np.testing.assert_allclose(position_error(est, truth), [5.0])
    np.testing.assert_allclose(velocity_error(est, truth), [np.sqrt(2.0)])
    est3 = np.array([1.0, 2.0, 2.0, 0.0, 0.0, 3.0])
    assert float(position_error(est3, np.zeros(6), dims=3)) == pytest.approx(3.0)
    assert float(velocity_error(est3, np.zeros(6), dims=3)) == pytest.approx(3.0)


def test_nees_matches_explicit_inverse_and_broadcasts():
    rng = np.random.default_rng(0)
    P = _spd(rng, 4, (5, 3))
    e = rng.standard_normal((5, 3, 4))
    ref = np.einsum("...i,...ij,...j->...", e, np.linalg.inv(P), e)
    np.testing.assert_allclose(nees(e, P), ref, rtol=1e-12)
    # one covariance for a batch of errors
    P1 = _spd(rng, 4)
    ref1 = np.einsum("...i,ij,...j->...", e, np.linalg.inv(P1), e)
    np.testing.assert_allclose(nees(e, P1), ref1, rtol=1e-12)
    assert np.ndim(nees(e[0, 0], P1)) == 0
    np.testing.assert_allclose(
        nis(e[..., :2], P[..., :2, :2]),
        np.einsum("...i,...ij,...j->...", e[..., :2], np.linalg.inv(P[..., :2, :2]), e[..., :2]),
        rtol=1e-12,
    )
    np.testing.assert_allclose(anees(e, P), ref.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(anis(e, P, axis=None), ref.mean(), rtol=1e-12)


def test_nees_rejects_bad_input():
    with pytest.raises(np.linalg.LinAlgError):
        nees(np.ones(2), np.array([[1.0, 2.0], [2.0, 1.0]]))  # indefinite
    with pytest.raises(ValueError, match="shape mismatch"):
        nees(np.ones(3), np.eye(2))


def test_nees_singular_covariance_is_found_explicitly_in_any_units():
    """An exactly singular covariance in a batch is refused by the scaled test (whatever
    LAPACK's Cholesky would do), with its index; badly scaled units alone are no problem."""
    from seatrack.information import SingularMatrixError

    units = np.diag([1e-4, 1e5])
    good = units @ np.array([[2.0, 1.0], [1.0, 3.0]]) @ units
    bad = units @ np.array([[1.0, 2.0], [2.0, 4.0]]) @ units  # rank 1
    e = np.ones((3, 2))
    assert np.all(np.isfinite(nees(e, np.stack([good, good, good]))))
    with pytest.raises(SingularMatrixError, match=r"index \(2,\)"):
        nees(e, np.stack([good, good, bad]))


@pytest.mark.parametrize(
    ("dof", "runs", "alpha"), [(1, 1, 0.05), (4, 200, 0.05), (2, 50, 0.01), (6, 1000, 0.1)]
)
def test_chi2_interval_vs_scipy(dof, runs, alpha):
    lo, hi = chi2_interval(dof, runs, alpha)
    assert lo == pytest.approx(stats.chi2.ppf(alpha / 2, dof * runs) / runs, rel=1e-12)
    assert hi == pytest.approx(stats.chi2.ppf(1 - alpha / 2, dof * runs) / runs, rel=1e-12)
    assert lo < dof < hi


def test_chi2_interval_coverage():
    # the average of `runs` chi2(dof) draws falls inside the interval ~95 % of the time
    rng = np.random.default_rng(3)
    lo, hi = chi2_interval(3, 20)
    avg = rng.chisquare(3, size=(20000, 20)).mean(axis=1)
    cover = fraction_inside(avg, lo, hi)
    assert 0.94 < cover < 0.96


def test_chi2_interval_rejects_bad_arguments():
    with pytest.raises(ValueError):
        chi2_interval(0, 10)
    with pytest.raises(ValueError):
        chi2_interval(2, 10, alpha=1.5)


def _linear_cv_mc(n_runs=200, steps=60, dt=2.0, q=0.5, sigma=(30.0, 30.0), r_factor=1.0, seed=11):
    """Batched Monte-Carlo of a 2-D CV target with position measurements."""
    rng = np.random.default_rng(seed)
    F = cv_transition(dt)
    Q = cv_noise(dt, q)
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    R = np.diag(np.square(sigma))
    m0 = np.array([1000.0, 2000.0, 5.0, -3.0])
    P0 = np.diag([100.0**2, 100.0**2, 5.0**2, 5.0**2])
    Lq = np.linalg.cholesky(Q)
    Lr = np.linalg.cholesky(R)
    truth = m0 + rng.standard_normal((n_runs, 4)) @ np.linalg.cholesky(P0).T
    x = np.broadcast_to(m0, (n_runs, 4)).copy()
    P = np.broadcast_to(P0, (n_runs, 4, 4)).copy()
    err, covs, innov, S = [], [], [], []
    for _ in range(steps):
        truth = truth @ F.T + rng.standard_normal((n_runs, 4)) @ Lq.T
        z = truth @ H.T + rng.standard_normal((n_runs, 2)) @ Lr.T
        x, P = kalman.predict(x, P, F, Q)  # (runs, n) batch, shared F and Q
        res = kalman.update(x, P, z, H, R * r_factor)
        x, P = res.x, res.P
        err.append(x - truth)
        covs.append(P)
        innov.append(res.y)
        S.append(res.S)
    return (
        np.stack(err, 1),
        np.stack(covs, 1),
        np.stack(innov, 1),
        np.stack(S, 1),
        (P0, F, Q, H, R),
    )


def test_linear_gaussian_anees_inside_chi2_bounds():
    n_runs = 200
    err, P, y, S, _ = _linear_cv_mc(n_runs)
    per_step = anees(err, P)  # (steps,)
    lo, hi = chi2_interval(4, n_runs)
    assert lo < per_step.mean() < hi
    assert fraction_inside(per_step, lo, hi) >= 0.9
    lo2, hi2 = chi2_interval(2, n_runs)
    per_step_nis = anis(y, S)
    assert lo2 < per_step_nis.mean() < hi2
    assert fraction_inside(per_step_nis, lo2, hi2) >= 0.9


def test_mis_specified_filter_fails_the_nees_test():
    # a filter that under-states R by 4x is over-confident: its ANEES leaves the bounds
    n_runs = 200
    err, P, _, _, _ = _linear_cv_mc(n_runs, r_factor=0.25)
    lo, hi = chi2_interval(4, n_runs)
    assert anees(err, P).mean() > hi
    assert fraction_inside(anees(err, P), lo, hi) < 0.2


def test_kalman_covariance_equals_pcrb_and_mc_error():
    err, P, _, _, (P0, F, Q, H, R) = _linear_cv_mc(200, steps=40)
    bound = pcrb_linear(P0, F, Q, H, R, n_steps=40)
    # the filter covariance is data independent and equals the PCRB (steps 1..K)
    np.testing.assert_allclose(P[0], bound[1:], rtol=1e-9, atol=1e-9)
    # and the Monte-Carlo MSE of the position matches the bound (within MC error)
    mse = np.mean(err[..., 0] ** 2, axis=0)
    ratio = mse[10:] / bound[11:, 0, 0]
    assert 0.8 < ratio.mean() < 1.2
