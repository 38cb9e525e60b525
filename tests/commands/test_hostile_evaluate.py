"""Hostile inputs for `seatrack evaluate` (see hostile_inputs.py): mutated scenarios and
options end in exit status 0 or 2 (one error line naming the file and key, or the option;
the previous --csv output intact, no temporary left)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest
from hostile_inputs import assert_clean
from hostile_inputs import mutated_text
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
from test_hostile_simulate import SCENARIO

#: the hostile scenario, shortened: mutations that keep it valid run a real evaluation
SHORT = SCENARIO.replace("duration_s = 20.0", "duration_s = 8.0")
FAST = ["--methods", "ekf", "--runs", "1", "--no-progress"]


def _run(d: Path, scenario: Path, *extra: object) -> None:
    out = d / "table.csv"
    out.write_bytes(b"previous\n")
    before = snapshot([out])
    args = ["evaluate", scenario, "--csv", out, *extra]
    res = run_cli(*args)
    assert_clean(res, before, args)
    if res.code == 0:
        with out.open(newline="") as fh:
            rows = list(csv.DictReader(fh))
        assert rows and all(r["method"] for r in rows)


@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_mutated_scenarios(tmp_path_factory, data):
    d = tmp_path_factory.mktemp("ev")
    sc = d / "scenario.toml"
    sc.write_bytes(data.draw(mutated_text(SHORT)))
    _run(d, sc, *FAST)


VALUES = ["-1", "0", "1", "3", "1000", "1e3", "abc", "", "99999999999999999999", "nan"]


@settings(max_examples=60, deadline=None)
@given(
    option=st.sampled_from(["--runs", "--processes", "--seed", "--skip"]),
    value=st.sampled_from(VALUES),
    methods=st.sampled_from(["ekf", "ekf,ekf", "nope", "", "all", ",", "mm-rangerate"]),
    sensor=st.sampled_from([None, "radar", "sonar", "nope", ""]),
)
def test_options(tmp_path_factory, option, value, methods, sensor):
    d = tmp_path_factory.mktemp("evopt")
    sc = d / "scenario.toml"
    sc.write_text(SHORT)
    args: list[object] = ["--no-progress", "--methods", methods, option, value]
    if option != "--runs":
        args += ["--runs", "1"]
    if option not in ("--runs", "--processes", "--skip") or value not in ("1000", "1e3"):
        if sensor is not None:
            args += ["--sensor", sensor]
    if methods in ("", "all", ","):  # every method on 1 run: keep it to fail-fast values
        args += ["--skip", "-1"]
    _run(d, sc, *args)


def test_regressions_named_in_issue_13(tmp_path):
    """A zero sigma (ZeroDivisionError), --skip 1000 (an empty table of NaN), a string for
    a method parameter (an internal float() message): clean errors naming key or option."""
    sc = tmp_path / "s.toml"
    sc.write_text(SHORT.replace("range_m = 20.0", "range_m = 0.0"))
    r = run_cli("evaluate", sc, *FAST)
    assert r.code == 2 and "sensors[0].sigma.range_m: must be > 0, got 0" in r.err
    sc.write_text(SHORT)
    r = run_cli("evaluate", sc, *FAST, "--skip", "1000")
    assert r.code == 2 and r.err.startswith("error: --skip = 1000 must be in [0, 4]")
    sc.write_text(SHORT.replace("q = 2.0", 'q = "abc"'))
    r = run_cli("evaluate", sc, *FAST)
    assert r.code == 2 and "s.toml: evaluate.ekf: q: expected a number, got 'abc'" in r.err
    assert "could not convert" not in r.err


def test_csv_and_plots_are_written_atomically(tmp_path):
    sc = tmp_path / "s.toml"
    sc.write_text(SHORT)
    out, plots = tmp_path / "t.csv", tmp_path / "plots"
    r = run_cli("evaluate", sc, *FAST, "--csv", out, "--plots", plots)
    assert r.code == 0, r.err
    assert sorted(p.name for p in plots.iterdir()) == ["anees.png", "pos_rmse.png"]
    rows = list(csv.DictReader(out.open()))
    assert [r["method"] for r in rows] == ["ekf"] and math.isfinite(float(rows[0]["pos_rmse_m"]))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plots", "s.toml", "t.csv"]


@pytest.mark.parametrize("option", ["--csv", "--plots"])
@pytest.mark.parametrize("case", ["directory", "under_a_file"])
def test_bad_output_paths_fail_before_any_work(tmp_path, option, case):
    sc = tmp_path / "s.toml"
    sc.write_text(SHORT)
    f = tmp_path / "f"
    f.write_text("x")
    out = {"directory": tmp_path if option == "--csv" else f, "under_a_file": f / "x"}[case]
    r = run_cli("evaluate", sc, *FAST, option, out)
    assert r.code == 2 and r.err.startswith("error: ") and "Traceback" not in r.err
    assert "ekf" not in r.out  # failed before the evaluation
