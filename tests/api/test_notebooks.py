"""The example notebooks (jupytext percent scripts in examples/notebooks) run to the end."""

from __future__ import annotations

import os
import runpy
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "examples" / "notebooks").glob("*.py"))


def test_there_are_four_notebooks():
    assert [p.stem for p in NOTEBOOKS] == [
        "ais_map",
        "multitarget_arrays",
        "tma_bearings",
        "track_plot_file",
    ]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path, tmp_path):
    assert path.read_text(encoding="utf-8").startswith("# ---\n# jupyter:\n#   jupytext:")
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        runpy.run_path(str(path), run_name="__main__")
    finally:
        os.chdir(old)
