"""The demo's text and page (seatrack.report.demo_page): tables, one sentence per method,
figures inlined, HTML escaped, written atomically."""

from __future__ import annotations

import base64
import math
import re

from seatrack.report.demo import WHEN
from seatrack.report.demo import Row
from seatrack.report.demo import Section
from seatrack.report.demo_page import demo_page
from seatrack.report.demo_page import demo_text
from seatrack.report.demo_page import write_demo_page
from seatrack.report.plots import save
from seatrack.report.plots import situation_figure


def _sections(tmp_path):
    import numpy as np

    t = np.arange(50.0)
    truth = np.stack([t * 10, t * 5], -1)
    png = save(situation_figure(truth, {"ekf": truth + 3}, truth, t, title="a <b>"),
               tmp_path / "a.png")  # fmt: skip
    rows = (Row("turning", "defaults", 10.0, 0.5), Row("ekf", "best <q>", 20.0, 1.0))
    a = Section("a", "Turns <&>", "why", rows, ("x < y",), png, 1.0, ("turning", "ekf"))
    b = Section("b", "TMA", "bearings", (Row("tma", "defaults", 5.0, math.nan),), (), None, 2.0,
                ("tma", "turning"))  # fmt: skip
    return [a, b], png


def test_text_lists_rows_and_each_sentence_once(tmp_path):
    secs, _ = _sections(tmp_path)
    text = demo_text(secs, 3.0)
    assert "turning" in text and "10.0" in text and "0.50" in text
    assert text.count(f"use turning: {WHEN['turning']}") == 1
    assert f"use tma: {WHEN['tma']}" in text and "demo total 3 s" in text


def test_page_inlines_figures_and_escapes(tmp_path):
    secs, png = _sections(tmp_path)
    page = demo_page(secs, 3.0, 4)
    data = re.search(r'data-figure="a" alt="a" src="data:image/png;base64,([^"]+)"', page)
    assert data and base64.b64decode(data.group(1)) == png.read_bytes()
    assert "Turns &lt;&amp;&gt;" in page and "best &lt;q&gt;" in page and "x &lt; y" in page
    assert 'data-sections="2"' in page and 'data-key="b" data-rows="1"' in page
    assert page.count(WHEN["turning"]) == 1
    assert (
        "<table>" in page.split('data-key="b"')[0]
        and "<table>" not in page.split('data-key="b"')[1]
    )


def test_written_atomically(tmp_path):
    secs, _ = _sections(tmp_path)
    p = write_demo_page(tmp_path / "r.html", secs, 1.0, 2)
    assert p.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert not [f for f in tmp_path.iterdir() if f.name.startswith(".")]
