"""Unlabelled plot files and the multi-target outputs."""

import csv

import numpy as np
import pytest

from seatrack.config import parse_config
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.registry import METHODS
from seatrack.io.multitarget import has_track_column
from seatrack.io.multitarget import make_filter
from seatrack.io.multitarget import read_unlabelled_plots
from seatrack.io.multitarget import run_unlabelled
from seatrack.io.multitarget import tracker_setup
from seatrack.io.multitarget import write_plot_labels
from seatrack.io.multitarget import write_tracks
from seatrack.io.multitarget import write_unlabelled_plots
from seatrack.io.table import InputError
from seatrack.tracking import MultiTargetTracker
from seatrack.tracking import TrackerConfig
from seatrack.tracking.adaptive import NoiseLevels


def _write(path, rows, header="time_s,range_m,azimuth_deg"):
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def test_read_and_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    n = 30
    p = Plots(
        np.repeat(np.arange(10) * 2.0, 3), rng.uniform(1000, 9000, n), rng.uniform(0, 6.28, n),
        None, rng.normal(0, 5, n), np.tile([[100.0, 50.0, 10.0]], (n, 1)),
    )  # fmt: skip
    f = tmp_path / "p.csv"
    write_unlabelled_plots(f, p)
    assert not has_track_column(f)
    q = read_unlabelled_plots(f)
    assert np.allclose(q.range, p.range, atol=1e-6) and np.allclose(q.azimuth, p.azimuth, atol=1e-8)
    assert np.allclose(q.range_rate, p.range_rate, atol=1e-6) and q.elevation is None
    assert np.allclose(q.sensor, p.sensor) and np.allclose(q.sensor_vel, 0.0)
    assert q.line.tolist() == list(range(2, n + 2))


@pytest.mark.parametrize(
    "rows, match",
    [
        (["0,1000,10", "0,-5,10"], "line 3: range_m must be > 0"),
        (["0,1000,10", "0,1000,360"], r"line 3: azimuth_deg must be in \[0, 360\)"),
        (["2,1000,10", "1,1000,10"], "line 3: time_s = 1 is earlier"),
        (["0,1000,x"], "line 2: column azimuth_deg = 'x' is not a number"),
    ],
)
def test_read_errors_name_the_line(tmp_path, rows, match):
    with pytest.raises(InputError, match=match):
        read_unlabelled_plots(_write(tmp_path / "p.csv", rows))


def test_partly_filled_optional_column(tmp_path):
    f = _write(
        tmp_path / "p.csv",
        ["0,1000,10,1", "0,1000,10,"],
        "time_s,range_m,azimuth_deg,range_rate_mps",
    )
    with pytest.raises(InputError, match="line 3: column range_rate_mps is empty here"):
        read_unlabelled_plots(f)


def test_duplicate_times_are_scans(tmp_path):
    f = _write(tmp_path / "p.csv", ["0,1000,10", "0,2000,20", "2.5,1010,10"])
    p = read_unlabelled_plots(f)
    assert len(p) == 3 and np.unique(p.t).size == 2
    assert has_track_column(
        _write(tmp_path / "l.csv", ["a,0,1000,10"], "track,time_s,range_m,azimuth_deg")
    )


def test_make_filter_builds_every_registered_method_and_rejects_unknown_ones():
    p = Plots(np.array([0.0, 2.0]), np.array([1000.0, 1000.0]), np.array([0.1, 0.1]),
              range_rate=np.zeros(2))  # fmt: skip
    for name in METHODS:
        m, rule = make_filter(name, {}, p)
        assert rule == METHODS[name].noise and m.name == name
        assert isinstance(m.filter, NoiseLevels) == (rule != "own")
    m, rule = make_filter("ekf", {"q": 0.5}, p)
    assert rule == "given" and not isinstance(m.filter, NoiseLevels)
    # the tracker's turn_rate_dps adds one coordinated-turn model each way
    tcfg = parse_config(TrackerConfig, {"turn_rate_dps": 2.0})
    m, rule = make_filter("ekf", {}, p, tracker=tcfg)
    assert rule == "levels" and np.allclose(m.filter.omega, np.radians([2.0, -2.0]))
    assert make_filter("ekf", {}, p)[0].filter.omega.size == 0
    with pytest.raises(ValueError, match="unknown method"):
        make_filter("kalman9", {}, p)


