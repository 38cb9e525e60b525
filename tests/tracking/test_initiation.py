"""Two-point initiation with a speed gate, and M-of-N confirmation."""

import numpy as np
import pytest

from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import plot_gaussian
from seatrack.tracking.initiation import confirmed
from seatrack.tracking.initiation import hopeless
from seatrack.tracking.initiation import polar_covariance
from seatrack.tracking.initiation import speed_gate_pairs


def _cov(n, s=20.0):
    return np.repeat(np.eye(2)[None] * s**2, n, 0)


def test_speed_gate_passes_ships_and_stops_fast_movers():
    p1 = np.array([[10000.0, 0.0], [0.0, 10000.0], [-8000.0, -8000.0]])
    dt = 2.5
    # 10 m/s, 100 m/s (too fast for 25 m/s), 24 m/s
    p2 = p1 + np.array([[25.0, 0.0], [0.0, 250.0], [60.0, 0.0]])
    pr = speed_gate_pairs(p1, _cov(3), np.zeros(3), p2, _cov(3), dt, 25.0, 0.999, np.zeros(3))
    pairs = sorted(zip(pr.first.tolist(), pr.second.tolist(), strict=True))
    assert pairs == [(0, 0), (2, 2)]


def test_each_plot_starts_at_most_one_track_and_the_likelier_pair_wins():
    p1 = np.array([[0.0, 0.0], [30.0, 0.0]])
    p2 = np.array([[2.0, 0.0]])
    pr = speed_gate_pairs(p1, _cov(2, 5.0), np.zeros(2), p2, _cov(1, 5.0), 2.5, 25.0, 0.999,
                          np.zeros(3))  # fmt: skip
    assert pr.first.tolist() == [0] and pr.second.tolist() == [0]


def test_older_plots_get_a_wider_speed_gate():
    p1 = np.array([[0.0, 0.0]])
    p2 = np.array([[100.0, 0.0]])  # 100 m: 40 m/s over one scan, 20 m/s over two
    one = speed_gate_pairs(p1, _cov(1, 3.0), [2.5], p2, _cov(1, 3.0), 5.0, 25.0, 0.999, np.zeros(3))
    two = speed_gate_pairs(p1, _cov(1, 3.0), [0.0], p2, _cov(1, 3.0), 5.0, 25.0, 0.999, np.zeros(3))
    assert one.first.size == 0 and two.first.size == 1


def test_m_of_n():
    hits = np.array([2, 3, 2, 3, 2, 4])
    age = np.array([2, 3, 3, 5, 4, 4])
    # M = 3 of N = 4
    assert confirmed(hits, age, 3, 4).tolist() == [False, True, False, False, False, True]
    # 2 hits at age 3 can still make 3 of 4; at age 4 the window is over
    assert hopeless(hits, age, 3, 4).tolist() == [False, False, False, True, True, True]
    # M = 2: confirmed at birth (two initiating plots)
    assert confirmed(np.array([2]), np.array([2]), 2, 3).tolist() == [True]


@pytest.mark.parametrize("three_d", [False, True])
def test_polar_covariance_equals_the_plot_gaussian(three_d):
    rng = np.random.default_rng(5)
    n = 20
    p = Plots(np.zeros(n), rng.uniform(500, 30000, n), rng.uniform(0, 2 * np.pi, n),
              rng.uniform(-0.3, 0.6, n) if three_d else None)  # fmt: skip
    sn = SensorNoise(sigma_range=12.0, sigma_azimuth=0.004, sigma_elevation=0.007)
    d = 3 if three_d else 2
    want = plot_gaussian(p, sn, 1.0)[1][:, :d, :d]
    assert np.allclose(polar_covariance(p, sn), want, rtol=1e-9, atol=1e-9)
