"""seatrack.io.tma: BEARINGS.csv / SUPPORT.csv validation (file, line N), RESULT.json as
valid JSON, the console summary."""

import dataclasses
import json
import math
import re

import numpy as np
import pytest

from seatrack.io.table import InputError
from seatrack.io.tma import MeasurementDefaults
from seatrack.io.tma import apply_base_frequencies
from seatrack.io.tma import parse_tonal_values
from seatrack.io.tma import read_bearings
from seatrack.io.tma import read_support
from seatrack.io.tma import read_tma_input
from seatrack.io.tma import result_json
from seatrack.io.tma import solution_summary
from seatrack.io.tma import solution_to_dict
from seatrack.simulate.tma import classic_scenario
from seatrack.tma import Bearings
from seatrack.tma import TMAConfig
from seatrack.tma import solve
from seatrack.tma.measurements import Frequencies
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


EXTRA = (
    "contact,time_s,bearing_deg,observer_x_m,observer_y_m,frequency_hz,frequency_sigma_hz,"
    "tonal,atb_deg,range_m\n"
)


def _extras_file(tmp_path, body):
    p = tmp_path / "m.csv"
    p.write_text(EXTRA + body)
    return p


def test_read_measurement_columns(tmp_path):
    p = _extras_file(
        tmp_path,
        "A,0,10,0,0,300.1,,a,,\n"
        "A,0,,0,0,120.5,0.05,b,,\n"  # frequency-only row at the same time, another tonal
        "A,60,11,60,0,300.2,,a,30,\n"
        "A,120,12,120,0,,,,,5000\n",
    )
    got = read_tma_input(p, MeasurementDefaults(frequency=0.2))
    b = got.contacts["A"]
    assert b.t.tolist() == [0.0, 60.0, 120.0]
    fr = b.frequencies
    assert fr.tonal.tolist() == ["a", "b", "a"] and fr.sigma.tolist() == [0.2, 0.05, 0.2]
    assert np.allclose(fr.observer_velocity, [[1.0, 0.0]] * 3)  # differenced own-ship track
    assert b.bow_angles.angle[0] == pytest.approx(math.radians(30))
    (r,) = got.support["A"]
    assert r.kind == "range" and r.value == 5000 and r.observer == (120.0, 0.0)


def test_plain_bearings_file_reads_as_before(tmp_path):
    p = write_bearings(tmp_path / "b.csv", ("A",))
    got = read_tma_input(p)
    assert got.support == {} and got.contacts["A"].frequencies is None
    assert np.array_equal(got.contacts["A"].bearing, read_bearings(p)["A"].bearing)


@pytest.mark.parametrize(
    "body, message",
    [
        ("A,0,10,0,0,-1,,,,\nA,60,11,0,0,,,,,\n", "line 2: frequency_hz = -1 must be in (0"),
        ("A,0,10,0,0,300,0,,,\nA,60,11,0,0,,,,,\n", "line 2: frequency_sigma_hz = 0 must be"),
        ("A,0,10,0,0,,,,400,\nA,60,11,0,0,,,,,\n", "line 2: atb_deg = 400 is outside"),
        ("A,0,10,0,0,,,,,-5\nA,60,11,0,0,,,,,\n", "line 2: range_m = -5 must be in"),
        ("A,0,10,0,0,,,,,\nA,60,,0,0,,,,,\n", "line 3: the row holds no measurement"),
        ("A,0,10,0,0,,0.1,,,\nA,60,11,0,0,,,,,\n", "line 2: frequency_sigma_hz is given without"),
        ("A,0,,0,0,300,,,,\nA,60,11,0,0,,,,,\nA,90,12,0,0,,,,,\n", "line 2: a measurement before"),
        ("A,0,10,0,0,,,,,\nA,60,,0,0,300,,,,\n", "contact 'A' has 1 bearing(s)"),
        ("A,0,10,0,0,,,,,\nA,0,11,0,0,,,,,\n", "line 3: duplicate time_s"),
    ],
)
def test_bad_measurement_columns_name_the_row(tmp_path, body, message):
    with pytest.raises(InputError, match=re.escape(message)):
        read_tma_input(_extras_file(tmp_path, body))


def test_tonal_options_and_base_frequencies():
    assert parse_tonal_values(["a=150.5", "0.2"], "--x", "Hz", True) == (0.2, {"a": 150.5})
    for bad in (["a=-1"], ["a=x"], ["a=1", "a=2"], ["=3"]):
        with pytest.raises(InputError, match="--x"):
            parse_tonal_values(bad, "--x", "Hz")
    with pytest.raises(InputError, match="is not TONAL=HZ"):
        parse_tonal_values(["3"], "--x", "Hz")
    t = np.arange(3.0)
    obs = np.zeros((3, 2))
    fr = Frequencies(t, np.full(3, 100.0), obs, obs, 0.1, np.array(["a", "a", "b"]))
    got = apply_base_frequencies({"A": Bearings(t, t, obs, frequencies=fr)}, {"b": 99.5})
    assert got["A"].frequencies.base_frequency == {"b": 99.5}
    with pytest.raises(InputError, match="tonal\\(s\\) c not in the input"):
        apply_base_frequencies({"A": Bearings(t, t, obs, frequencies=fr)}, {"c": 1.0})


def test_result_json_with_frequencies():
    r = np.random.default_rng(4)
    b = dataclasses.replace(SC.bearings(r), frequencies=SC.frequencies(r, 200.0, 0.05))
    sol = solve(b, manoeuvres=None)
    d = json.loads(result_json({"A": sol}))["A"]
    (f,) = d["base_frequencies"]
    assert f["tonal"] == "1" and abs(f["f0_hz"] - 200.0) < 4 * f["sigma_f0_hz"]
    assert set(d["nis"]) == {"bearing", "frequency"} and d["nis"]["frequency"]["rows"] == 32
    assert len(d["residuals"]["frequency_hz"]) == 32
    assert d["leg_estimates"][0]["range_m"] == pytest.approx(sol.last.range)
    assert all(d["determined"].values())