def test_outputs_account_for_every_plot(tmp_path):
    rng = np.random.default_rng(1)
    t = np.repeat(np.arange(8) * 2.5, 4)
    # two steady targets and two clutter plots per scan
    rr = np.column_stack([5000 + 10 * np.arange(8), 7000 - 5 * np.arange(8),
                          rng.uniform(1000, 9000, (8, 2))]).ravel()  # fmt: skip
    az = np.column_stack([np.full(8, 0.5), np.full(8, 2.0), rng.uniform(0, 6, (8, 2))]).ravel()
    p = Plots(t, rr + rng.normal(0, 5, t.size), az, line=np.arange(t.size) + 2)
    flt, _ = make_filter("ekf", {}, p)
    run = MultiTargetTracker(flt.filter, SensorNoise()).run(p)
    n = write_tracks(tmp_path / "tracks.csv", run, p)
    with open(tmp_path / "tracks.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == n > 0
    assert list(rows[0])[:2] == ["track", "time_s"] and "manoeuvre" in rows[0]
    assert {r["status"] for r in rows} <= {"confirmed", "coasting"}
    assert all(r["z_m"] == "" for r in rows)
    used = [int(r["plot_line"]) for r in rows if r["plot_line"]]
    write_plot_labels(tmp_path / "labels.csv", p, run.plot_track)
    with open(tmp_path / "labels.csv") as fh:
        lab = list(csv.DictReader(fh))
    assert [int(r["line"]) for r in lab] == list(range(2, t.size + 2))
    by_line = {int(r["line"]): r["track"] for r in lab}
    for r in rows:
        if r["plot_line"]:
            assert by_line[int(r["plot_line"])] == r["track"]
    assert {r["track"] for r in lab} - {"clutter"} == {r["track"] for r in rows}
    assert set(used) <= set(by_line)


def test_tracker_setup_parses_once_for_the_run(tmp_path):
    """The record of :func:`tracker_setup` is what the run uses: the ``--association``
    override, the sensor keys (flat or ``[sensor]``) and the method keys apart."""
    table = {"tracker": {"association": "gnn"}, "sensor": {"sigma_range_m": 15.0}, "q": 0.5}
    setup = tracker_setup(table, "radar.toml", association="jpda")
    assert setup.tracker.association == "jpda" and setup.source == "radar.toml"
    assert setup.sensor.sigma_range == 15.0
    assert setup.method_table == {"sensor": {"sigma_range_m": 15.0}, "q": 0.5}
    with pytest.raises(InputError, match="--association: must be gnn or jpda"):
        tracker_setup(table, association="mht")
    sim = _radar_file(tmp_path / "plots.csv", seed=3)
    res = run_unlabelled(sim.plots, "ekf", setup)
    assert res.tracker.config is setup.tracker and res.tracker.sensor is setup.sensor
    assert res.noise == "given" and res.run.confirmed_ids.size > 0


def _radar_file(path, seed):
    """A small unlabelled scenario with range rate (so that every method can run)."""
    from seatrack.simulate.multitarget import TargetPopulation
    from seatrack.simulate.multitarget import simulate_multitarget
    from seatrack.simulate.scenarios import SensorConfig

    radar = SensorConfig(
        "r", "radar2d", ("azimuth", "range", "range_rate"), (np.radians(0.3), 15.0, 0.5),
        p_detect=0.95, clutter_density=4.0, clutter_range=(500.0, 9000.0), scan_period=2.5,
    )  # fmt: skip
    pop = TargetPopulation(targets=4, births_per_scan=0.0, mean_life=0.0, crossings=0,
                           range_limits=(2000.0, 8000.0))  # fmt: skip
    sim = simulate_multitarget(pop, radar, 60.0, np.random.default_rng(seed))
    write_unlabelled_plots(path, sim.plots)
    return sim


@pytest.mark.parametrize("method", sorted(METHODS))
def test_every_registered_method_tracks_unlabelled_plots(tmp_path, method):
    """Any registered method is the per-track filter: tracks confirmed on every target,
    every plot accounted for, no NaN."""
    from cli_inprocess import seatrack

    sim = _radar_file(tmp_path / "plots.csv", seed=21)
    cfg = tmp_path / "radar.toml"
    cfg.write_text("[sensor]\nsigma_range_m = 15.0\nsigma_azimuth_deg = 0.3\n"
                   "sigma_range_rate_mps = 0.5\n")  # fmt: skip
    res = seatrack("track", tmp_path / "plots.csv", "--out", tmp_path / "t.csv", "--method",
                   method, "--config", cfg, "--plots-out", tmp_path / "labels.csv")  # fmt: skip
    assert res.returncode == 0, res.stderr
    line = res.stdout.strip()
    assert line.startswith(f"{method} multi-target (gnn)")
    with open(tmp_path / "t.csv") as fh:
        rows = list(csv.DictReader(fh))
    with open(tmp_path / "labels.csv") as fh:
        labels = list(csv.DictReader(fh))
    xy = np.array([[float(r["x_m"]), float(r["y_m"]), float(r["std_x_m"])] for r in rows])
    assert xy.size and np.isfinite(xy).all()
    assert len(labels) == len(sim.plots)  # every plot, with its track or as clutter
    ids = {r["track"] for r in rows}
    lab = np.array([r["track"] for r in labels])
    assert set(lab) - {"clutter"} <= ids
    # each target's plots mostly went to one reported track
    order = np.argsort(sim.plots.t, kind="stable")  # the file is in time order
    origin = sim.origin[order]
    for k in np.unique(origin[origin >= 0]):
        mine = lab[origin == k]
        top = max(np.unique(mine[mine != "clutter"], return_counts=True)[1], default=0)
        assert top >= 0.6 * mine.size, (k, method)
