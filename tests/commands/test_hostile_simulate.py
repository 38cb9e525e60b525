"""Hostile inputs for `seatrack simulate` (see hostile_inputs.py): mutated scenario TOML
files and options end in exit status 0 (every file read back) or 2 (one error line naming
the file and key or the option; the previous files intact, no temporary left)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile_inputs import assert_clean
from hostile_inputs import mutated_text
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st

from seatrack.io.plots import read_plots
from seatrack.simulate.files import read_truth

#: a short scenario using every part of the format (two targets with legs, a radar with
#: clutter and range rate, a passive sonar, a fixed sensor, method parameters)
SCENARIO = """\
name = "hostile"
duration_s = 20.0
dt_s = 1.0
seed = 3
runs = 2

[ownship]
position_m = [0.0, 0.0]
course_deg = 30.0
speed_kn = 8.0
legs = [
  { type = "straight", duration_s = 5.0 },
  { type = "turn", turn_rate_dps = 2.0, angle_deg = 20.0 },
]

[[targets]]
name = "T1"
position_m = [3000.0, 4000.0]
course_deg = 200.0
speed_kn = 12.0
[[targets.legs]]
type = "speed_change"
to_speed_kn = 15.0
accel_mps2 = 0.5
[[targets.legs]]
type = "turn"
g = 0.2
angle_deg = -30.0

[[targets]]
name = "T2"
position_m = [-2000.0, 5000.0, 100.0]
course_deg = 90.0
speed_mps = 5.0

[[sensors]]
name = "radar"
type = "radar2d"
components = ["azimuth", "range", "range_rate"]
sigma = { azimuth_deg = 0.3, range_m = 20.0, range_rate_mps = 1.0 }
epsilon = 0.05
outlier_scale = 10.0
p_detect = 0.9
clutter_density = 2.0
clutter_range_m = [100.0, 8000.0]
scan_period_s = 2.0

[[sensors]]
name = "sonar"
type = "passive_sonar"
sigma = { azimuth_deg = 1.0 }
scan_period_s = 4.0
position_m = [100.0, 100.0]

[evaluate.ekf]
q = 2.0
"""

FILES = ("plots_radar.csv", "clutter_radar.csv", "bearings_sonar.csv", "truth.csv", "ownship.csv")


def _run(folder: Path, scenario: Path, *extra: object) -> None:
    folder.mkdir(exist_ok=True)
    outs = [folder / f for f in FILES]
    for p in outs:
        p.write_bytes(b"previous\n")
    before = snapshot(outs)
    args = ["simulate", scenario, "--out", folder, *extra]
    res = run_cli(*args)
    assert_clean(res, before, args)
    if res.code == 0:
        for line in res.out.splitlines():
            assert line.startswith("wrote ")
        plots = folder / "plots_radar.csv"
        if plots.read_bytes() != b"previous\n" and "T1" in plots.read_text():
            read_plots(plots)
        truth = folder / "truth.csv"
        if truth.read_bytes() != b"previous\n":
            read_truth(truth)


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_mutated_scenarios(tmp_path_factory, data):
    d = tmp_path_factory.mktemp("sim")
    sc = d / "scenario.toml"
    sc.write_bytes(data.draw(mutated_text(SCENARIO)))
    _run(d / "out", sc)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.sampled_from(["-1", "0", "5", "abc", "1e3", "99999999999999999999999", ""]),
    run=st.sampled_from(["-1", "0", "3", "100000", "10000000000000", "x", "1.5"]),
)
def test_seed_and_run_options(tmp_path_factory, seed, run):
    d = tmp_path_factory.mktemp("simopt")
    sc = d / "scenario.toml"
    sc.write_text(SCENARIO)
    _run(d / "out", sc, "--seed", seed, "--run", run)


def test_regressions_named_in_issue_13(tmp_path):
    """duration 1e7 s / scan period 1e-6 s ran 70 s into a MemoryError; now refused at once."""
    for old, new, key in (
        ("duration_s = 20.0", "duration_s = 1e7", "scans; at most"),
        ("scan_period_s = 2.0", "scan_period_s = 1e-6", "scans; at most"),
        ("range_m = 20.0", "range_m = 0.0", "must be > 0, got 0"),
        ("q = 2.0", 'q = "abc"', None),
    ):
        sc = tmp_path / "s.toml"
        sc.write_text(SCENARIO.replace(old, new))
        r = run_cli("simulate", sc, "--out", tmp_path / "o")
        if key is None:  # a method parameter is checked by `evaluate`, not by `simulate`
            assert r.code == 0
        else:
            assert r.code == 2 and key in r.err and str(sc) in r.err


@pytest.mark.parametrize("case", ["file", "under_a_file", "file_is_a_folder"])
def test_bad_output_folders(tmp_path, case):
    sc = tmp_path / "s.toml"
    sc.write_text(SCENARIO)
    f = tmp_path / "f"
    f.write_text("x")
    out = f if case != "under_a_file" else f / "sub"
    if case == "file_is_a_folder":
        out = tmp_path / "o"
        (out / "truth.csv").mkdir(parents=True)
    r = run_cli("simulate", sc, "--out", out)
    assert r.code == 2 and r.err.startswith("error: ") and "Traceback" not in r.err
    assert f.read_text() == "x"
    assert not (tmp_path / "o" / "plots_radar.csv").exists()  # nothing written before failing
