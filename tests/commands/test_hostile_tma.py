"""Hostile inputs for `seatrack tma` (see hostile_inputs.py).

The command belongs to another work package; these tests state the contract every command
meets: exit status 0 or 2, one error line, the previous RESULT.json intact on failure, no
temporary left, and on success a RESULT.json that is valid JSON (no NaN / Infinity).
"""

from __future__ import annotations

import json
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

from seatrack.geometry import bearing_rad_to_deg
from seatrack.simulate.tma import classic_scenario

HEADER = "contact,time_s,bearing_deg,observer_x_m,observer_y_m,sigma_deg"
SUPPORT = (
    "contact,kind,time_s,value,sigma,observer_x_m,observer_y_m\n"
    "A,range,600,9000,500,0,0\n"
    "A,speed,600,5,1,,\n"
)


def bearings_text(step: int = 8) -> str:
    """A valid BEARINGS.csv: contact A of the classic scenario, every ``step``-th bearing."""
    b = classic_scenario().bearings(np.random.default_rng(0))
    rows = [HEADER]
    for t, z, o in list(zip(b.t, b.bearing, b.observer, strict=True))[::step]:
        rows.append(f"A,{t:g},{bearing_rad_to_deg(z):.4f},{o[0]:.2f},{o[1]:.2f},1.5")
    return "\n".join(rows) + "\n"


BEARINGS = bearings_text()


def _strict_json(text: str) -> object:
    def refuse(c: str) -> None:
        raise ValueError(f"{c} is not JSON")

    return json.loads(text, parse_constant=refuse)


def _run(d: Path, bearings: bytes, support: bytes | None = None, *extra: object) -> None:
    b = d / "b.csv"
    b.write_bytes(bearings)
    out = d / "result.json"
    out.write_bytes(b"previous\n")
    args: list[object] = ["tma", b, "--out", out, *extra]
    if support is not None:
        s = d / "s.csv"
        s.write_bytes(support)
        args += ["--support", s]
    before = snapshot([out])
    res = run_cli(*args)
    assert_clean(res, before, args)
    if res.code == 0:
        _strict_json(out.read_text())


@settings(max_examples=80, deadline=None)
@given(data=st.data())
def test_mutated_bearings(tmp_path_factory, data):
    _run(tmp_path_factory.mktemp("tma"), data.draw(mutated_csv(BEARINGS)), None, "--no-detect")


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_mutated_support(tmp_path_factory, data):
    _run(tmp_path_factory.mktemp("tmasup"), BEARINGS.encode(), data.draw(mutated_csv(SUPPORT)),
         "--no-detect")  # fmt: skip


@settings(max_examples=40, deadline=None)
@given(
    option=st.sampled_from(["--sigma-deg", "--manoeuvres"]),
    value=st.sampled_from(
        ["nan", "inf", "0", "-1", "1e308", "abc", "", "600", "600,300", "1e-300"]
    ),
)
def test_options(tmp_path_factory, option, value):
    _run(tmp_path_factory.mktemp("tmaopt"), BEARINGS.encode(), None, option, value)


def test_result_json_is_valid_with_an_absurd_support_value(tmp_path):
    """Issue 13 item 7: a support sigma of 1e308 once gave "cost": Infinity."""
    _run(tmp_path, BEARINGS.encode(), SUPPORT.replace("9000,500", "9000,1e308").encode(),
         "--no-detect")  # fmt: skip


@pytest.mark.parametrize("option", ["--out", "--plot"])
@pytest.mark.parametrize("case", ["directory", "under_a_file"])
def test_bad_output_paths(tmp_path, option, case):
    f = tmp_path / "f"
    f.write_text("x")
    b = tmp_path / "b.csv"
    b.write_text(BEARINGS)
    out = {"directory": tmp_path, "under_a_file": f / "r.json"}[case]
    r = run_cli("tma", b, "--no-detect", option, out)
    assert r.code == 2 and r.err.startswith("error: ") and "Traceback" not in r.err
    assert f.read_text() == "x"
