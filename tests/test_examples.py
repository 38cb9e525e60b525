"""The scripts under ``examples/`` run, and their files drive the commands the README shows.

Each script writes next to itself, so it runs from a copy in a temporary folder (the
repository's own files are not touched). ``make_navigation_example.py`` had been broken
by a module move without any test noticing.
"""

from __future__ import annotations

import re
import runpy
import shutil
from pathlib import Path

import pytest

from cli_inprocess import seatrack

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _run_copy(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    script = tmp_path / name
    shutil.copy(EXAMPLES / name, script)
    runpy.run_path(str(script), run_name="__main__")
    return capsys.readouterr().out


def test_navigation_example_feeds_seatrack_navigate(tmp_path, capsys):
    out = _run_copy("make_navigation_example.py", tmp_path, capsys)
    start = re.search(r'--start "([^"]+)"', out)
    assert start is not None, out
    for f in ("river_map.csv", "river_echoes.csv", "river_gyro.csv"):
        assert (tmp_path / f).stat().st_size > 0
    r = seatrack("navigate", "--map", "river_map.csv", "--echoes", "river_echoes.csv",
                 "--gyro", "river_gyro.csv", "--start", start.group(1), "--out", "nav.csv",
                 cwd=tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert len((tmp_path / "nav.csv").read_text().splitlines()) > 100


def test_tma_example_feeds_seatrack_tma(tmp_path, capsys):
    _run_copy("make_tma_example.py", tmp_path, capsys)
    r = seatrack("tma", "tma_bearings.csv", "--support", "tma_support.csv", "-o", "r.json",
                 cwd=tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    # the bundled files are what the script writes (seeded)
    for f in ("tma_bearings.csv", "tma_support.csv"):
        assert (tmp_path / f).read_text() == (EXAMPLES / f).read_text()
