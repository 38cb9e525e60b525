"""seatrack.io.rep: Debrief REP track and sensor lines (the project's public sample and
hand-written lines), NULL sensor positions from the host track, errors with file and line,
the REP track writer read back."""

import math
import re
from datetime import UTC
from datetime import datetime

import numpy as np
import pytest

from seatrack.io.rep import YARD_M
from seatrack.io.rep import read_rep
from seatrack.io.rep import read_tma_files
from seatrack.io.rep import rep_tma_input
from seatrack.io.rep import rep_track_text
from seatrack.io.table import InputError
from seatrack.io.tma import MeasurementDefaults
from seatrack.tma import solve

DATA = "tests/data/debrief/"
SENSOR, BLUE, RED = (DATA + f for f in ("Freq_BlueSensor.rep", "Freq_BlueTrack.rep",
                                        "Freq_RedTrack.rep"))  # fmt: skip
T0 = datetime(2010, 1, 12, 12, 0, 0, tzinfo=UTC).timestamp()


def test_debrief_sample_tracks_and_cuts():
    data = read_rep([SENSOR, BLUE, RED])
    assert set(data.tracks) == {"SENSOR", "SUBJECT"}
    own = data.tracks["SENSOR"]
    assert len(own.time_s) == 145  # the repeated first fix is kept once
    assert own.time_s[0] == T0 and own.time_s[-1] == T0 + 7200
    assert own.lat_deg[0] == pytest.approx(60.2) and own.lon_deg[0] == pytest.approx(0.2)
    assert math.degrees(own.course[0]) == pytest.approx(40.0)
    assert own.speed_mps[0] == pytest.approx(12 * 1852 / 3600)
    assert data.tracks["SUBJECT"].lon_deg[1] == pytest.approx(-9.64 / 3600)  # West
    assert len(data.cuts) == 290
    brg = [c for c in data.cuts if c.sensor == "NB_BRG"]
    frq = [c for c in data.cuts if c.sensor == "NB_FREQ"]
    assert math.degrees(brg[0].bearing) == pytest.approx(360 - 153.5)
    assert math.isnan(brg[0].range_m)  # a range of 0000 yd is no range
    assert frq[0].frequency_hz == 149.589 and math.isnan(frq[0].lat_deg)


def test_null_position_is_the_host_track_interpolated(tmp_path):
    p = tmp_path / "a.rep"
    p.write_text(
        "100112 120000 OWN @A 60 00 00.00 N 000 00 00.00 E 90.0 10.0 0.0\n"
        "100112 120100 OWN @A 60 00 00.00 N 000 01 00.00 E 90.0 10.0 0.0\n"
        ";SENSOR: 100112 120000 OWN @A NULL 45.0 NULL S1 label\n"
        ";SENSOR: 100112 120030 OWN @A NULL 46.0 2000 S1 label\n"
        ";SENSOR2: 100112 120030 OWN @A NULL NULL NULL 300.5 NULL TONAL_A label\n"
        ';SENSOR3: 100112 120045 OWN @A NULL NULL NULL 301.0 0.2 NULL "TONAL B" a label\n'
    )
    inp, frame = rep_tma_input(read_rep([p]))
    b = inp.contacts["OWN"]
    mid = frame.to_local(np.array([60.0]), np.array([0.5 / 60]))[0]
    assert np.allclose(b.observer[1], mid, atol=0.05)  # halfway between the fixes
    assert b.frequencies is not None
    assert b.frequencies.tonals == ["TONAL_A", "TONAL B"]
    assert b.frequencies.sigma.tolist() == [0.1, 0.2]  # default, then the line's accuracy
    v = b.frequencies.observer_velocity[0]
    assert np.hypot(*v) == pytest.approx(10 * 1852 / 3600)
    (rng,) = inp.support["OWN"]
    assert rng.value == pytest.approx(2000 * YARD_M)
    # bearings turned into the plane by the meridian convergence at the sensor
    gam = frame.convergence(np.array([60.0]), np.array([0.0]))[0]
    assert b.bearing[0] == pytest.approx(math.radians(45.0) + gam)


def test_hemisphere_joined_to_longitude(tmp_path):
    p = tmp_path / "a.rep"
    p.write_text("100112 120000 OWN @A 50 30 00.00 S000 15 00.00 W 10.0 3.0 0.0\n")
    tr = read_rep([p]).tracks["OWN"]
    assert tr.lat_deg[0] == pytest.approx(-50.5) and tr.lon_deg[0] == pytest.approx(-0.25)


@pytest.mark.parametrize(
    "line, message",
    [
        ("100112 120000 OWN @A 60 00 00.00 N 000 00 00.00 E 90.0 fast 0.0", "speed 'fast'"),
        ("10011 120000 OWN @A 60 00 00.00 N 000 00 00.00 E 90.0 1.0 0.0", "date/time 10011"),
        ("100112 120000 OWN @A 60 00 00.00 X 000 00 00.00 E 90.0 1.0 0.0", "not a valid"),
        ("100112 120000 OWN @A 60 00", "needs date, time"),
        (";SENSOR2: 100112 120000 OWN @A NULL NULL NULL -3 NULL S l", "frequency -3 Hz"),
        (";SENSOR: 100112 120000 OWN @A NULL NULL NULL S l", "holds no bearing"),
        (";SENSOR3: 100112 120000 OWN @A NULL 10 0 NULL NULL NULL S l", "accuracy must be"),
        (";SENSOR: 100112 120000 OWN", "too few fields"),
    ],
)
def test_bad_lines_name_file_and_line(tmp_path, line, message):
    p = tmp_path / "bad.rep"
    p.write_text(";; comment\n" + line + "\n")
    with pytest.raises(
        InputError, match=re.escape("bad.rep, line 2: ") + ".*" + re.escape(message)
    ):
        read_rep([p])


def test_sensor_outside_its_host_track_is_rejected(tmp_path):
    p = tmp_path / "a.rep"
    p.write_text(
        "100112 120000 OWN @A 60 00 00.00 N 000 00 00.00 E 90.0 10.0 0.0\n"
        "100112 120100 OWN @A 60 00 00.00 N 000 01 00.00 E 90.0 10.0 0.0\n"
        ";SENSOR: 100112 120200 OWN @A NULL 45.0 NULL S1 label\n"
    )
    with pytest.raises(InputError, match=r"a.rep, line 3: the sensor time is outside"):
        rep_tma_input(read_rep([p]))
    only_sensor = tmp_path / "s.rep"
    only_sensor.write_text(";SENSOR: 100112 120000 HOST @A NULL 45.0 NULL S1 label\n")
    with pytest.raises(InputError, match=r"s.rep, line 1: host track 'HOST' is not in"):
        read_tma_files([only_sensor])


def test_written_track_reads_back(tmp_path):
    inp, frame = read_tma_files([SENSOR, BLUE], MeasurementDefaults(bearing=math.radians(0.1)))
    b = inp.contacts["SENSOR"]
    sol = solve(b, manoeuvres=[b.t[0] + 2250.0, b.t[0] + 6100.0])
    p = tmp_path / "sol.rep"
    p.write_text(rep_track_text(sol, frame, b.t, "TMA SOL"))
    back = read_rep([p]).tracks["TMA SOL"]
    assert back.time_s == sorted(set(b.t.tolist()))
    xy = frame.to_local(np.array(back.lat_deg), np.array(back.lon_deg))
    assert np.abs(xy - sol.position_at(b.t)).max() < 0.5  # DMS to 0.01 s of arc
    v = sol.state.reshape(-1, 2)[-1]
    assert back.speed_mps[-1] == pytest.approx(np.hypot(*v), abs=0.01)
