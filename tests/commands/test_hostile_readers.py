"""Every reader on mutated valid files: it returns, or raises InputError naming the file;
no other exception escapes (see hostile_inputs.py for the mutations)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from hostile_inputs import mutated_csv
from hostile_inputs import mutated_text
from hypothesis import Phase
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
from test_hostile_ais import CSV_TEXT
from test_hostile_ais import NMEA_TEXT
from test_hostile_navigate import nav_inputs
from test_hostile_simulate import SCENARIO
from test_hostile_tma import BEARINGS
from test_hostile_tma import SUPPORT
from test_hostile_track import PLOTS

from seatrack.io.ais import read_ais
from seatrack.io.landmarks import read_map_csv
from seatrack.io.navigation import read_echoes
from seatrack.io.navigation import read_gyro
from seatrack.io.plots import read_plots
from seatrack.io.table import InputError
from seatrack.io.tma import read_bearings
from seatrack.io.tma import read_support
from seatrack.simulate.files import read_truth
from seatrack.simulate.files import write_truth
from seatrack.simulate.scenarios import load_scenario
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import trajectory


@pytest.fixture(scope="module")
def texts(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    d = tmp_path_factory.mktemp("readers")
    nav_inputs(d)
    tr = trajectory([0, 0, 0], 0.5, 10.0, [Leg.straight(5), Leg.turn(0.5, 0.05)], dt=1.0)
    write_truth(d / "truth.csv", [("T1", tr)])
    out = {k: (d / f"{k}.csv").read_text() for k in ("echoes", "gyro", "map", "truth")}
    out["echoes"] = "".join(out["echoes"].splitlines(keepends=True)[:40])
    return out | {"plots": PLOTS, "bearings": BEARINGS, "support": SUPPORT, "ais": CSV_TEXT}


READERS: dict[str, Callable[[Path], object]] = {
    "echoes": read_echoes,
    "gyro": read_gyro,
    "map": read_map_csv,
    "truth": read_truth,
    "plots": read_plots,
    "bearings": read_bearings,
    "support": read_support,
    "ais": lambda p: read_ais([p]),
}


def _read(reader: Callable[[Path], object], path: Path) -> None:
    try:
        reader(path)
    except InputError as exc:
        assert str(exc).startswith(str(path)), str(exc)
        assert "\n" not in str(exc).strip()


@pytest.mark.parametrize("name", sorted(READERS))
def test_csv_readers(texts, tmp_path_factory, name):
    d = tmp_path_factory.mktemp(name)

    @settings(max_examples=60, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate))
    @given(data=st.data())
    def check(data: st.DataObject) -> None:
        p = d / f"{name}.csv"
        p.write_bytes(data.draw(mutated_csv(texts[name])))
        _read(READERS[name], p)

    check()


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_scenario_reader(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("toml") / "s.toml"
    p.write_bytes(data.draw(mutated_text(SCENARIO)))
    _read(load_scenario, p)


REP = """;; host track and sensor lines (Debrief REP)
100112 120000 OWN @A 60 00 00.00 N 000 00 00.00 E 90.0 10.0 0.0
100112 120100 OWN @A 60 00 00.00 N 000 01 00.00 E 90.0 10.0 0.0
100112 120200 OWN @A 60 00 30.00 N 000 02 00.00 E 45.0 10.0 0.0
;SENSOR: 100112 120000 OWN @A NULL 45.0 NULL S1 label
;SENSOR: 100112 120100 OWN @A 60 00 00.00 N 000 01 00.00 E 46.0 2000 S1 label
;SENSOR2: 100112 120130 OWN @A NULL 47.0 NULL 300.5 NULL TONAL_A label
;SENSOR3: 100112 120200 OWN @A NULL 48.0 0.5 301.0 0.2 NULL "TONAL B" a label
"""


@settings(max_examples=80, deadline=None)
@given(data=st.data())
def test_rep_reader(tmp_path_factory, data):
    from seatrack.io.rep import read_tma_files

    p = tmp_path_factory.mktemp("rep") / "a.rep"
    p.write_bytes(data.draw(mutated_text(REP)))
    _read(lambda q: read_tma_files([q]), p)


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_bearings_reader_with_measurement_columns(tmp_path_factory, data):
    from seatrack.io.tma import read_tma_input

    text = (
        "contact,time_s,bearing_deg,observer_x_m,observer_y_m,frequency_hz,tonal,atb_deg,range_m\n"
        "A,0,10,0,0,300.1,a,,\nA,0,,0,0,120.5,b,,\nA,60,11,60,0,300.2,a,30,\n"
        "A,120,12,120,0,,,,5000\nA,180,13,180,0,300.3,a,,\n"
    )
    p = tmp_path_factory.mktemp("mcsv") / "m.csv"
    p.write_bytes(data.draw(mutated_csv(text)))
    _read(read_tma_input, p)


@settings(max_examples=80, deadline=None)
@given(data=st.data())
def test_nmea_reader(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("nmea") / "log.nmea"
    p.write_bytes(data.draw(mutated_text(NMEA_TEXT)))
    _read(lambda q: read_ais([q]), p)


@pytest.mark.parametrize(
    ("name", "raw"),
    [("a.nmea", b"\x80"), ("a.csv", b"\xf8" + CSV_TEXT.encode()), ("b.csv", b"\xef\xbb\xbf\xf8")],
)
def test_ais_reader_on_bytes_that_are_not_utf8(tmp_path, name, raw):
    p = tmp_path / name
    p.write_bytes(raw)
    _read(lambda q: read_ais([q]), p)
