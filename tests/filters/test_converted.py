"""Tests of the polar-to-Cartesian converted measurements."""

from __future__ import annotations

import numpy as np
import pytest

from seatrack.evaluate.metrics import chi2_interval
from seatrack.evaluate.metrics import nees
from seatrack.filters.converted import convert_plots
from seatrack.filters.converted import polar_jacobian
from seatrack.geometry import cart_to_spherical
from seatrack.geometry import polar_to_cart
from seatrack.geometry import spherical_to_cart
from seatrack.models import numerical_jacobian


@pytest.mark.parametrize("d", [2, 3])
def test_polar_jacobian_numerical(d):
    rng = np.random.default_rng(1)
    for _ in range(20):
        p = np.array([rng.uniform(1e3, 6e4), rng.uniform(0, 2 * np.pi), rng.uniform(-0.5, 0.5)])[:d]
        f = (lambda q: polar_to_cart(q[0], q[1])) if d == 2 else (lambda q: spherical_to_cart(*q))
        J = polar_jacobian(*p) if d == 3 else polar_jacobian(p[0], p[1])
        np.testing.assert_allclose(J, numerical_jacobian(f, p), rtol=1e-6, atol=1e-6)


def test_2d_unbiased_matches_longbin_closed_form():
    """Mo Longbin et al. (1998) eq. (11)-(13), measurement-conditioned form, written for
    azimuth clockwise from North (x = r sin a, y = r cos a)."""
    r, a, sr, sa = 4.2e4, 1.1, 35.0, np.radians(1.5)
    cm = convert_plots(r, a, None, sr, sa, method="unbiased")
    lam = np.exp(-(sa**2) / 2)
    lp = lam**4
    np.testing.assert_allclose(cm.z, [r * np.sin(a) / lam, r * np.cos(a) / lam])
    k = lam**-2 - 2
    Rxx = k * r**2 * np.sin(a) ** 2 + 0.5 * (r**2 + sr**2) * (1 - lp * np.cos(2 * a))
    Ryy = k * r**2 * np.cos(a) ** 2 + 0.5 * (r**2 + sr**2) * (1 + lp * np.cos(2 * a))
    Rxy = k * r**2 * np.sin(a) * np.cos(a) + 0.5 * (r**2 + sr**2) * lp * np.sin(2 * a)
    np.testing.assert_allclose(cm.R, [[Rxx, Rxy], [Rxy, Ryy]], rtol=1e-9)


@pytest.mark.parametrize("method", ["linearized", "unbiased"])
def test_small_noise_both_agree_and_sensor_offset(method):
    sensor = np.array([1200.0, -300.0, 15.0])
    r, a, e = 2.0e4, np.radians(230.0), np.radians(3.0)
    cm = convert_plots(r, a, e, 10.0, 1e-4, 1e-4, sensor=sensor, method=method)
    np.testing.assert_allclose(cm.z, spherical_to_cart(r, a, e) + sensor, rtol=1e-7)
    J = polar_jacobian(r, a, e)
    Rlin = J @ np.diag([10.0**2, 1e-8, 1e-8]) @ J.T
    np.testing.assert_allclose(cm.R, Rlin, rtol=1e-3, atol=1e-6)
    assert np.all(np.linalg.eigvalsh(cm.R) > 0)
    # back to polar relative to the sensor
    rr, aa, ee = cart_to_spherical(cm.z - sensor)
    assert abs(rr - r) < 1e-3 * (1 + (method == "unbiased")) and abs(aa - a) < 1e-9


def _monte_carlo(method, sa, n=20000, seed=3):
    rng = np.random.default_rng(seed)
    truth_polar = (5.0e4, np.radians(40.0), np.radians(10.0))
    truth = spherical_to_cart(*truth_polar)
    sr, se = 30.0, sa
    rm = truth_polar[0] + rng.normal(0, sr, n)
    am = truth_polar[1] + rng.normal(0, sa, n)
    em = truth_polar[2] + rng.normal(0, se, n)
    cm = convert_plots(rm, am, em, sr, sa, se, method=method)
    return cm.z - truth, cm.R


def test_unbiased_conversion_is_unbiased_and_consistent_at_large_cross_range_error():
    sa = np.radians(4.0)  # cross-range 3.5 km at 50 km: the linearised form fails here
    n = 20000
    err, R = _monte_carlo("unbiased", sa, n)
    se = err.std(axis=0) / np.sqrt(n)
    assert np.all(np.abs(err.mean(axis=0)) < 4 * se)
    lo, hi = chi2_interval(3, n)
    assert lo < nees(err, R).mean() < hi
    # and the empirical covariance matches the average R
    C = np.cov(err.T)
    np.testing.assert_allclose(np.diag(C), np.diag(R.mean(axis=0)), rtol=0.05)


def test_linearized_conversion_is_biased_and_optimistic_there():
    sa = np.radians(4.0)
    n = 20000
    err, R = _monte_carlo("linearized", sa, n)
    se = err.std(axis=0) / np.sqrt(n)
    assert np.max(np.abs(err.mean(axis=0)) / se) > 10  # bias ~ r sigma^2 = 120 m along range
    lo, hi = chi2_interval(3, n)
    assert nees(err, R).mean() > hi


def test_linearized_consistent_at_small_cross_range_error():
    err, R = _monte_carlo("linearized", np.radians(0.3))
    lo, hi = chi2_interval(3, err.shape[0])
    assert lo < nees(err, R).mean() < hi


def test_batch_shapes_and_errors():
    r = np.full((4, 5), 1e4)
    cm = convert_plots(r, 0.3, 0.1, 20.0, 0.01, 0.01)
    assert cm.z.shape == (4, 5, 3) and cm.R.shape == (4, 5, 3, 3)
    cm2 = convert_plots(r, 0.3, None, 20.0, 0.01, sensor=np.ones((4, 5, 3)))
    assert cm2.z.shape == (4, 5, 2) and np.allclose(
        cm2.z - 1.0, convert_plots(1e4, 0.3, None, 20.0, 0.01).z
    )
    cm3 = convert_plots(1e4, 0.3, None, 20.0, 0.01, sensor_cov=np.eye(2) * 4.0)
    np.testing.assert_allclose(cm3.R - convert_plots(1e4, 0.3, None, 20.0, 0.01).R, np.eye(2) * 4.0)
    with pytest.raises(ValueError, match="unknown conversion"):
        convert_plots(1e4, 0.3, None, 20.0, 0.01, method="magic")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="sigma_elevation"):
        convert_plots(1e4, 0.3, 0.1, 20.0, 0.01)
    with pytest.raises(ValueError, match="range"):
        convert_plots(-1.0, 0.3, None, 20.0, 0.01)
    with pytest.raises(ValueError, match="sigma_azimuth"):
        convert_plots(1e4, 0.3, None, 20.0, -0.01)
