"""CLI tests of `seatrack simulate`, `seatrack evaluate` and `seatrack demo` (its full run:
tests/commands/test_demo.py), and of clean user errors (message naming file and key/line,
exit status 2, no traceback)."""

import csv
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from seatrack.cli import app
from seatrack.cli import main
from seatrack.io.plots import read_plot_tracks
from seatrack.simulate.files import BEARING_COLUMNS
from seatrack.simulate.files import read_truth
from seatrack.simulate.scenarios import bundled_scenario
from seatrack.simulate.scenarios import load_scenario

runner = CliRunner()

BAD_SCENARIO = """
duration_s = 60.0
[[targets]]
position_m = [1000.0, 2000.0]
course_deg = 90.0
speed_kn = 10.0
legs = [
  { type = "straight", duration_s = 10.0 },
  { type = "turn", turn_rate_dps = "fast", duration_s = 5.0 },
]
[[sensors]]
type = "radar2d"
sigma = { azimuth_deg = 0.5, range_m = 10.0 }
scan_period_s = 2.0
"""


def _main(monkeypatch, capsys, *args):
    monkeypatch.setattr(sys, "argv", ["seatrack", *args])
    with pytest.raises(SystemExit) as exc:
        main()
    cap = capsys.readouterr()
    return exc.value.code, cap.out + cap.err


@pytest.mark.parametrize("cmd", ["simulate", "evaluate", "demo"])
def test_help(cmd):
    res = runner.invoke(app, [cmd, "--help"])
    assert res.exit_code == 0
    assert "Usage" in res.output and cmd in res.output


def test_help_texts_are_shown_as_written():
    """Square brackets in help texts are text, not markup (they were swallowed)."""
    res = runner.invoke(app, ["track", "--help"])
    assert res.exit_code == 0
    text = " ".join(res.output.split())
    assert "[elevation_deg], [range_rate_mps]" in text and "a [sensor] table" in text


