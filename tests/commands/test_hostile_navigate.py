"""Hostile inputs for `seatrack navigate` and `seatrack survey` (see hostile_inputs.py).

Every mutation of the map, echo and gyro files and of every option ends in exit status 0
(with a NAV.csv / MAP.csv that reads back with finite values) or 2 (one error line, the
previous output intact, no temporary left).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hostile_inputs import assert_clean
from hostile_inputs import mutated_csv
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st

from seatrack.io.landmarks import write_map_csv
from seatrack.io.navigation import NAV_COLUMNS
from seatrack.io.navigation import write_echoes
from seatrack.io.navigation import write_gyro
from seatrack.io.table import read_csv_table
from seatrack.simulate.radar_echoes import channel_landmarks
from seatrack.simulate.radar_echoes import river_route
from seatrack.simulate.radar_echoes import simulate_radar

PREVIOUS = b"previous output\n"


def nav_inputs(d: Path) -> str:
    """Write small valid inputs to ``d`` (echoes.csv: 1.2 s of echoes, ~200 rows; gyro.csv;
    map.csv: 8 landmarks); returns the matching ``--start``."""
    route = river_route(2000.0, 4.0)
    sim = simulate_radar(route, channel_landmarks(route, 8, np.random.default_rng(1)),
                         np.random.default_rng(2))  # fmt: skip
    e = sim.echoes
    keep = e.t <= 1.2
    write_echoes(d / "echoes.csv", e.t[keep], e.antenna[keep], e.range[keep], e.amplitude[keep])
    g = sim.gyro_t <= 3.0
    write_gyro(d / "gyro.csv", sim.gyro_t[g], sim.gyro_rate[g])
    write_map_csv(sim.nav_map, d / "map.csv")
    x0 = sim.truth[0]
    return f"{x0[0]:.1f},{x0[1]:.1f},{np.degrees(x0[2]):.2f},{np.hypot(x0[3], x0[4]):.2f}"


@pytest.fixture(scope="module")
def nav(tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    d = tmp_path_factory.mktemp("hostile_nav")
    start = nav_inputs(d)
    texts = {k: (d / f"{k}.csv").read_text() for k in ("echoes", "gyro", "map")}
    return {"dir": d, "start": start, "texts": texts}


def _files(nav: dict[str, object], which: str, data: bytes, sub: str) -> dict[str, Path]:
    d = nav["dir"] / sub  # type: ignore[operator]
    d.mkdir(exist_ok=True)
    paths = {}
    for k, text in nav["texts"].items():  # type: ignore[attr-defined]
        p = d / f"{k}.csv"
        p.write_bytes(data if k == which else text.encode())
        paths[k] = p
    return paths


def _check_output(path: Path, columns: list[str]) -> None:
    t = read_csv_table(path, columns)
    for c in columns:
        if t[c].dtype.kind == "f":
            assert np.all(np.isfinite(t[c])), c


def _command(cmd: str, nav: dict[str, object], paths: dict[str, Path], *extra: object) -> None:
    """Run navigate (NAV.csv out) or survey (MAP.csv out) and check the contract."""
    out = paths["echoes"].parent / f"{cmd}_out.csv"
    out.write_bytes(PREVIOUS)
    args = [cmd, "--map", paths["map"], "--echoes", paths["echoes"], "--gyro", paths["gyro"],
            "--start", nav["start"], "--out", out, *extra]  # fmt: skip
    before = snapshot([out])
    res = run_cli(*args)
    assert_clean(res, before, args)
    if res.code == 0:
        _check_output(out, list(NAV_COLUMNS) if cmd == "navigate" else ["x_m", "y_m"])


def _navigate(nav: dict[str, object], paths: dict[str, Path], *extra: object) -> None:
    _command("navigate", nav, paths, *extra)


def _survey(nav: dict[str, object], paths: dict[str, Path], *extra: object) -> None:
    _command("survey", nav, paths, *extra)


@settings(max_examples=80, deadline=None)
@given(data=st.data(), which=st.sampled_from(("echoes", "echoes", "gyro", "map")))
def test_navigate_mutated_files(nav, data, which):
    text = nav["texts"][which]
    _navigate(nav, _files(nav, which, data.draw(mutated_csv(text)), "nav_files"))


@settings(max_examples=40, deadline=None)
@given(data=st.data(), which=st.sampled_from(("echoes", "gyro", "map")))
def test_survey_mutated_files(nav, data, which):
    text = nav["texts"][which]
    _survey(nav, _files(nav, which, data.draw(mutated_csv(text)), "survey_files"))


NUMBERS = st.sampled_from(
    ["nan", "inf", "-inf", "1e308", "-1e308", "0", "-0", "-1", "1e-300", "abc", "", "2.5", "1e9"]
)
OPTIONS = ("--antenna-period", "--range-limit", "--antenna-offset", "--clutter-density")


@settings(max_examples=50, deadline=None)
@given(option=st.sampled_from(OPTIONS), value=NUMBERS, survey=st.booleans())
def test_numeric_options(nav, option, value, survey):
    paths = _files(nav, "", b"", "options")
    (_survey if survey else _navigate)(nav, paths, option, value)


@settings(max_examples=20, deadline=None)
@given(value=NUMBERS, drop=st.booleans())
def test_min_visibility(nav, value, drop):
    paths = _files(nav, "", b"", "minvis")
    _survey(nav, paths, "--min-visibility", value, *(["--drop-poor"] if drop else []))


@settings(max_examples=40, deadline=None)
@given(
    parts=st.lists(NUMBERS, min_size=0, max_size=5),
    origin=st.one_of(st.none(), st.lists(NUMBERS, min_size=1, max_size=3)),
)
def test_start_and_origin(nav, parts, origin):
    paths = _files(nav, "", b"", "start")
    out = paths["echoes"].parent / "nav_out.csv"
    out.write_bytes(PREVIOUS)
    args = ["navigate", "--map", paths["map"], "--echoes", paths["echoes"],
            "--start", ",".join(parts), "--out", out]  # fmt: skip
    if origin is not None:
        args += ["--origin", ",".join(origin)]
    before = snapshot([out])
    res = run_cli(*args)
    assert_clean(res, before, args)


def test_regressions_named_in_issue_13(nav, tmp_path):
    """1e308 as the last echo time (OverflowError), NaN antenna offset (no updates), NaN
    minimum visibility with --drop-poor (a map with 0 landmarks): all clean errors now."""
    e = tmp_path / "e.csv"
    e.write_text(nav["texts"]["echoes"] + "1e308,10.0,500.0,1.0\n")
    paths = {"map": nav["dir"] / "map.csv", "echoes": e, "gyro": nav["dir"] / "gyro.csv"}
    out = tmp_path / "o.csv"
    base = ["--map", paths["map"], "--echoes", e, "--start", nav["start"], "--out", out]
    r = run_cli("navigate", *base)
    assert r.code == 2 and "line" in r.err and "time_s = 1e308 must be in" in r.err
    base[3] = nav["dir"] / "echoes.csv"
    r = run_cli("navigate", *base, "--antenna-offset", "nan")
    assert r.code == 2 and r.err.startswith("error: --antenna-offset = nan is not a finite")
    r = run_cli("survey", *base, "--min-visibility", "nan", "--drop-poor")
    assert r.code == 2 and r.err.startswith("error: --min-visibility = nan is not a finite")
    # an echo log whose last time is far away: refused before allocating the filter cycles
    e.write_text(nav["texts"]["echoes"] + "4e9,10.0,500.0,1.0\n")
    base[3] = e
    r = run_cli("navigate", *base, "--antenna-period", "2.5")
    assert r.code == 2 and "filter cycles" in r.err


@pytest.mark.parametrize("case", ["directory", "under_a_file", "empty"])
def test_bad_output_paths_fail_before_any_work(nav, tmp_path, case):
    d = nav["dir"]
    f = tmp_path / "file"
    f.write_text("x")
    out = {"directory": tmp_path, "under_a_file": f / "nav.csv", "empty": ""}[case]
    for cmd in ("navigate", "survey"):
        r = run_cli(cmd, "--map", d / "map.csv", "--echoes", d / "echoes.csv",
                    "--start", nav["start"], "--out", out)  # fmt: skip
        assert r.code == 2 and r.err.startswith("error: ") and "Traceback" not in r.err
        assert f.read_text() == "x"
