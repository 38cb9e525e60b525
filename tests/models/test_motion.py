import numpy as np
import pytest

from seatrack.kalman import predict_core
from seatrack.models import ConstantAcceleration
from seatrack.models import ConstantVelocity
from seatrack.models import CoordinatedTurn
from seatrack.models import numerical_jacobian
from seatrack.models.motion import along_track_shape
from seatrack.models.motion import ca_transition
from seatrack.models.motion import ct_jacobian
from seatrack.models.motion import ct_noise
from seatrack.models.motion import ct_transition
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_noise_discrete
from seatrack.models.motion import cv_predict_core
from seatrack.models.motion import cv_transition
from seatrack.simulate import Leg
from seatrack.simulate import trajectory


def test_cv_transition_propagates_position():
    F = cv_transition(2.0, d=3)
    x = np.array([1, 2, 3, 10, -5, 1.0])
    np.testing.assert_allclose(F @ x, [21, -8, 5, 10, -5, 1])


def test_cv_noise_blocks_and_pd():
    Q = cv_noise(3.0, 0.5, d=2)
    np.testing.assert_allclose(Q[0, 0], 0.5 * 27 / 3)
    np.testing.assert_allclose(Q[0, 2], 0.5 * 9 / 2)
    np.testing.assert_allclose(Q[2, 2], 0.5 * 3)
    assert Q[0, 1] == 0 and Q[0, 3] == 0
    assert np.all(np.linalg.eigvalsh(Q) > 0)
    Qd = cv_noise_discrete(2.0, 1.5, d=2)
    np.testing.assert_allclose(Qd[0, 0], 1.5**2 * 4.0)
    np.testing.assert_allclose(Qd[0, 2], 1.5**2 * (4.0 / 2) * 2.0)


def test_along_track_shape_scales_the_noise_along_the_velocity():
    """``A = I - (1 - ratio) u u^T``: PSD ``ratio`` along ``v``, 1 across it, for each track
    of a batch, 2-D and 3-D; an unknown direction (speed below 3 sigma) keeps ``A = I``."""
    v = np.array([[30.0, 40.0], [0.5, 0.0], [0.0, 0.0]])
    Pv = np.broadcast_to(np.eye(2), (3, 2, 2))
    A = along_track_shape(v, Pv, 0.3)
    u, n = np.array([0.6, 0.8]), np.array([0.8, -0.6])
    np.testing.assert_allclose([u @ A[0] @ u, n @ A[0] @ n, u @ A[0] @ n], [0.3, 1.0, 0.0],
                               atol=1e-15)  # fmt: skip
    np.testing.assert_array_equal(A[1:], np.broadcast_to(np.eye(2), (2, 2, 2)))
    assert np.all(np.linalg.eigvalsh(A[0]) > 0)
    A3 = along_track_shape(np.array([0.0, 0.0, 200.0]), 4.0 * np.eye(3), 0.1)
    np.testing.assert_allclose(A3, np.diag([1.0, 1.0, 0.1]), atol=1e-15)
    np.testing.assert_array_equal(along_track_shape(v, Pv, 1.0), Pv)  # ratio 1: isotropic


def test_transitions_batch_over_dt():
    dts = np.array([1.0, 2.0, 0.5])
    F = cv_transition(dts, d=2)
    assert F.shape == (3, 4, 4)
    np.testing.assert_allclose(F[:, 0, 2], dts)
    Fa = ca_transition(dts, d=2)
    np.testing.assert_allclose(Fa[:, 0, 4], dts**2 / 2)


def test_ca_matches_kinematics():
    x = np.array([0, 0, 1, 2, 0.5, -0.25])
    x1 = ConstantAcceleration(d=2).transition(x, 4.0)[0]
    np.testing.assert_allclose(x1, [4 + 4, 8 - 2, 3, 1, 0.5, -0.25])


@pytest.mark.parametrize("w", [0.03, -0.02, 1e-9, 0.0, 2e-4, -0.3])
@pytest.mark.parametrize("dt", [0.5, 4.0])
def test_ct_jacobian_matches_numerical(w, dt):
    x = np.array([120.0, -40.0, 8.0, -3.0, w])
    J = ct_jacobian(x, dt)
    Jn = numerical_jacobian(lambda s: ct_transition(s, dt), x, eps=1e-7)
    np.testing.assert_allclose(J, Jn, atol=1e-5, rtol=1e-6)


def test_ct3_jacobian_matches_numerical():
    x = np.array([120.0, -40.0, 300.0, 8.0, -3.0, 1.5, 0.05])
    np.testing.assert_allclose(
        ct_jacobian(x, 2.0), numerical_jacobian(lambda s: ct_transition(s, 2.0), x), atol=1e-6
    )


def test_ct_matches_trajectory_simulator_clockwise():
    v = 10.0
    w = np.radians(3.0)
    tr = trajectory([0, 0], np.radians(90.0), v, [Leg(30.0, turn_rate=w)], dt=30.0)
    x0 = np.array([0.0, 0.0, v, 0.0, w])
    x1 = ct_transition(x0, 30.0)
    np.testing.assert_allclose(x1[:2], tr.pos[-1, :2], atol=1e-9)
    np.testing.assert_allclose(x1[2:4], tr.vel[-1, :2], atol=1e-9)
    assert x1[3] < 0  # heading east, turning clockwise -> towards south


def test_ct_zero_rate_equals_cv():
    x = np.array([1.0, 2.0, 3.0, 4.0, 0.0])
    np.testing.assert_allclose(ct_transition(x, 5.0)[:4], cv_transition(5.0) @ x[:4])


def test_ct_noise_shape():
    Q = ct_noise(2.0, 0.1, 1e-4, d=3)
    assert Q.shape == (7, 7)
    assert Q[-1, -1] == pytest.approx(2e-4)


def test_model_objects_names_and_shapes():
    for m in (ConstantVelocity(d=3), ConstantAcceleration(d=2), CoordinatedTurn(d=2)):
        x = np.arange(m.ndim_state, dtype=float) + 1.0
        fx, F = m.transition(x, 1.0)
        assert fx.shape == (m.ndim_state,) and F.shape == (m.ndim_state,) * 2
        assert m.noise(1.0).shape == F.shape
        assert len(m.state_names) == m.ndim_state
    assert CoordinatedTurn(d=2).state_names == ("x", "y", "vx", "vy", "w")
    with pytest.raises(ValueError, match="5 .2-D. or 7"):
        ct_transition(np.zeros(4), 1.0)


@pytest.mark.parametrize("d", [2, 3])
def test_cv_predict_core_is_the_general_prediction_bit_for_bit(d):
    rng = np.random.default_rng(d)
    n = 2 * d
    for T in (0.0, 0.37, 2.0, 61.5):
        x = rng.normal(size=n) * 1e3
        A = rng.normal(size=(n, n))
        P = A @ A.T + np.eye(n)
        Q = cv_noise(T, 3.7, d) + rng.normal(size=(n, n)) * 1e-9  # not exactly symmetric
        want_x, want_P = np.empty(n), np.empty((n, n))
        predict_core(x, P, cv_transition(T, d), Q, want_x, want_P)
        got_x, got_P = np.empty(n), np.empty((n, n))
        cv_predict_core(x, P, T, Q, got_x, got_P, np.empty((n, n)), d)
        assert np.array_equal(got_x, want_x) and np.array_equal(got_P, want_P)
