"""Tests of the Monte-Carlo batches of Ramazanov's sonar scenario."""

from __future__ import annotations

import numpy as np
import pytest

from seatrack.geometry import angle_diff
from seatrack.geometry import bearing
from seatrack.geometry import course_speed
from seatrack.simulate.marine import MarineScenario
from seatrack.simulate.marine import simulate_runs


def test_geometry_and_noise_of_the_paper() -> None:
    sc = MarineScenario(steps=50)
    r = simulate_runs(sc, 200, 0.2, np.random.default_rng(1))
    assert r.z.shape == (200, 50, 2) and r.truth.shape == (200, 50, 4)
    d0 = r.truth[:, 0, :2] - r.sensor[:, 0]
    r0 = np.hypot(d0[:, 0], d0[:, 1])
    assert r0.min() >= 900.0 and r0.max() <= 950.0
    # the measurements are range and true bearing of the relative position plus noise
    d = r.truth[..., :2] - r.sensor
    err_r = r.z[..., 0] - np.hypot(d[..., 0], d[..., 1])
    err_b = angle_diff(r.z[..., 1], bearing(d[..., 0], d[..., 1]))
    nom = ~r.outlier
    assert np.std(err_r[nom[..., 0]]) == pytest.approx(1.5, rel=0.05)
    assert np.std(err_b[nom[..., 1]]) == pytest.approx(np.deg2rad(2.0), rel=0.05)
    assert np.std(err_r[~nom[..., 0]]) == pytest.approx(1.5 * np.sqrt(10), rel=0.1)
    assert np.std(err_b[~nom[..., 1]]) == pytest.approx(np.deg2rad(10.0), rel=0.1)
    assert r.outlier.mean() == pytest.approx(0.2, abs=0.01)
    # own ship moves at 4 m/s
    v = np.diff(r.sensor, axis=1) / sc.dt
    np.testing.assert_allclose(np.hypot(v[..., 0], v[..., 1]), 4.0, rtol=1e-9)


def test_same_seed_same_geometry_for_every_epsilon() -> None:
    sc = MarineScenario(steps=20)
    a = simulate_runs(sc, 5, 0.0, np.random.default_rng(3))
    b = simulate_runs(sc, 5, 0.3, np.random.default_rng(3))
    np.testing.assert_array_equal(a.truth, b.truth)
    np.testing.assert_array_equal(a.sensor, b.sensor)
    assert not a.outlier.any() and b.outlier.any()


def test_manoeuvre_turns_and_accelerates() -> None:
    sc = MarineScenario(manoeuvre=True)
    r = simulate_runs(sc, 3, 0.0, np.random.default_rng(4))
    course, speed = course_speed(r.truth[..., 2], r.truth[..., 3])
    turned = angle_diff(course[:, -1], course[:, 0])
    np.testing.assert_allclose(turned, sc.turn_angle, atol=1e-9)
    turn_time = sc.turn_angle / sc.turn_rate
    np.testing.assert_allclose(speed[:, -1], sc.target_speed + sc.turn_accel * turn_time, rtol=1e-9)
    during = (r.t > sc.turn_start + 1) & (r.t < sc.turn_start + turn_time - 1)
    lateral = sc.turn_rate * speed[:, during]
    np.testing.assert_allclose(r.accel[:, during], np.hypot(lateral, sc.turn_accel), rtol=1e-6)
    assert np.all(r.accel[:, r.t < sc.turn_start] == 0.0)


def test_bad_scenarios_raise() -> None:
    with pytest.raises(ValueError, match="steps"):
        MarineScenario(steps=1)
    with pytest.raises(ValueError, match="manoeuvre"):
        MarineScenario(manoeuvre=True, steps=50)
    with pytest.raises(ValueError, match="n_runs"):
        simulate_runs(MarineScenario(), 0, 0.1, np.random.default_rng(0))