def test_simulate_writes_csv_that_round_trips(tmp_path):
    res = runner.invoke(app, ["simulate", "demo", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    files = {p.name for p in tmp_path.iterdir()}
    assert {
        "plots_radar.csv",
        "bearings_sonar.csv",
        "clutter_radar.csv",
        "truth.csv",
        "ownship.csv",
    } <= files
    sc = load_scenario(bundled_scenario("demo"))
    sim = sc.simulate(np.random.default_rng(np.random.SeedSequence(sc.seed).spawn(1)[0]))
    tracks = read_plot_tracks(tmp_path / "plots_radar.csv")
    assert [t.label for t in tracks] == sc.target_names
    radar = sim.sensor("radar")
    for t, m in zip(tracks, radar.measurements, strict=True):
        det = m.detected
        np.testing.assert_array_equal(t.t, m.t[det])
        np.testing.assert_array_equal(t.range, m.z[det, 1])
        np.testing.assert_allclose(t.azimuth, m.z[det, 0], atol=1e-14)
        np.testing.assert_array_equal(t.range_rate, m.z[det, 2])
        np.testing.assert_array_equal(t.sensor, m.sensor_pos[det])
    with open(tmp_path / "bearings_sonar.csv") as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == BEARING_COLUMNS
    sonar = sim.sensor("sonar")
    assert len(rows) - 1 == sum(int(m.detected.sum()) for m in sonar.measurements)
    truth = read_truth(tmp_path / "truth.csv")
    np.testing.assert_array_equal(truth["T1"].pos, sim.targets[0].pos)
    own = read_truth(tmp_path / "ownship.csv")[""]
    np.testing.assert_array_equal(own.pos, sim.ownship.pos)


def test_simulate_run_and_seed_options(tmp_path):
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    assert (
        runner.invoke(app, ["simulate", "linear_cv", "--out", str(a), "--run", "2"]).exit_code == 0
    )
    assert (
        runner.invoke(app, ["simulate", "linear_cv", "--out", str(b), "--run", "2"]).exit_code == 0
    )
    assert (
        runner.invoke(app, ["simulate", "linear_cv", "--out", str(c), "--seed", "99"]).exit_code
        == 0
    )
    pa = (a / "plots_radar.csv").read_text()
    assert pa == (b / "plots_radar.csv").read_text()
    assert pa != (c / "plots_radar.csv").read_text()
    sc = load_scenario(bundled_scenario("linear_cv"))
    sim = sc.simulate(np.random.default_rng(np.random.SeedSequence(sc.seed).spawn(3)[2]))
    (t,) = read_plot_tracks(a / "plots_radar.csv")
    np.testing.assert_array_equal(t.range, sim.sensors[0].measurements[0].z[:, 1])


def _csv_rows(path):
    with open(path) as fh:
        return [{k: v for k, v in r.items() if k != "us_per_plot"} for r in csv.DictReader(fh)]


def test_evaluate_table_and_reproducibility(tmp_path):
    one, two = tmp_path / "one.csv", tmp_path / "two.csv"
    res = runner.invoke(
        app,
        [
            "evaluate",
            "linear_cv",
            "--runs",
            "4",
            "--methods",
            "ekf",
            "--no-progress",
            "--csv",
            str(one),
            "--plots",
            str(tmp_path / "plots"),
        ],
    )
    assert res.exit_code == 0, res.output
    assert "ekf" in res.output and "pos RMSE" in res.output and "ANEES" in res.output
    res2 = runner.invoke(
        app,
        [
            "evaluate",
            "linear_cv",
            "--runs",
            "4",
            "--methods",
            "ekf",
            "--no-progress",
            "--processes",
            "2",
            "--csv",
            str(two),
        ],
    )
    assert res2.exit_code == 0, res2.output
    assert (tmp_path / "plots" / "pos_rmse.png").stat().st_size > 0
    assert (tmp_path / "plots" / "anees.png").stat().st_size > 0
    assert "posterior CRB" in res.output  # linear_cv: constant-velocity target, Gaussian noise
    rows = _csv_rows(one)
    assert rows == _csv_rows(two)
    assert rows[0]["method"] == "ekf" and float(rows[0]["pos_rmse_m"]) > 0
    assert rows[0]["failures"] == "0"


def test_malformed_scenario_is_a_clean_error(tmp_path, monkeypatch, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(BAD_SCENARIO)
    code, out = _main(monkeypatch, capsys, "simulate", str(bad), "--out", str(tmp_path / "o"))
    assert code == 2
    assert "error:" in out and str(bad) in out and "targets[0].legs[1].turn_rate_dps" in out
    assert "expected a number" in out and "Traceback" not in out
    code, out = _main(monkeypatch, capsys, "evaluate", str(bad), "--runs", "2")
    assert code == 2 and "targets[0].legs[1].turn_rate_dps" in out and "Traceback" not in out
    syntax = tmp_path / "syntax.toml"
    syntax.write_text("duration_s = 60.0\nseed = = 1\n")
    code, out = _main(monkeypatch, capsys, "simulate", str(syntax))
    assert code == 2 and str(syntax) in out and "line 2" in out and "Traceback" not in out


def test_bad_options_are_clean_errors(monkeypatch, capsys, tmp_path):
    code, out = _main(
        monkeypatch, capsys, "evaluate", "linear_cv", "--methods", "nope", "--runs", "1"
    )
    assert code == 2 and "nope" in out and "Traceback" not in out
    code, out = _main(monkeypatch, capsys, "evaluate", "tma_classic", "--runs", "1")
    assert code == 2 and "no active sensor" in out and "Traceback" not in out
    code, out = _main(monkeypatch, capsys, "simulate", str(tmp_path / "missing.toml"))
    assert code == 2 and "missing.toml" in out and "not found" in out


def test_malformed_measurement_file_is_a_clean_error(monkeypatch, capsys, tmp_path):
    # a simulated PLOTS file with one corrupted row fed to `seatrack track`
    res = runner.invoke(app, ["simulate", "linear_cv", "--out", str(tmp_path)])
    assert res.exit_code == 0
    p = tmp_path / "plots_radar.csv"
    lines = p.read_text().splitlines()
    fields = lines[3].split(",")
    fields[2] = "-5.0"  # range_m
    lines[3] = ",".join(fields)
    p.write_text("\n".join(lines) + "\n")
    code, out = _main(
        monkeypatch, capsys, "track", str(p), "--method", "ekf", "--out", str(tmp_path / "T.csv")
    )
    assert code == 2
    assert str(p) in out and "line 4" in out and "range_m" in out and "Traceback" not in out


def test_real_entry_point_prints_no_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        BAD_SCENARIO.replace('"fast"', "1.0").replace('type = "radar2d"', 'type = "sonar9000"')
    )
    proc = subprocess.run(
        [sys.executable, "-m", "seatrack.cli", "simulate", str(bad)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert (
        "sensors[0].type" in proc.stderr and "sonar9000" in proc.stderr and str(bad) in proc.stderr
    )
    assert "Traceback" not in proc.stderr + proc.stdout
