"""``seatrack track`` on unlabelled plots and ``seatrack evaluate`` on a multi-target scenario."""

import csv

import numpy as np
import pytest

from cli_inprocess import seatrack
from seatrack.io.multitarget import write_unlabelled_plots
from seatrack.simulate.multitarget import TargetPopulation
from seatrack.simulate.multitarget import simulate_multitarget
from seatrack.simulate.scenarios import SensorConfig


def _seatrack(*args, cwd):
    return seatrack(*args, cwd=cwd)


def _plots_file(path, seed=0):
    radar = SensorConfig(
        "r", "radar2d", ("azimuth", "range"), (np.radians(0.3), 15.0), p_detect=0.95,
        clutter_density=8.0, clutter_range=(500.0, 12000.0), scan_period=2.5,
    )  # fmt: skip
    pop = TargetPopulation(targets=5, births_per_scan=0.0, mean_life=0.0, crossings=0,
                           range_limits=(2000.0, 10000.0))  # fmt: skip
    sim = simulate_multitarget(pop, radar, 100.0, np.random.default_rng(seed))
    write_unlabelled_plots(path, sim.plots)
    return sim


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_unlabelled_plots_run_the_multitarget_tracker(tmp_path):
    sim = _plots_file(tmp_path / "plots.csv")
    cfg = tmp_path / "radar.toml"
    cfg.write_text("sigma_range_m = 15.0\nsigma_azimuth_deg = 0.3\n")
    r = _seatrack(
        "track", "plots.csv", "--config", "radar.toml", "-o", "out/tracks.csv",
        "--plots-out", "out/labels.csv", "--plot", "out/tracks.png", cwd=tmp_path,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "multi-target (gnn)" in r.stdout and "5 confirmed tracks" in r.stdout
    rows = _rows(tmp_path / "out/tracks.csv")
    assert {x["status"] for x in rows} == {"confirmed", "coasting"}
    assert len({x["track"] for x in rows}) == 5
    labels = _rows(tmp_path / "out/labels.csv")
    assert len(labels) == len(sim.plots)
    # every plot accounted for, target plots with their track, clutter as clutter
    target = sim.origin >= 0
    lab = np.array([x["track"] for x in labels])
    assert np.mean(lab[target] != "clutter") > 0.9 and np.mean(lab[~target] == "clutter") > 0.95
    assert (tmp_path / "out/tracks.png").stat().st_size > 10_000


def test_all_tracks_and_jpda(tmp_path):
    _plots_file(tmp_path / "plots.csv", seed=1)
    r = _seatrack("track", "plots.csv", "-o", "t.csv", "--all-tracks", "--association", "jpda",
                  cwd=tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "multi-target (jpda)" in r.stdout
    assert "tentative" in {x["status"] for x in _rows(tmp_path / "t.csv")}


@pytest.mark.parametrize("method", ["ekf", "imm", "turning"])
def test_no_confirmed_track_writes_the_header_and_accounts_for_every_plot(tmp_path, method):
    """One plot (or clutter only): no track is ever confirmed -- a header-only TRACKS.csv,
    every plot `clutter` in --plots-out, exit 0 (it was an internal error: no columns)."""
    (tmp_path / "p.csv").write_text(
        "time_s,range_m,azimuth_deg,elevation_deg,range_rate_mps\n0,9506.91,31.82,6.5973,54.571\n"
    )
    r = _seatrack("track", "p.csv", "-o", "t.csv", "--method", method, "--plots-out", "pl.csv",
                  "--plot", "t.png", cwd=tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "0 confirmed tracks" in r.stdout
    head = (tmp_path / "t.csv").read_text().splitlines()
    assert len(head) == 1 and head[0].startswith("track,time_s,x_m,y_m,z_m")
    assert [x["track"] for x in _rows(tmp_path / "pl.csv")] == ["clutter"]
    assert (tmp_path / "t.png").stat().st_size > 0


def test_errors_are_one_line(tmp_path):
    _plots_file(tmp_path / "plots.csv")
    r = _seatrack("track", "plots.csv", "-o", "t.csv", "--association", "mht", cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.startswith("error: --association")
    (tmp_path / "c.toml").write_text("m_of_n = [5, 2]\n")
    (tmp_path / "q.toml").write_text("[sensor]\nsigma_range_m = -1\n")
    for args, message in (
        (("--config", "c.toml"), "c.toml: m_of_n"),
        (("--method", "mm-rangerate"), "needs a range_rate_mps column"),
        (("--config", "q.toml"), "q.toml: sigma_range_m"),
    ):
        r = _seatrack("track", "plots.csv", "-o", "t.csv", *args, cwd=tmp_path)
        assert r.returncode == 2 and message in r.stderr, r.stderr
        assert len(r.stderr.splitlines()) == 1
    (tmp_path / "bad.csv").write_text("time_s,range_m,azimuth_deg\n0,100,10\n0,-1,10\n")
    r = _seatrack("track", "bad.csv", "-o", "t.csv", cwd=tmp_path)
    assert r.returncode == 2 and "bad.csv, line 3: range_m must be > 0" in r.stderr
    assert not (tmp_path / "t.csv").exists()
    assert "Traceback" not in r.stderr


def test_evaluate_multitarget_scenario(tmp_path):
    text = (
        "name = 'mt'\nduration_s = 60.0\nseed = 4\nruns = 1\n"
        "[multitarget]\ntargets = 4\nbirths_per_scan = 0.0\ncrossings = 1\n"
        "[[targets]]\nposition_m = [5000.0, 0.0]\ncourse_deg = 0.0\nspeed_kn = 10.0\n"
        "[[sensors]]\ntype = 'radar2d'\nsigma = { azimuth_deg = 0.3, range_m = 15.0 }\n"
        "p_detect = 0.9\nclutter_density = 5.0\nclutter_range_m = [500.0, 16000.0]\n"
        "scan_period_s = 2.5\nposition_m = [0.0, 0.0]\n"
    )
    (tmp_path / "mt.toml").write_text(text)
    r = _seatrack("evaluate", "mt.toml", "--csv", "mt.csv", "--plots", "pics", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "ekf + gnn" in r.stdout and "ekf + jpda" in r.stdout and "GOSPA" in r.stdout
    rows = _rows(tmp_path / "mt.csv")
    assert [x["tracker"] for x in rows] == ["ekf + gnn", "ekf + jpda"]
    assert float(rows[0]["gospa"]) < 200
    assert (tmp_path / "pics/multitarget_ekf_gnn.png").exists()


def test_simulate_a_multitarget_scenario_gives_unlabelled_plots(tmp_path):
    """``seatrack simulate coastal_multitarget``: plots without a track column (the tracker's
    input), the origin of every plot by line, and the truth of every target per scan."""
    r = _seatrack("simulate", "coastal_multitarget", "-o", "sim", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    plots, origin = (
        _rows(tmp_path / "sim/plots_radar.csv"),
        _rows(tmp_path / "sim/plot_origin_radar.csv"),
    )
    truth = _rows(tmp_path / "sim/truth.csv")
    assert "track" not in plots[0] and len(plots) == len(origin) > 1000
    assert [int(o["line"]) for o in origin] == list(range(2, len(plots) + 2))
    assert all(o["range_m"] == p["range_m"] and o["time_s"] == p["time_s"]
               for o, p in zip(origin, plots, strict=True))  # fmt: skip
    t = np.array([float(p["time_s"]) for p in plots])
    assert np.all(np.diff(t) >= 0)
    targets = {o["track"] for o in origin} - {"clutter"}
    assert targets <= {x["target"] for x in truth} and len(targets) >= 10
    assert 0.2 < np.mean([o["track"] == "clutter" for o in origin]) < 0.8
    cfg = tmp_path / "radar.toml"
    cfg.write_text("sigma_range_m = 15.0\nsigma_azimuth_deg = 0.3\n")
    r = _seatrack("track", "sim/plots_radar.csv", "--config", "radar.toml", "-o", "t.csv",
                  cwd=tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "multi-target (gnn)" in r.stdout
    assert len({x["track"] for x in _rows(tmp_path / "t.csv")}) >= len(targets) // 2


def test_tracker_keys_at_their_extremes_are_a_result_or_a_clear_error(tmp_path):
    """The multi-target tracker's numeric keys at 1e308 and 1e-308: exit 0 or a one-line
    error (max_speed_kn = 1e-308 made a zero speed variance and a division by zero in the
    turning filter's initiation before it had bounds)."""
    from seatrack.config import describe
    from seatrack.tracking.tracker import TrackerConfig

    _plots_file(tmp_path / "plots.csv")
    keys = [
        k
        for k, default, _, _ in describe(TrackerConfig)
        if isinstance(default, int | float) and not isinstance(default, bool)
    ]
    assert "max_speed_kn" in keys
    for key in keys:
        for value in ("1e308", "1e-308"):
            (tmp_path / "c.toml").write_text(f"{key} = {value}\n")
            r = _seatrack("track", "plots.csv", "-o", "t.csv", "--method", "turning",
                          "--config", "c.toml", cwd=tmp_path)  # fmt: skip
            assert r.returncode in (0, 2), (key, value, r.stderr)
            assert "internal error" not in r.stderr and "Traceback" not in r.stderr
