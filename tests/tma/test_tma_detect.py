"""Multi-leg targets: given manoeuvre times, and leg changes found from the residuals."""

import math

import numpy as np
import pytest

from seatrack.geometry import knots_to_mps
from seatrack.simulate import Leg
from seatrack.simulate import trajectory
from seatrack.simulate.tma import classic_scenario
from seatrack.simulate.tma import scenario_from_trajectories
from seatrack.tma import crb
from seatrack.tma import detect_legs
from seatrack.tma import solve

R = math.radians
DT = 30.0
TIMES = DT * np.arange(120)
M1, M2 = 1207.0, 2422.0  # middles of the two target turns


@pytest.fixture(scope="module")
def two_manoeuvre():
    obs = trajectory(
        [0, 0], R(90), knots_to_mps(8),
        [Leg.straight(600), Leg.turn(R(-90), R(3)), Leg.straight(900), Leg.turn(R(120), R(3)),
         Leg.straight(900), Leg.turn(R(-90), R(3)), Leg.straight(5000)],
        times=TIMES,
    )  # fmt: skip
    tgt = trajectory(
        [6000, 9000], R(200), knots_to_mps(10),
        [Leg.straight(1200), Leg.turn(R(-70), R(5)), Leg.straight(1200), Leg.turn(R(80), R(5)),
         Leg.straight(5000)],
        times=TIMES,
    )  # fmt: skip
    return scenario_from_trajectories(tgt, obs, R(0.5), [M1, M2])


def test_two_manoeuvre_target_recovered_with_given_times(two_manoeuvre):
    sc = two_manoeuvre
    rng = np.random.default_rng(21)
    P = crb(sc.state, sc.times, sc.observer.pos, sc.sigma, manoeuvres=[M1, M2])
    sd = np.sqrt(np.diag(P))
    z = []
    for _ in range(20):
        s = solve(sc.bearings(rng), manoeuvres=[M1, M2], sigma=sc.sigma)
        assert s.converged and s.observable
        assert s.state.size == 8 and np.allclose(s.manoeuvres, [M1, M2])
        z.append((s.state - sc.state) / sd)
    z = np.array(z)
    # every component within 4 CRB standard deviations, and the normalised errors are
    # about unit size (the turns last 14-16 s, so the leg model is not exact)
    assert np.all(np.abs(z) < 4.0)
    assert np.sqrt(np.mean(z**2)) < 1.5
    # the one-leg model cannot explain these bearings, and says so
    one = solve(sc.bearings(rng), sigma=sc.sigma)
    assert one.residual_rms > 3 * sc.sigma
    assert any("residuals are larger" in w for w in one.warnings)


def test_leg_changes_are_found_within_a_few_samples(two_manoeuvre):
    sc = two_manoeuvre
    rng = np.random.default_rng(22)
    for _ in range(3):
        b = sc.bearings(rng)
        d = detect_legs(b, sigma=sc.sigma)
        assert d.manoeuvres.size == 2
        assert np.all(np.abs(d.manoeuvres - [M1, M2]) <= 3 * DT)
        s = d.solution
        assert s.manoeuvres_detected and s.converged and s.observable
        assert abs(s.residual_rms / sc.sigma - 1) < 0.25
        assert d.costs[0] - d.costs[1] > d.penalty and d.costs[1] - d.costs[2] > d.penalty


def test_coarse_to_fine_candidate_scan(two_manoeuvre):
    """With fewer candidate slots than bearings, the coarse scan plus local refinement still
    finds both leg changes."""
    sc = two_manoeuvre
    b = sc.bearings(np.random.default_rng(25))
    d = detect_legs(b, sigma=sc.sigma, max_candidates=12)
    assert d.manoeuvres.size == 2
    assert np.all(np.abs(d.manoeuvres - [M1, M2]) <= 3 * DT)


def test_no_leg_change_detected_for_a_straight_target():
    sc = classic_scenario()
    rng = np.random.default_rng(23)
    found = [detect_legs(sc.bearings(rng), sigma=sc.sigma).manoeuvres.size for _ in range(10)]
    assert sum(found) <= 1  # BIC false alarms are rare


def test_solve_auto_uses_detection(two_manoeuvre):
    sc = two_manoeuvre
    b = sc.bearings(np.random.default_rng(24))
    s = solve(b, manoeuvres="auto", sigma=sc.sigma)
    assert s.manoeuvres_detected and s.manoeuvres.size == 2
    with pytest.raises(ValueError, match="auto"):
        solve(b, manoeuvres="detect")
