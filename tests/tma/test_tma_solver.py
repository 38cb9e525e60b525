"""TMA solver: classic-scenario Monte Carlo against the CRB, observability, support values,
step control, wrapping, batching."""

import math

import numpy as np
import pytest

from seatrack.evaluate.metrics import anees
from seatrack.evaluate.metrics import chi2_interval
from seatrack.geometry import bearing
from seatrack.geometry import knots_to_mps
from seatrack.simulate import Leg
from seatrack.simulate import trajectory
from seatrack.simulate.tma import TMAScenario
from seatrack.simulate.tma import classic_scenario
from seatrack.tma import Bearings
from seatrack.tma import SupportValue
from seatrack.tma import TMAConfig
from seatrack.tma import crb
from seatrack.tma import position_crb
from seatrack.tma import solve
from seatrack.tma import solve_many
from seatrack.tma.legs import leg_starts
from seatrack.tma.lm import levenberg_marquardt
from seatrack.tma.problem import Problem
from tma_samples import random_geometry

SC = classic_scenario()


@pytest.fixture(scope="module")
def classic_runs():
    rng = np.random.default_rng(20240601)
    runs = SC.bearings_batch(rng, 500)
    sols = solve_many({str(i): b for i, b in enumerate(runs)}, sigma=SC.sigma)
    return runs, list(sols.values())


def test_classic_scenario_converges_and_reaches_the_crb(classic_runs):
    """Ristic et al. ch. 6 scenario, 500 seeded runs, automatic start (issue 3 acceptance)."""
    _, sols = classic_runs
    t_last = SC.times[-1]
    # the chi-square residual warning (99.9 % quantile) fires rarely on correct data
    assert sum(any("residuals are larger" in w for w in s.warnings) for s in sols) <= 3
    converged = np.mean([s.converged for s in sols])
    assert converged >= 0.99
    assert all(s.observable for s in sols)
    err = np.array([s.position_at(np.array([t_last]))[0] for s in sols]) - SC.target.pos[-1, :2]
    rmse = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
    P = crb(SC.state, SC.times, SC.observer.pos, SC.sigma)
    bound = float(np.sqrt(np.trace(position_crb(P, SC.starts, t_last))))
    assert abs(rmse / bound - 1.0) <= 0.10, (rmse, bound)


def test_classic_scenario_covariance_is_consistent(classic_runs):
    """Average NEES of the final position with the reported (J^T W J)^-1 is chi-square(2)."""
    _, sols = classic_runs
    t_last = SC.times[-1]
    err = np.array([s.position_at(np.array([t_last]))[0] for s in sols]) - SC.target.pos[-1, :2]
    P = np.array([s.position_covariance_at(t_last) for s in sols])
    lo, hi = chi2_interval(2, len(sols))
    assert lo <= float(anees(err, P)) <= hi
    # the reported 1-sigma of position equals sqrt(diag) of that covariance; 95 % = 1.96 sigma
    s = sols[0]
    assert np.isclose(s.last.sigma_x, math.sqrt(P[0][0, 0]))
    assert np.isclose(s.last.halfwidths["range"], 1.959964 * s.last.sigma_range, rtol=1e-6)
    # range: 95 % intervals cover the true final range in about 95 % of the runs
    o = SC.observer.pos[-1, :2]
    true_range = float(np.hypot(*(SC.target.pos[-1, :2] - o)))
    inside = [abs(s.last.range - true_range) <= s.last.halfwidths["range"] for s in sols]
    assert 0.92 <= np.mean(inside) <= 0.98


def test_noise_free_recovers_truth_exactly():
    d = SC.target.pos[:, :2] - SC.observer.pos[:, :2]
    exact = Bearings(SC.times, bearing(d[:, 0], d[:, 1]), SC.observer.pos[:, :2])
    s = solve(exact, sigma=SC.sigma)
    assert s.converged and s.observable
    assert np.allclose(s.state, SC.state, atol=1e-3)
    assert s.residual_rms < 1e-9


def _cv_scenario():
    obs = trajectory(
        [0, 0], math.radians(140), knots_to_mps(5), [Leg.straight(3000)], times=SC.times
    )
    return TMAScenario(SC.target, obs, SC.sigma, SC.state)


def test_no_manoeuvre_no_support_is_not_observable():
    sc = _cv_scenario()
    s = solve(sc.bearings(np.random.default_rng(3)), sigma=sc.sigma)
    assert not s.observable
    assert s.observer_deviation < 1e-6
    assert any("not observable" in w for w in s.warnings)
    L = s.last
    for v in (L.x, L.y, L.range, L.course, L.speed, L.sigma_range, L.sigma_course, L.sigma_speed):
        assert math.isnan(v)
    assert math.isfinite(L.bearing)  # the bearing itself is measured
    with pytest.raises(np.linalg.LinAlgError):
        crb(sc.state, sc.times, sc.observer.pos, sc.sigma)


