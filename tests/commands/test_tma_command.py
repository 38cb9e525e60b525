"""The ``seatrack tma`` command: RESULT.json and plot, options validated, output paths checked
before any work, outputs written atomically, one-line errors with exit status 2."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import typer
from hypothesis import HealthCheck
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from seatrack import cli
from seatrack.commands.tma import register
from seatrack.geometry import bearing
from seatrack.geometry import bearing_rad_to_deg
from seatrack.io.table import InputError
from seatrack.simulate.tma import classic_scenario
from tma_samples import HEADER
from tma_samples import write_bearings

SC = classic_scenario()


def _app():
    app = typer.Typer()

    @app.callback()
    def main() -> None:  # a group, so the command is invoked by name
        pass

    register(app)
    return app


def _main(monkeypatch, capsys, *args):
    """Run the real entry point in-process: (exit status, stdout, stderr)."""
    monkeypatch.setattr(sys, "argv", ["seatrack", "tma", *map(str, args)])
    with pytest.raises(SystemExit) as exc:
        cli.main()
    out = capsys.readouterr()
    return exc.value.code, out.out, out.err


def test_cli_writes_result_json_and_plot(tmp_path):
    b = write_bearings(tmp_path / "b.csv", ("A", "B"))
    s = tmp_path / "s.csv"
    o = SC.observer.pos[-1, :2]
    s.write_text(
        f"contact,kind,time_s,value,sigma,observer_x_m,observer_y_m\nB,range,1860,2500,100,{o[0]},{o[1]}\n"
    )
    out, png = tmp_path / "r.json", tmp_path / "r.png"
    res = CliRunner().invoke(
        _app(),
        ["tma", str(b), "--support", str(s), "--no-detect", "--out", str(out), "--plot", str(png)],
    )
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert set(data) == {"A", "B"}
    a = data["A"]
    keys = ["t0_s", "x_m", "y_m", "vx_mps", "vy_mps", "legs", "covariance", "last", "iterations"]
    keys += ["converged", "observable", "condition_number", "residual_rms_deg"]
    for key in keys:
        assert key in a
    assert a["observable"] and a["converged"] and len(a["legs"]) == 1
    assert np.array(a["covariance"]).shape == (4, 4)
    keys = ["time_s", "x_m", "y_m", "range_m", "bearing_deg", "course_deg", "speed_mps"]
    keys += ["sigma_range_m", "sigma_bearing_deg", "sigma_course_deg", "sigma_speed_mps"]
    for key in keys:
        assert a["last"][key] is not None
    assert abs(a["x_m"] - 4920) < 1500 and data["B"]["n_support"] == 1
    assert png.stat().st_size > 10_000


def test_cli_unobservable_gives_nulls(tmp_path):
    p = tmp_path / "b.csv"
    rows = [HEADER] + [
        f"1,{60 * i},{bearing_rad_to_deg(bearing(5000 - 180.0 * i, 2000.0)):.5f},{180.0 * i},0,1\n"
        for i in range(20)
    ]
    p.write_text("".join(rows))
    res = CliRunner().invoke(_app(), ["tma", str(p), "--no-detect"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)["1"]
    assert d["observable"] is False
    assert d["last"]["range_m"] is None and d["last"]["sigma_range_m"] is None
    assert d["x_m"] is None and d["covariance"] is None
    assert d["last"]["bearing_deg"] is not None
    assert d["warnings"] and "not observable" in d["warnings"][0]


def test_cli_manoeuvres_option_and_errors(tmp_path):
    b = write_bearings(tmp_path / "b.csv")
    res = CliRunner().invoke(_app(), ["tma", str(b), "--manoeuvres", "900"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)["A"]
    assert [leg["start_s"] for leg in d["legs"]] == [0.0, 900.0] and not d["manoeuvres_detected"]
    res = CliRunner().invoke(_app(), ["tma", str(b), "--manoeuvres", "9x0"])
    assert isinstance(res.exception, InputError) and "9x0" in str(res.exception)


def test_console_error_is_one_line_with_exit_status_2(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text(HEADER + "1,0,10,0,0,1\n1,60,400,0,0,1\n")
    r = subprocess.run(
        [sys.executable, "-m", "seatrack.cli", "tma", str(p)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2
    assert r.stderr.startswith("error:") and "line 3" in r.stderr and "outside [0, 360)" in r.stderr


@pytest.mark.parametrize(
    "option, value, message",
    [
        ("--sigma-deg", "nan", "--sigma-deg must be a number of degrees in [1e-06, 180)"),
        ("--sigma-deg", "0", "--sigma-deg must be"),
        ("--sigma-deg", "200", "--sigma-deg must be"),
        ("--manoeuvres", "inf", "--manoeuvres: 'inf' is not a finite time"),
        ("--manoeuvres", "900,600", "--manoeuvres: times must be strictly increasing"),
        ("--manoeuvres", "5000", "--manoeuvres: 5000 s is not before the last bearing"),
        ("--manoeuvres", "-5", "--manoeuvres: -5 s is not after the first bearing"),
    ],
)
def test_options_are_validated(tmp_path, monkeypatch, capsys, option, value, message):
    b = write_bearings(tmp_path / "b.csv")
    code, out, err = _main(monkeypatch, capsys, b, option, value)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and message in err and len(err.strip().splitlines()) == 1


def test_bad_output_paths_fail_before_any_work(tmp_path, monkeypatch, capsys):
    b = write_bearings(tmp_path / "b.csv")
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("x")
    cases = [
        (["--out", tmp_path / "adir"], "is a directory"),
        (["--out", tmp_path / "afile" / "r.json"], "is a file"),
        (["--plot", tmp_path / "adir"], "is a directory"),
        (["--out", tmp_path / "r.png", "--plot", tmp_path / "r.png"], "the same file"),
    ]
    if os.geteuid() != 0:  # root writes anywhere
        ro = tmp_path / "ro"
        ro.mkdir(mode=0o500)
        cases.append((["--out", ro / "r.json"], "not writable"))
    for args, message in cases:
        code, out, err = _main(monkeypatch, capsys, b, *args)
        assert code == 2 and message in err, (args, err)
        assert err.startswith(f"error: {args[0]} {args[1]}") or "same file" in err
        assert out == ""  # nothing was computed or printed
    assert not (tmp_path / "r.json").exists()


def test_failed_run_leaves_the_previous_result_intact(tmp_path, monkeypatch, capsys):
    good = write_bearings(tmp_path / "b.csv")
    res = tmp_path / "r.json"
    code, out, _ = _main(monkeypatch, capsys, good, "--no-detect", "--out", res)
    assert code == 0 and "iterations" in out
    before = res.read_text()
    json.loads(before)
    bad = tmp_path / "bad.csv"
    bad.write_text(HEADER + "A,0,10,0,0,1\nA,60,11,0,0,1\nA,120,12,0,1e300,1\n")
    code, _, err = _main(monkeypatch, capsys, bad, "--out", res)
    assert code == 2 and "line 4" in err and "implausible" in err
    assert res.read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.csv", "bad.csv", "r.json"]


def test_stdout_result_is_strict_json_with_iteration_counts(tmp_path, monkeypatch, capsys):
    b = write_bearings(tmp_path / "b.csv")
    code, out, _ = _main(monkeypatch, capsys, b)  # default: leg detection

    def refuse(name):
        raise ValueError(name)

    d = json.loads(out, parse_constant=refuse)["A"]
    assert code == 0 and d["converged"] and d["observable"]
    assert d["iterations_total"] > d["iterations"] >= 2


_CELLS = ["", "nan", "inf", "-inf", "1e308", "-1e308", "abc", "0", "-1", "360", "1e11", "5"]


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    edits=st.lists(
        st.tuples(st.integers(1, 12), st.integers(0, 5), st.sampled_from(_CELLS)),
        min_size=1,
        max_size=3,
    )
)
def test_mutated_bearings_exit_0_or_2_never_a_traceback(tmp_path, monkeypatch, capsys, edits):
    """Property: a BEARINGS.csv with hostile cells either solves (strict JSON out) or stops
    with one `error: FILE, line N: ...` line and exit status 2."""
    rows = write_bearings(tmp_path / "ok.csv").read_text().splitlines()[:13]
    cells = [r.split(",") for r in rows]
    for line, col, value in edits:
        cells[line][col] = value
    p = tmp_path / "mut.csv"
    p.write_text("\n".join(",".join(c) for c in cells) + "\n")
    code, out, err = _main(monkeypatch, capsys, p, "--no-detect")
    assert code in (0, 2)
    if code == 0:
        json.loads(out, parse_constant=lambda name: pytest.fail(f"{name} in JSON"))
    else:
        assert err.startswith(f"error: {p}") and len(err.strip().splitlines()) == 1


_SUPPORT = (
    "contact,kind,time_s,value,sigma,observer_x_m,observer_y_m\n"
    "A,range,1860,2500,100,0,0\nA,speed,600,2.0,0.2,,\nA,course,900,220,5,,\n"
)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    edits=st.lists(
        st.tuples(
            st.integers(1, 3),
            st.integers(0, 6),
            st.sampled_from(_CELLS + ["range", "speed", "course", "bogus", "B"]),
        ),
        min_size=1,
        max_size=2,
    )
)
def test_mutated_support_exit_0_or_2_never_a_traceback(tmp_path, monkeypatch, capsys, edits):
    b = write_bearings(tmp_path / "b.csv")
    cells = [r.split(",") for r in _SUPPORT.splitlines()]
    for line, col, value in edits:
        cells[line][col] = value
    s = tmp_path / "s.csv"
    s.write_text("\n".join(",".join(c) for c in cells) + "\n")
    code, out, err = _main(monkeypatch, capsys, b, "--support", s, "--no-detect")
    assert code in (0, 2)
    if code == 0:
        json.loads(out, parse_constant=lambda name: pytest.fail(f"{name} in JSON"))
    else:
        assert err.startswith(f"error: {s}") and len(err.strip().splitlines()) == 1


DEBRIEF = "tests/data/debrief/"


def test_cli_debrief_rep_in_and_out(tmp_path):
    out, rep = tmp_path / "r.json", tmp_path / "sol.rep"
    res = CliRunner().invoke(
        _app(),
        ["tma", DEBRIEF + "Freq_BlueSensor.rep", DEBRIEF + "Freq_BlueTrack.rep",
         "--sigma-deg", "0.1", "--manoeuvres", "1263299850,1263303700",
         "--out", str(out), "--rep-out", str(rep)],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    d = json.loads(out.read_text())["SENSOR"]
    assert d["observable"] and d["base_frequencies"][0]["tonal"] == "NB_FREQ"
    assert abs(d["base_frequencies"][0]["f0_hz"] - 150.0) < 0.05
    assert [leg["start_s"] for leg in d["leg_estimates"]] == [1263297600, 1263299850, 1263303700]
    lines = rep.read_text().splitlines()
    assert lines[1].startswith("100112 120000.000 TMA_SENSOR @C ")
    assert len(lines) == 1 + 145  # every measurement time (the leg starts are among them)


def test_cli_frequency_options_validated(tmp_path, monkeypatch, capsys):
    b = write_bearings(tmp_path / "b.csv", ("A",))
    code, _, err = _main(monkeypatch, capsys, b, "--rep-out", tmp_path / "x.rep")
    assert code == 2 and "--rep-out needs REP input" in err
    code, _, err = _main(monkeypatch, capsys, b, "--base-frequency", "x=100")
    assert code == 2 and "tonal(s) x not in the input" in err
    code, _, err = _main(monkeypatch, capsys, b, "--sound-speed", "0")
    assert code == 2 and "--sound-speed must be a number of m/s in" in err
    code, _, err = _main(monkeypatch, capsys, b, DEBRIEF + "Freq_BlueTrack.rep")
    assert code == 2 and "mix of REP and CSV input" in err
