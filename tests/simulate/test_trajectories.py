import numpy as np
import pytest

from seatrack.geometry import G0
from seatrack.simulate import Leg
from seatrack.simulate import leg_times
from seatrack.simulate import trajectory


def test_straight_then_quarter_turn_geometry():
    v, w = 10.0, np.radians(3.0)
    tr = trajectory(
        [0, 0],
        np.radians(90),
        v,
        [Leg.straight(60), Leg.turn(np.pi / 2, w), Leg.straight(60)],
        dt=1.0,
    )
    r = v / w
    np.testing.assert_allclose(tr.pos[-1, :2], [600 + r, -r - 600], atol=1e-9)
    assert np.degrees(tr.course[-1]) == pytest.approx(180.0)
    assert tr.t[-1] == pytest.approx(150.0)
    np.testing.assert_allclose(tr.speed, v)


def test_velocity_is_derivative_of_position():
    tr = trajectory(
        [100, -50, 10],
        0.3,
        12.0,
        [Leg(40, turn_rate=0.02, accel=0.1, climb_rate=1.0), Leg(30, turn_rate=-0.05, accel=-0.2)],
        dt=0.01,
    )
    inner = (np.abs(tr.t - 40) > 0.05)[5:-5]  # central differences straddle the leg change
    num = np.gradient(tr.pos, tr.t, axis=0)
    np.testing.assert_allclose(num[5:-5][inner], tr.vel[5:-5][inner], atol=2e-4)
    acc = np.gradient(tr.vel, tr.t, axis=0)
    np.testing.assert_allclose(acc[5:-5][inner][:, :2], tr.acc[5:-5][inner][:, :2], atol=2e-3)


def test_turn_g_and_speed_change():
    leg = Leg.turn_g(np.pi, 3.0, 200.0)
    assert leg.turn_rate == pytest.approx(3 * G0 / 200)
    sc = Leg.speed_change(5.0, 10.0, 0.5)
    assert sc.duration == pytest.approx(10.0) and sc.accel == 0.5
    tr = trajectory([0, 0], 0.0, 5.0, [sc], dt=1.0)
    assert tr.speed[-1] == pytest.approx(10.0)
    assert tr.pos[-1, 1] == pytest.approx(75.0)


def test_state_layouts_and_interpolation():
    tr = trajectory([0, 0, 100], 1.0, 8.0, [Leg(20, turn_rate=0.05)], dt=2.0)
    assert tr.state("cv2").shape == (11, 4)
    assert tr.state("ct3").shape == (11, 7)
    assert tr.state("ca2").shape == (11, 6)
    fine = trajectory([0, 0, 100], 1.0, 8.0, [Leg(20, turn_rate=0.05)], times=[7.3])
    np.testing.assert_allclose(tr.at(7.3), fine.pos[0], atol=0.05)
    with pytest.raises(ValueError, match="unknown state layout"):
        tr.state("xyz")


def test_invalid_legs_and_sampling():
    with pytest.raises(ValueError, match="positive"):
        Leg(-1.0)
    with pytest.raises(ValueError, match="finite"):
        Leg(1.0, turn_rate=float("nan"))
    with pytest.raises(ValueError, match="exactly one"):
        trajectory([0, 0], 0, 1, [Leg(1)])
    with pytest.raises(ValueError, match="negative"):
        trajectory([0, 0], 0, 1.0, [Leg(10, accel=-1.0)], dt=1)
    np.testing.assert_allclose(leg_times([Leg(2), Leg(3)], 10.0), [10, 12, 15])


def test_closed_form_displacements_match_fine_simpson():
    from seatrack.simulate.trajectories import _displacement
    from seatrack.simulate.trajectories import _displacements

    rng = np.random.default_rng(0)
    n = 500
    c, s = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 30, n)
    w = rng.choice([0.0, 1e-7, 2e-5, 0.01, -0.05], n)
    a, vz, T = rng.choice([0.0, 0.3, -0.1], n), rng.normal(size=n), rng.uniform(0, 300, n)
    fast = _displacements(c, s, w, a, vz, T, 0.25)
    ref = np.array([_displacement(*x, 0.005) for x in zip(c, s, w, a, vz, T, strict=True)])
    np.testing.assert_allclose(fast, ref, atol=1e-6)
