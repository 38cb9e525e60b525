"""Rotating-radar echo simulator: clutter density, landmark echoes, misses, rotation."""

from __future__ import annotations

import numpy as np

from seatrack.geometry import TWO_PI
from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.navigation.landmarks import LandmarkMap
from seatrack.simulate.radar_echoes import EchoEnvironment
from seatrack.simulate.radar_echoes import RadarConfig
from seatrack.simulate.radar_echoes import channel_landmarks
from seatrack.simulate.radar_echoes import river_route
from seatrack.simulate.radar_echoes import simulate_radar
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import trajectory

ROUTE = trajectory([0.0, 0.0], 0.0, 4.0, [Leg.straight(200.0), Leg.turn(np.pi / 2, 0.02)], dt=1.0)


def test_clutter_count_and_uniform_area_density():
    env = EchoEnvironment(clutter_density=2e-5)
    rc = RadarConfig()
    lm = LandmarkMap.from_arrays(np.array([[1e6, 1e6]]))  # out of range: clutter only
    sim = simulate_radar(ROUTE, lm, np.random.default_rng(1), rc, env)
    n_rev = int(ROUTE.t[-1] // rc.period)
    expect = 2e-5 * np.pi * (rc.range_limit**2 - rc.min_range**2) * n_rev
    n = sim.echoes.t.size
    assert abs(n - expect) < 4 * np.sqrt(expect) + 0.002 * expect  # a few (pulse, bin) duplicates
    assert np.all(sim.echoes.source == -1)
    # uniform in area: the fraction inside half the range is about a quarter
    inner = np.mean(sim.echoes.range < rc.range_limit / 2)
    assert abs(inner - 0.25) < 0.01


def test_echoes_follow_the_antenna_rotation_and_are_sorted():
    sim = simulate_radar(ROUTE, channel_landmarks(river_route(2000.0), 6), np.random.default_rng(2))
    e = sim.echoes
    assert np.all(np.diff(e.t) >= 0)
    np.testing.assert_allclose(wrap_pi(e.antenna - TWO_PI * e.t / 2.5), 0.0, atol=1e-9)
    assert np.all((e.range > 0) & (e.range < 3000.0))
    assert np.allclose(np.mod(e.range, 6.0), 3.0)  # bin centres of 6 m bins


def test_point_reflector_echoes_are_where_the_landmark_is():
    lm = LandmarkMap.from_arrays(np.array([[600.0, 900.0]]))
    env = EchoEnvironment(p_miss=0.0, p_pulse=1.0, clutter_density=1e-12, point_spread=0.0)
    rc = RadarConfig()
    sim = simulate_radar(ROUTE, lm, np.random.default_rng(3), rc, env)
    e = sim.echoes
    assert np.all(e.source == 0)
    x = np.interp(e.t, sim.truth_t, sim.truth[:, 0])
    y = np.interp(e.t, sim.truth_t, sim.truth[:, 1])
    h = np.interp(e.t, sim.truth_t, sim.truth[:, 2])
    r_true = np.hypot(600.0 - x, 900.0 - y)
    assert np.all(np.abs(e.range - r_true) <= 3.0 + 1e-6)  # inside the range bin
    rel = wrap_pi(bearing(600.0 - x, 900.0 - y) - h - e.antenna)
    assert np.all(np.abs(rel) <= 0.5 * rc.beam_width + 1e-9)  # inside the beam
    # every revolution sees it, on about beam / (360 deg / pulses per revolution) pulses
    n_rev = int(ROUTE.t[-1] // rc.period)
    per_rev = rc.beam_width / TWO_PI * rc.period * rc.prf
    assert abs(e.t.size / n_rev - per_rev) < 1.0


def test_missed_passes_and_hidden_interval():
    lm = LandmarkMap.from_arrays(np.array([[600.0, 900.0]]))
    env = EchoEnvironment(p_miss=0.2, clutter_density=1e-12, hidden=((100.0, 160.0),))
    sim = simulate_radar(ROUTE, lm, np.random.default_rng(4), env=env)
    revs = np.unique(np.floor(sim.echoes.t / 2.5))
    n_rev = int(ROUTE.t[-1] // 2.5)
    visible_revs = n_rev - 60.0 / 2.5
    frac = revs.size / visible_revs
    assert abs(frac - 0.8) < 4 * np.sqrt(0.16 / visible_revs)
    assert not np.any((sim.echoes.t >= 100.0) & (sim.echoes.t <= 160.0))


def test_map_errors_and_gyro():
    lms = channel_landmarks(river_route(2000.0), 10)
    env = EchoEnvironment(map_error_std=3.0, gyro_sigma=np.radians(0.1))
    sim = simulate_radar(ROUTE, lms, np.random.default_rng(5), env=env)
    d = sim.nav_map.xy - sim.true_map.xy
    assert 1.0 < d.std() < 6.0
    assert np.array_equal(sim.true_map.xy, lms.xy)
    w_true = np.interp(sim.gyro_t, ROUTE.t, ROUTE.turn_rate)
    assert abs(np.std(sim.gyro_rate - w_true) - np.radians(0.1)) < np.radians(0.01)
