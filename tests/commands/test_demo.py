"""`seatrack demo` end to end: every situation runs, the comparison is printed and written,
and the one-page report opens in headless Chromium with every figure decoded."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from browser import browse
from browser import chromium
from cli_inprocess import seatrack
from seatrack.commands.demo import SECTION_FILES
from seatrack.filters.registry import METHODS
from seatrack.report.demo import SECTIONS
from seatrack.report.demo import WHEN


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    out = tmp_path_factory.mktemp("demo") / "out"
    res = seatrack("demo", "--out", out, "--runs", "2", "--processes", "1")
    assert res.returncode == 0, res.stderr
    return {"out": out, "stdout": res.stdout}


def test_every_output_is_written(demo):
    out: Path = demo["out"]
    for k in SECTIONS:
        assert (out / f"{k}.png").stat().st_size > 10_000, k
    for f in (*SECTION_FILES, "data/plots_radar.csv", "data/truth.csv", "results.txt"):
        assert (out / f).stat().st_size > 0, f
    assert not [p for p in out.rglob(".*")]  # no temporaries left


def test_the_comparison_is_honest_and_teaches(demo):
    text = (demo["out"] / "results.txt").read_text()
    assert text == demo["stdout"].split("open ")[0]
    for title in ("Turns", "range rate", "Outliers", "Bearings only", "Landmark", "AIS", "Multi"):
        assert title in text
    # every tracking table ends with the oracle anchor, ratio 1.00 to itself
    assert text.count("best fixed q in hindsight") == 3
    for m in ("turning", "turning-spec", "robust-adaptive", "robust-adaptive-spec",
              "mm-rangerate", "mm-rangerate-spec"):  # fmt: skip
        assert f"use {m}: {WHEN[m]}" in text
    rows = re.findall(r"^  (\S+)\s+(defaults|target=\S+)\s+([\d.]+)\s+([\d.]+)$", text, re.M)
    assert len(rows) >= 15
    assert all(np.isfinite(float(v)) and float(v) > 0 for _, _, v, _ in rows)


def test_every_method_has_a_sentence():
    assert set(METHODS) <= set(WHEN)


def test_report_opens_in_headless_chromium(demo, tmp_path):
    exe = chromium()
    page = demo["out"] / "report.html"
    text = page.read_text(encoding="utf-8")
    assert 'src="data:image/png;base64,' in text and "http" not in text.split("<body")[0]
    dom = browse(exe, tmp_path / "p1", page.as_uri(), "--dump-dom").stdout
    body = dict(re.findall(r'data-([a-z]+)="([^"]*)"', re.search(r"<body([^>]*)>", dom).group(1)))
    assert body["sections"] == str(len(SECTIONS))
    assert body["images"] == str(len(SECTIONS))  # every inlined PNG decoded
    keys = re.findall(r'<section data-key="([a-z_]+)" data-rows="(\d+)"', dom)
    assert [k for k, _ in keys] == list(SECTIONS)
    assert dict(keys)["outliers"] == "9" and dict(keys)["turns"] == "6"
    shot = tmp_path / "shot.png"
    browse(exe, tmp_path / "p2", page.as_uri(), f"--screenshot={shot}", "--window-size=1200,900")
    from PIL import Image

    px = np.asarray(Image.open(shot).convert("L"), dtype=float)
    assert px.std() > 20  # text, tables and plots drawn, not a blank page


def _written_section(out: Path, runs: int) -> Any:
    from seatrack.io.atomic import atomic_write
    from seatrack.report.demo import Section

    with atomic_write(out / "turns.png", "wb") as fh:
        fh.write(b"new picture")
    return Section("turns", "t", "s", figure=out / "turns.png")


def _failing_section(out: Path, runs: int) -> Any:
    from seatrack.io.atomic import atomic_write

    with atomic_write(out / "data" / "plots_unlabelled.csv") as fh:
        fh.write("new\n")
    raise KeyboardInterrupt  # an interrupt once other outputs are written


@pytest.mark.parametrize("processes", ["1", "2"])
def test_a_failure_midway_keeps_every_previous_output(tmp_path, monkeypatch, processes):
    """All outputs of the demo are one transaction (sections in worker processes
    included): an interrupt in the last section keeps every previous file, leaves no
    temporary, and prints one line."""
    import seatrack.report.demo as demo_module

    monkeypatch.setattr(
        demo_module, "SECTIONS", {"turns": _written_section, "multitarget": _failing_section}
    )
    out = tmp_path / "out"
    (out / "data").mkdir(parents=True)
    previous = [out / "turns.png", out / "results.txt", out / "data" / "plots_radar.csv",
                out / "data" / "plots_unlabelled.csv"]  # fmt: skip
    for p in previous:
        p.write_text("previous\n")
    res = seatrack("demo", "--out", out, "--runs", "1", "--processes", processes)
    assert res.returncode != 0 and res.stderr.strip().splitlines() == ["error: interrupted"]
    assert [p.read_text() for p in previous] == ["previous\n"] * len(previous)
    assert not (out / "report.html").exists()
    assert not [p for p in out.rglob(".*")]  # no temporaries left
