"""BEARINGS.csv / SUPPORT.csv validation, RESULT.json fields and the `seatrack tma` command."""

import json
import math
import re
import subprocess
import sys

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from seatrack.commands.tma import register
from seatrack.geometry import bearing, bearing_rad_to_deg
from seatrack.io.table import InputError
from seatrack.simulate.tma import classic_scenario
from seatrack.io.tma import read_bearings, read_support

SC = classic_scenario()
HEADER = "contact,time_s,bearing_deg,observer_x_m,observer_y_m,sigma_deg\n"


def _write_bearings(path, contacts=("A",), rng_seed=0, no_turn=False):
    rng = np.random.default_rng(rng_seed)
    rows = [HEADER]
    for c in contacts:
        b = SC.bearings(rng)
        for t, z, o in zip(b.t, b.bearing, b.observer, strict=True):
            rows.append(f"{c},{t:g},{bearing_rad_to_deg(z):.4f},{o[0]:.2f},{o[1]:.2f},1.5\n")
    path.write_text("".join(rows))
    return path


def _app():
    app = typer.Typer()

    @app.callback()
    def main() -> None:  # a group, so the command is invoked by name
        pass

    register(app)
    return app


def test_read_bearings_round_trip(tmp_path):
    p = _write_bearings(tmp_path / "b.csv", ("A", "B"))
    got = read_bearings(p)
    assert list(got) == ["A", "B"]
    assert len(got["A"]) == 32
    assert np.allclose(got["A"].sigma, math.radians(1.5))


@pytest.mark.parametrize(
    "body, message",
    [
        ("1,0,10,0,0,1\n1,60,11,0,0,1\n1,30,12,0,0,1\n", "line 4: time_s = 30 is earlier"),
        ("1,0,10,0,0,1\n1,0,11,0,0,1\n", "line 3: duplicate time_s"),
        ("1,0,10,0,0,1\n1,60,nan,0,0,1\n", "line 3: column bearing_deg = 'nan' is not a finite"),
        ("1,0,10,0,0,1\n1,60,360,0,0,1\n", "line 3: bearing_deg = 360 is outside [0, 360)"),
        ("1,0,-1,0,0,1\n1,60,10,0,0,1\n", "line 2: bearing_deg = -1 is outside"),
        ("1,0,10,0,0,1\n", "line 2: contact '1' has a single bearing"),
        ("1,0,10,0,0,1\n1,60,11,0,0,0\n", "line 3: sigma_deg = 0 must be in (0, 180) degrees"),
        ("1,0,10,0,0,1\n1,60,11,0,0,180\n", "line 3: sigma_deg = 180 must be in (0, 180)"),
        ("1,0,10,0,0,1\n1,60,11,1e9,0,1\n", "line 3: observer_x_m = 1e+09 is implausible"),
        ("1,0,10,0,0,1\n1,1e11,11,0,0,1\n", "line 3: time_s = 1e+11 is implausible"),
        ("1,0,10,0,0,1\n1,60,inf,0,0,1\n", "line 3: column bearing_deg = 'inf' is not a finite"),
        ("1,0,10,0,0,1\n1,60,11,0,,1\n", "line 3: column observer_y_m is empty"),
    ],
)
def test_bad_bearings_name_the_row(tmp_path, body, message):
    p = tmp_path / "bad.csv"
    p.write_text(HEADER + body)
    with pytest.raises(InputError, match=re.escape(message)):
        read_bearings(p)


def test_missing_column(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("time_s,bearing_deg,observer_x_m\n0,1,2\n")
    with pytest.raises(InputError, match="missing required column.*observer_y_m"):
        read_bearings(p)


def test_support_file_validation(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text(
        "contact,kind,time_s,value,sigma,observer_x_m,observer_y_m\n"
        "A,range,100,5000,50,0,0\nA,speed,200,2.1,0.2,,\nA,course,300,220,5,,\n"
    )
    s = read_support(p)["A"]
    assert [v.kind for v in s] == ["range", "speed", "course"]
    assert math.isclose(s[2].value, math.radians(220)) and math.isclose(s[2].sigma, math.radians(5))
    for row, msg in [
        ("A,bogus,1,1,1,,", "line 2: kind = 'bogus'"),
        ("A,range,1,100,5,,", "line 2: a range support value needs observer_x_m"),
        ("A,speed,1,2,0,,", "line 2: sigma = 0 must be in (0, 1000] m/s"),
        ("A,course,1,400,5,,", "line 2: course value = 400 is outside"),
        ("A,range,1,1e308,5,0,0", "line 2: range value = 1e+308 must be in (0, 1e+08] m"),
        ("A,range,1,5000,1e300,0,0", "line 2: sigma = 1e+300 must be in (0, 1e+08] m"),
        ("A,range,1,5000,50,1e12,0", "line 2: observer position (1e+12, 0) is implausible"),
        ("A,speed,1,5000,1,,", "line 2: speed value = 5000 must be in (0, 1000] m/s"),
        ("A,speed,1,-2,1,,", "line 2: speed value = -2 must be in"),
        ("A,course,1,90,200,,", "line 2: sigma = 200 must be in (0, 180] deg"),
        ("A,course,1e12,90,2,,", "line 2: time_s = 1e+12 is implausible"),
        ("A,speed,1,nan,1,,", "line 2: column value = 'nan' is not a finite"),
    ]:
        p.write_text("contact,kind,time_s,value,sigma,observer_x_m,observer_y_m\n" + row + "\n")
        with pytest.raises(InputError, match=re.escape(msg)):
            read_support(p)


def test_cli_writes_result_json_and_plot(tmp_path):
    b = _write_bearings(tmp_path / "b.csv", ("A", "B"))
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
    b = _write_bearings(tmp_path / "b.csv")
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
