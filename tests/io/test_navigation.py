"""ECHOES.csv / GYRO.csv / NAV.csv: values checked with file and line, atomic writes."""

from __future__ import annotations

import os

import numpy as np
import pytest

from seatrack.io.navigation import read_echoes
from seatrack.io.navigation import read_gyro
from seatrack.io.navigation import write_echoes
from seatrack.io.navigation import write_gyro
from seatrack.io.table import InputError


def test_round_trip_and_atomic_write(tmp_path):
    p = tmp_path / "e.csv"
    write_echoes(p, [0.0, 0.1], np.radians([10.0, 20.0]), [500.0, 600.0], [3.0, 4.0])
    e = read_echoes(p)
    np.testing.assert_allclose(np.degrees(e.antenna), [10, 20], atol=1e-4)
    assert e.lines.tolist() == [2, 3] and os.listdir(tmp_path) == ["e.csv"]
    write_gyro(tmp_path / "g.csv", [0.0, 1.0], np.radians([0.5, -0.5]))
    t, w = read_gyro(tmp_path / "g.csv")
    np.testing.assert_allclose(np.degrees(w), [0.5, -0.5])


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("0,10,500\n1e308,10,500\n", "line 3: time_s = 1e308 must be in"),
        ("0,10,500\n1,10,1e9\n", "line 3: range_m = 1e9 must be in (0, 1e+08]"),
        ("0,10,500\n1,800,500\n", "line 3: antenna_deg = 800 must be in [-360, 720]"),
        ("0,10,500\n1,10,-0\n", "line 3: range_m = -0 must be in (0, 1e+08]"),
    ],
)
def test_echo_values_are_checked(tmp_path, text, message):
    p = tmp_path / "e.csv"
    p.write_text("time_s,antenna_deg,range_m\n" + text)
    with pytest.raises(InputError) as ei:
        read_echoes(p)
    assert str(ei.value).startswith(str(p)) and message in str(ei.value)


def test_gyro_values_are_checked(tmp_path):
    p = tmp_path / "g.csv"
    p.write_text("time_s,turn_rate_dps\n0,1\n1,5000\n")
    with pytest.raises(InputError, match="line 3: turn_rate_dps = 5000 must be in"):
        read_gyro(p)
