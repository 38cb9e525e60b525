"""seatrack.io.tma: BEARINGS.csv / SUPPORT.csv validation (file, line N), RESULT.json as
valid JSON, the console summary."""

import dataclasses
import json
import math
import re

import numpy as np
import pytest

from seatrack.io.table import InputError
from seatrack.io.tma import read_bearings
from seatrack.io.tma import read_support
from seatrack.io.tma import result_json
from seatrack.io.tma import solution_summary
from seatrack.io.tma import solution_to_dict
from seatrack.simulate.tma import classic_scenario
from seatrack.tma import TMAConfig
from seatrack.tma import solve
from tma_samples import HEADER
from tma_samples import write_bearings

SC = classic_scenario()


def test_read_bearings_round_trip(tmp_path):
    p = write_bearings(tmp_path / "b.csv", ("A", "B"))
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
        ("1,0,10,0,0,1\n1,60,11,0,0,0\n", "line 3: sigma_deg = 0 must be in [1e-06, 180) degrees"),
        ("1,0,10,0,0,1\n1,60,11,0,0,180\n", "line 3: sigma_deg = 180 must be in [1e-06, 180)"),
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


def _strict_json(text):
    """json.loads that refuses NaN / Infinity (which Python's json would accept)."""

    def refuse(name):
        raise ValueError(f"not valid JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_result_json_is_always_valid_json():
    b = SC.bearings(np.random.default_rng(1))
    sol = solve(b, sigma=SC.sigma)
    broken = dataclasses.replace(
        sol, cost=math.inf, condition_number=math.nan, residual_rms=math.inf
    )
    doc = _strict_json(result_json({"A": sol, "B": broken}))
    assert doc["A"]["cost"] == pytest.approx(sol.cost)
    assert doc["B"]["cost"] is None and doc["B"]["condition_number"] is None
    assert doc["B"]["residual_rms_deg"] is None
    assert doc["A"]["iterations_total"] > doc["A"]["iterations"] >= 2


def test_not_converged_and_unobservable_have_no_operator_numbers():
    b = SC.bearings(np.random.default_rng(4))
    far = np.array([0.0, 60_000.0, -10.0, 10.0])
    s = solve(b, sigma=SC.sigma, initial=far, config=TMAConfig(max_iterations=2))
    assert not s.converged
    d = solution_to_dict(s)
    assert d["converged"] is False and d["x_m"] is None and d["covariance"] is None
    for key in ("range_m", "sigma_range_m", "course_deg", "speed_mps", "ellipse"):
        assert d["last"][key] is None
    assert d["last"]["bearing_deg"] is not None
    ok = solve(b, sigma=SC.sigma)
    for bad in (s, dataclasses.replace(ok, converged=False)):
        line = solution_summary("A", bad)
        assert "NOT " in line and " m," not in line and "+/-" not in line
    assert "NOT CONVERGED" in solution_summary("A", dataclasses.replace(ok, converged=False))
    assert "+/-" in solution_summary("A", ok) and "iterations" in solution_summary("A", ok)