def test_navigation_noise_is_not_an_own_ship_manoeuvre():
    """A straight own-ship track with 2 m navigation noise: not observable, whether the
    geometry test (default threshold) or -- with it disabled -- the scaled rank test or the
    range-precision test reject it."""
    sc = _cv_scenario()
    reasons = set()
    cfg0 = TMAConfig(sigma=sc.sigma, min_observer_deviation=0.0)
    for seed in range(8):
        rng = np.random.default_rng(seed)
        b = sc.bearings(rng)
        noisy = Bearings(b.t, b.bearing, b.observer + 2.0 * rng.standard_normal(b.observer.shape))
        s = solve(noisy, sigma=sc.sigma)
        assert not s.observable and 1.0 < s.observer_deviation < 10.0
        s = solve(noisy, config=cfg0)
        assert not s.observable and math.isnan(s.last.range)
        reasons.add(s.warnings[0].split("(")[0].split(" is ")[0])
    assert reasons and reasons <= {
        "not observable: singular geometry ",
        "not observable: range 1-sigma",
    }


def test_early_solution_before_the_turn_has_completed_is_not_confident():
    """Classic scenario cut after 15 bearings (two samples into the own-ship turn): the
    first-order range sigma exceeds half the range, so no confident answer; at 20 bearings
    the answer is given."""
    rng = np.random.default_rng(15)
    b = SC.bearings(rng)
    early = solve(Bearings(b.t[:15], b.bearing[:15], b.observer[:15]), sigma=SC.sigma)
    assert not early.observable and "range 1-sigma" in early.warnings[0]
    later = solve(Bearings(b.t[:20], b.bearing[:20], b.observer[:20]), sigma=SC.sigma)
    assert later.observable


def test_range_support_makes_no_manoeuvre_geometry_observable():
    sc = _cv_scenario()
    rng = np.random.default_rng(4)
    b = sc.bearings(rng)
    t = float(sc.times[-1])
    o = sc.observer.pos[-1, :2]
    true_range = float(np.hypot(*(sc.target.pos[-1, :2] - o)))
    sup = [SupportValue("range", t, true_range + 30.0 * rng.standard_normal(), 30.0, (o[0], o[1]))]
    s = solve(b, sup, sigma=sc.sigma)
    assert s.observable and s.converged
    assert s.condition_number < 1e3
    assert abs(s.last.range - true_range) < 3 * s.last.sigma_range
    assert s.last.sigma_range <= 30.0 + 1e-6
    # the bound with the support value exists and matches the reported covariance
    P = crb(sc.state, sc.times, sc.observer.pos, sc.sigma, support=sup)
    assert np.allclose(np.sqrt(np.diag(P)), np.sqrt(np.diag(s.covariance)), rtol=0.2)


def test_support_values_reduce_iterations():
    """Patent claim: support values need far fewer iterations (same start, same bearings)."""
    rng = np.random.default_rng(8)
    t_last = float(SC.times[-1])
    o = SC.observer.pos[-1, :2]
    true_range = float(np.hypot(*(SC.target.pos[-1, :2] - o)))
    fewer = []
    for _ in range(10):
        b = SC.bearings(rng)
        init = [10_000 * math.sin(b.bearing[0]), 10_000 * math.cos(b.bearing[0]), 3.0, 3.0]
        sup = [
            SupportValue(
                "range", t_last, true_range + 50 * rng.standard_normal(), 50.0, (o[0], o[1])
            ),
            SupportValue("speed", 600.0, knots_to_mps(4.0) + 0.2 * rng.standard_normal(), 0.2),
        ]
        s0 = solve(b, sigma=SC.sigma, initial=init)
        s1 = solve(b, sup, sigma=SC.sigma, initial=init)
        assert s0.converged and s1.converged
        fewer.append(s1.iterations < s0.iterations)
    assert all(fewer)


def test_linear_and_squared_support_give_nearly_the_same_solution():
    rng = np.random.default_rng(9)
    b = SC.bearings(rng)
    o = SC.observer.pos[-1, :2]
    rt = float(np.hypot(*(SC.target.pos[-1, :2] - o)))
    sup = [
        SupportValue("range", float(SC.times[-1]), rt + 20.0, 40.0, (o[0], o[1])),
        SupportValue("speed", 100.0, knots_to_mps(4.0), 0.3),
        SupportValue("course", 200.0, math.radians(220.0), math.radians(5.0)),
    ]
    lin = solve(b, sup, sigma=SC.sigma)
    sq = solve(b, sup, sigma=SC.sigma, config=TMAConfig(support_residual="square"))
    assert lin.converged and sq.converged
    dp = np.hypot(lin.last.x - sq.last.x, lin.last.y - sq.last.y)
    assert dp < 0.05 * lin.last.sigma_range
    assert np.allclose(lin.covariance, sq.covariance, rtol=0.05)


