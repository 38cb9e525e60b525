"""Multi-target scenarios: reproducible, births and deaths, crossings, clutter, Pd."""

import math

import numpy as np
import pytest

from seatrack.io.table import InputError
from seatrack.simulate.multitarget import TargetPopulation
from seatrack.simulate.multitarget import parse_multitarget
from seatrack.simulate.multitarget import simulate_multitarget
from seatrack.simulate.scenarios import SensorConfig
from seatrack.simulate.scenarios import load_scenario
from seatrack.simulate.scenarios import resolve_scenario


def _radar(pd=0.9, clutter=20.0, components=("azimuth", "range")):
    sig = {"azimuth": np.radians(0.3), "range": 15.0, "range_rate": 1.0, "elevation": 0.005}
    return SensorConfig(
        "r", "radar2d", components, tuple(sig[c] for c in components), p_detect=pd,
        clutter_density=clutter, clutter_range=(500.0, 16000.0), scan_period=2.5,
    )  # fmt: skip


def test_reproducible_from_the_seed():
    pop = TargetPopulation(targets=5)
    a = simulate_multitarget(pop, _radar(), 100, np.random.default_rng(1))
    b = simulate_multitarget(pop, _radar(), 100, np.random.default_rng(1))
    c = simulate_multitarget(pop, _radar(), 100, np.random.default_rng(2))
    assert np.array_equal(a.plots.range, b.plots.range) and np.array_equal(a.origin, b.origin)
    assert a.plots.range.size != c.plots.range.size or not np.allclose(a.plots.range, c.plots.range)


def test_plots_and_truth():
    run = simulate_multitarget(TargetPopulation(targets=20, crossings=0), _radar(0.8, 30.0),
                               200, np.random.default_rng(3))  # fmt: skip
    p = run.plots
    assert np.all(np.diff(p.t) >= 0) and set(np.unique(p.t)) <= set(run.scan_times)
    # Poisson clutter with the given mean per scan, uniform in range over the window
    n_clutter = np.bincount(np.searchsorted(run.scan_times, p.t[run.origin < 0]),
                            minlength=run.scan_times.size)  # fmt: skip
    assert n_clutter.mean() == pytest.approx(30.0, abs=4 * math.sqrt(30 / n_clutter.size))
    assert p.range[run.origin < 0].min() >= 500 and p.range[run.origin < 0].max() <= 16000
    # detection probability: target plots over live (scan, target) pairs
    assert (run.origin >= 0).sum() / run.truth_t.size == pytest.approx(0.8, abs=0.03)
    # truth stays inside the surveillance annulus; target plots near their truth
    r = np.hypot(run.truth_pos[:, 0], run.truth_pos[:, 1])
    assert r.min() >= 1000 and r.max() <= 15000
    for k in np.unique(run.origin[run.origin >= 0])[:5]:
        m = run.origin == k
        tm = run.truth_id == k
        truth_at = run.truth_pos[tm][np.searchsorted(run.truth_t[tm], p.t[m])]
        err = np.linalg.norm(p.positions()[m] - truth_at[:, :2], axis=1)
        assert np.all(err < 6 * 15000 * np.radians(0.3))


def test_births_deaths_and_crossings():
    pop = TargetPopulation(targets=10, births_per_scan=0.2, mean_life=200.0, crossings=3)
    run = simulate_multitarget(pop, _radar(), 300, np.random.default_rng(4))
    first = {k: run.truth_t[run.truth_id == k].min() for k in np.unique(run.truth_id)}
    last = {k: run.truth_t[run.truth_id == k].max() for k in np.unique(run.truth_id)}
    assert sum(v > 0 for v in first.values()) >= 5  # born during the run (or entering)
    assert sum(v < 300 for v in last.values()) >= 5  # died or left
    # crossing pairs: the last 6 targets pass within metres of their partner once
    ids = np.unique(run.truth_id)
    met = 0
    for a, b in zip(ids[-6::2], ids[-5::2], strict=True):
        ta, tb = run.truth_id == a, run.truth_id == b
        common, ia, ib = np.intersect1d(run.truth_t[ta], run.truth_t[tb], return_indices=True)
        if common.size:
            dmin = np.linalg.norm(run.truth_pos[ta][ia] - run.truth_pos[tb][ib], axis=1).min()
            met += dmin < 40.0  # 2.5 s scans at up to 13 m/s
    assert met >= 2


def test_range_rate_and_scripted_targets():
    class Still:
        def trajectory(self, times):
            from seatrack.simulate import Leg
            from seatrack.simulate import trajectory

            return trajectory([5000.0, 0.0], 0.0, 5.0, [Leg.straight(1.0)], times=times)

    run = simulate_multitarget(TargetPopulation(targets=2, crossings=0),
                               _radar(components=("azimuth", "range", "range_rate")), 50,
                               np.random.default_rng(5), scripted=[Still()])  # fmt: skip
    assert run.plots.range_rate is not None
    assert np.all(np.isfinite(run.plots.range_rate))
    assert 0 in run.origin  # the scripted target is target 0


def test_parse_multitarget_and_scenario_file(tmp_path):
    pop = parse_multitarget({"targets": 7, "speed_kn": [2, 20], "turn_rate_dps": [1, 2]})
    assert pop.targets == 7 and pop.speed_limits[1] == pytest.approx(20 * 1852 / 3600)
    with pytest.raises(InputError, match="multitarget: unknown key 'ships'"):
        parse_multitarget({"ships": 3}, "f.toml")
    with pytest.raises(InputError, match="range_m"):
        parse_multitarget({"range_m": [5000.0, 1000.0]}, "f.toml")
    sc = load_scenario(resolve_scenario("coastal_multitarget"))
    assert sc.multitarget is not None and sc.multitarget.targets == 20
    bad = tmp_path / "bad.toml"
    bad.write_text(resolve_scenario("coastal_multitarget").read_text().replace(
        "crossings = 2", "crossings = -1"))  # fmt: skip
    with pytest.raises(InputError, match="crossings"):
        load_scenario(bad)
