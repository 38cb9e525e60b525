"""Hostile options and output folders for `seatrack demo`: refused at once with one error
line naming the option or path, before anything is simulated or written. (A full demo run
is tested in test_cli_foundation.py; its atomic outputs in test_hostile_atomic.py.)"""

from __future__ import annotations

import pytest
from hostile_inputs import assert_clean
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st

BAD_COUNTS = ["0", "-1", "abc", "", "1e3", "nan", "100001", "99999999999999999999"]


@settings(max_examples=40, deadline=None)
@given(option=st.sampled_from(["--runs", "--processes"]), value=st.sampled_from(BAD_COUNTS))
def test_bad_counts(tmp_path_factory, option, value):
    d = tmp_path_factory.mktemp("demo")
    marker = d / "out" / "results.txt"
    marker.parent.mkdir()
    marker.write_text("previous\n")
    args = ["demo", "--out", d / "out", option, value]
    res = run_cli(*args)
    assert res.code == 2, res
    assert_clean(res, snapshot([marker]), args)
    assert sorted(p.name for p in (d / "out").iterdir()) == ["results.txt"]


@pytest.mark.parametrize("case", ["file", "under_a_file", "data_is_a_file", "png_is_a_folder"])
def test_bad_output_folders(tmp_path, case):
    f = tmp_path / "f"
    f.write_text("x")
    out = {"file": f, "under_a_file": f / "demo"}.get(case, tmp_path / "demo")
    if case == "data_is_a_file":
        out.mkdir()
        (out / "data").write_text("x")
    if case == "png_is_a_folder":
        (out / "turns.png").mkdir(parents=True)
    r = run_cli("demo", "--out", out, "--runs", "1")
    assert r.code == 2 and r.err.startswith("error: ") and "Traceback" not in r.err, r
    assert str(out) in r.err
    assert f.read_text() == "x"
    assert not (tmp_path / "demo" / "data" / "truth.csv").exists()  # nothing simulated