def test_levenberg_marquardt_never_increases_the_cost():
    b = SC.bearings(np.random.default_rng(12))
    cfg = TMAConfig(sigma=SC.sigma)
    prob = Problem.stack([Problem.build(b, [], leg_starts(b.t[0]), cfg.sigma)])
    start = np.array([[0.0, 60_000.0, -10.0, 10.0]])  # far off: range 60 km, wrong course
    costs = [float(levenberg_marquardt(prob, start, cfg, k).cost[0]) for k in range(0, 40)]
    assert all(c2 <= c1 for c1, c2 in zip(costs, costs[1:]))
    assert costs[-1] < 1e-3 * costs[0]


def test_bearings_crossing_north_are_wrapped():
    times = 30.0 * np.arange(60)
    obs = trajectory(
        [0, 0], math.radians(90), 4.0,
        [Leg.straight(600), Leg.turn(math.radians(-150), math.radians(2)), Leg.straight(3000)],
        times=times,
    )  # fmt: skip
    tgt = trajectory([-1500, 8000], math.radians(90), 5.0, [Leg.straight(3000)], times=times)
    sc = TMAScenario(tgt, obs, math.radians(0.5), np.r_[-1500, 8000, 5.0, 0.0])
    b = sc.bearings(np.random.default_rng(2))
    assert b.bearing.min() < 0.2 and b.bearing.max() > 2 * np.pi - 0.2  # crosses North
    s = solve(b, sigma=sc.sigma)
    assert s.converged and s.observable
    assert np.all(np.abs(s.residuals) < 5 * sc.sigma)
    assert abs(s.residual_rms / sc.sigma - 1) < 0.3


def test_solve_many_matches_solve_with_padding():
    rng = np.random.default_rng(13)
    full = SC.bearings(rng)
    contacts = {
        "a": full,
        "b": Bearings(full.t[:24], full.bearing[:24], full.observer[:24]),
        "c": SC.bearings(rng),
    }
    sup = {"c": [SupportValue("speed", 100.0, 2.0, 0.3)]}
    many = solve_many(contacts, sup, sigma=SC.sigma)
    for cid, b in contacts.items():
        one = solve(b, sup.get(cid), sigma=SC.sigma)
        assert np.allclose(many[cid].state, one.state, rtol=1e-6, atol=1e-4)
        assert many[cid].n_bearings == len(b)
    # per-contact manoeuvres: contacts with different state sizes in one call
    man = {"a": [900.0], "b": None, "c": [600.0, 1200.0]}
    many = solve_many(contacts, sup, man, sigma=SC.sigma)
    assert list(many) == ["a", "b", "c"]
    assert [many[c].state.size for c in "abc"] == [6, 4, 8]
    one = solve(contacts["c"], sup["c"], [600.0, 1200.0], sigma=SC.sigma)
    assert np.allclose(many["c"].state, one.state, rtol=1e-6, atol=1e-4)
    with pytest.raises(ValueError, match="unknown contact"):
        solve_many(contacts, {"zz": sup["c"]})


def test_user_initial_guess_and_state_size_checks():
    b = SC.bearings(np.random.default_rng(14))
    s = solve(b, sigma=SC.sigma, initial=SC.state)
    auto = solve(b, sigma=SC.sigma)
    assert np.allclose(s.state, auto.state, rtol=1e-5, atol=1e-3)
    with pytest.raises(ValueError, match="components"):
        solve(b, initial=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="not after"):
        solve(b, manoeuvres=[-5.0])
    with pytest.raises(ValueError, match="not before the last bearing"):
        solve(b, manoeuvres=[b.t[-1] + 10.0])
    with pytest.raises(ValueError, match="contact x: manoeuvre time"):
        solve_many({"x": b}, manoeuvres=[b.t[-1]])


def test_bearings_validation():
    with pytest.raises(ValueError, match="at least 2"):
        Bearings(np.array([0.0]), np.array([1.0]), np.zeros((1, 2)))
    with pytest.raises(ValueError, match="strictly increasing"):
        Bearings(np.array([0.0, 2.0, 1.0]), np.ones(3), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="not finite"):
        Bearings(np.array([0.0, 1.0]), np.array([1.0, np.nan]), np.zeros((2, 2)))


def test_automatic_start_finds_the_global_minimum_on_random_geometries():
    """Random geometries with one own-ship turn (ranges 1-40 km, any courses, 20-80
    bearings): wherever the solve started at the truth converges to an observable answer,
    the automatic start reaches the same (or a lower) cost."""
    rng = np.random.default_rng(0)
    n_good = 0
    for _ in range(40):
        sc = random_geometry(rng)
        b = sc.bearings(rng)
        auto = solve(b, sigma=sc.sigma)
        ref = solve(b, sigma=sc.sigma, initial=sc.state)
        if ref.converged and ref.observable:
            n_good += 1
            assert auto.converged and auto.observable
            assert auto.cost <= ref.cost * (1 + 1e-6) + 1e-9
        # a weak geometry may have its minimum far out in range (the ML estimate runs off):
        # then the solver must not claim a confident answer
        assert auto.converged or not auto.observable
    assert n_good >= 20  # enough well-posed cases to exercise the claim (29 of 40 here)
