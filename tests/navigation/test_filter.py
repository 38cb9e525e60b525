"""Navigation filter: numerical checks of every Jacobian, process noise, EKF == SRIF."""

from __future__ import annotations

import numpy as np
import pytest

from seatrack.filters.base import PlotStatus
from seatrack.models import numerical_jacobian
from seatrack.models.motion import cv_noise
from seatrack.navigation.filter import KalmanNav
from seatrack.navigation.filter import ProcessNoise
from seatrack.navigation.filter import SRIFNav
from seatrack.navigation.filter import compass_row
from seatrack.navigation.filter import contour_measurement
from seatrack.navigation.filter import contour_row
from seatrack.navigation.filter import gnss_rows
from seatrack.navigation.filter import gyro_row
from seatrack.navigation.filter import landmark_geometry
from seatrack.navigation.filter import log_speed
from seatrack.navigation.filter import nav_noise
from seatrack.navigation.filter import nav_transition
from seatrack.navigation.filter import point_measurement
from seatrack.navigation.filter import point_rows

STATES = [
    np.array([120.0, -40.0, np.radians(30.0), 2.0, 3.5, np.radians(0.8)]),
    np.array([-500.0, 900.0, np.radians(200.0), -3.0, 0.5, np.radians(-1.5)]),
]
LANDMARKS = [np.array([800.0, 650.0]), np.array([-1400.0, -200.0])]


@pytest.mark.parametrize("x", STATES)
@pytest.mark.parametrize("lm", LANDMARKS)
@pytest.mark.parametrize("a", [0.0, 25.0])
def test_point_rows_numerically(x, lm, a):
    r_c, _, phi_c = landmark_geometry(x, lm, a)
    H = point_rows(x, lm, a)
    Hn = numerical_jacobian(lambda s: point_measurement(s, lm, a, r_c, phi_c), x)
    np.testing.assert_allclose(H, Hn, atol=1e-5 * max(1.0, r_c))


@pytest.mark.parametrize("x", STATES)
@pytest.mark.parametrize("lm", LANDMARKS)
@pytest.mark.parametrize("a", [0.0, 25.0])
@pytest.mark.parametrize("beta_deg", [0.0, 37.0, 90.0, 161.0])
def test_contour_row_numerically(x, lm, a, beta_deg):
    beta = np.radians(beta_deg)
    r_c, th_c, phi_c = landmark_geometry(x, lm, a)
    h = contour_row(x, lm, beta, a)
    hn = numerical_jacobian(lambda s: contour_measurement(s, lm, beta, a, r_c, th_c, phi_c), x)
    np.testing.assert_allclose(h, hn[0], atol=1e-5 * max(1.0, r_c))


def test_contour_row_is_projection_of_point_rows():
    # z = cos(th - beta) dr - sin(th - beta) dtheta  =>  h_z = c h_r - s h_t
    x, lm, a, beta = STATES[0], LANDMARKS[0], 12.0, np.radians(70.0)
    _, th, _ = landmark_geometry(x, lm, a)
    H = point_rows(x, lm, a)
    expect = np.cos(th - beta) * H[0] - np.sin(th - beta) * H[1]
    np.testing.assert_allclose(contour_row(x, lm, beta, a), expect, atol=1e-9)


@pytest.mark.parametrize("x", STATES)
def test_prediction_jacobian_numerically(x):
    _, F = nav_transition(x, 0.156)
    Fn = numerical_jacobian(lambda s: nav_transition(s, 0.156)[0], x)
    np.testing.assert_allclose(F, Fn, atol=1e-7)


def test_prediction_turns_velocity_clockwise():
    x = np.array([0.0, 0.0, 0.0, 0.0, 5.0, 0.1])  # heading North, turning to starboard
    fx, _ = nav_transition(x, 0.1)
    assert fx[3] > 0 and fx[4] == pytest.approx(5.0)  # velocity gains an East component
    assert fx[2] == pytest.approx(0.01) and fx[1] == pytest.approx(0.5)


@pytest.mark.parametrize("x", STATES)
def test_other_sensor_rows_numerically(x):
    np.testing.assert_allclose(log_speed(x)[1], numerical_jacobian(lambda s: log_speed(s)[0], x)[0],
                               atol=1e-7)  # fmt: skip
    np.testing.assert_allclose(gyro_row(), numerical_jacobian(lambda s: s[5], x)[0], atol=1e-9)
    np.testing.assert_allclose(compass_row(), numerical_jacobian(lambda s: s[2], x)[0], atol=1e-9)
    np.testing.assert_allclose(gnss_rows(), numerical_jacobian(lambda s: s[:2], x), atol=1e-9)


def test_nav_noise_matches_cv_noise():
    n = ProcessNoise(q_vel=0.3, q_turn=2e-5)
    q = np.array([0.3, 0.3, 2e-5] * 2)
    ref = cv_noise(0.7, 1.0, d=3) * np.sqrt(np.outer(q, q))
    np.testing.assert_allclose(nav_noise(0.7, n), ref, rtol=1e-12, atol=1e-18)


def test_ekf_and_srif_agree_on_a_sequence():
    rng = np.random.default_rng(11)
    x0 = STATES[0]
    P0 = np.diag([400.0, 400.0, 0.003, 1.0, 1.0, 1e-4])
    ekf, srif = KalmanNav(), SRIFNav()
    se, ss = ekf.initiate(0.0, x0, P0), srif.initiate(0.0, x0, P0)
    np.testing.assert_allclose(ss.x[0], x0, atol=1e-9)
    np.testing.assert_allclose(ss.P[0], P0, rtol=1e-9)
    t = 0.0
    for k in range(300):
        t += 0.156 * rng.uniform(0.2, 1.0)
        se, ss = ekf.predict(se, t), srif.predict(ss, t)
        np.testing.assert_allclose(se.x, ss.x, atol=1e-9)
        lm = LANDMARKS[k % 2]
        if k % 3 == 0:
            H = point_rows(se.x[0], lm, 10.0)
            y = rng.normal(0, 3.0, 2)
            R = np.diag(rng.uniform(4.0, 30.0, 2))
        elif k % 3 == 1:
            H = contour_row(se.x[0], lm, 0.4, 10.0)[None, :]
            y, R = rng.normal(0, 3.0, 1), np.array([[9.0]])
        else:
            H, y, R = gyro_row()[None, :], rng.normal(0, 1e-3, 1), np.array([[1e-6]])
        se, ss = ekf.update(se, y, H, R), srif.update(ss, y, H, R)
        assert se.status[0] == ss.status[0] == PlotStatus.UPDATED
        np.testing.assert_allclose(se.nis, ss.nis, rtol=1e-6)
    np.testing.assert_allclose(se.x, ss.x, atol=1e-6)
    np.testing.assert_allclose(se.P, ss.P, atol=1e-6 * np.abs(se.P).max())
    assert np.all(np.linalg.eigvalsh(se.P[0]) > 0)


@pytest.mark.parametrize("cls", [KalmanNav, SRIFNav])
def test_unusable_measurement_is_rejected_state_kept(cls):
    flt = cls()
    s = flt.predict(flt.initiate(0.0, STATES[0], np.eye(6)), 1.0)
    bad = flt.update(s, [np.nan], gyro_row()[None, :], [[1e-6]])
    assert bad.status[0] == PlotStatus.REJECTED
    np.testing.assert_array_equal(bad.x, s.x)
    neg = flt.update(s, [0.1], gyro_row()[None, :], [[-100.0]])  # S not positive definite
    assert neg.status[0] == PlotStatus.REJECTED
    np.testing.assert_array_equal(neg.x, s.x)
