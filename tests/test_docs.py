"""The documentation follows the code: every registered method, configuration key, sensor
key and target class is where the docs say it is, with the numbers the code holds.

Fails when a method, key or class is added, renamed or removed without its page.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from seatrack.config import describe
from seatrack.filters.base import SensorNoise
from seatrack.filters.registry import METHODS
from seatrack.filters.registry import TARGET_KEY
from seatrack.filters.registry import describe_method
from seatrack.filters.registry import methods_table
from seatrack.models.targets import TARGET_CLASSES

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _read(name: str) -> str:
    return (DOCS / name).read_text(encoding="utf-8")


def _ticked(text: str) -> set[str]:
    """Every name written in backticks."""
    return set(re.findall(r"`([^`\n]+)`", text))


def _table(text: str, heading: str) -> list[list[str]]:
    """The cells of the first Markdown table after ``heading`` (header row first)."""
    section = text[text.index(heading) :]
    rows = []
    for line in section.splitlines()[1:]:
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not set("".join(cells)) <= set("-: "):
                rows.append(cells)
        elif rows:
            break
    return rows


@pytest.mark.parametrize("page", ["docs/architecture.md", "README.md"])
def test_the_methods_table_is_the_registry_s(page):
    """The methods tables are generated from the records: the page holds the table
    regenerated now, and it lists every method with its class."""
    table = methods_table()
    assert table in (ROOT / page).read_text(encoding="utf-8"), f"{page}: regenerate the table"
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in table.splitlines()[2:]]
    assert [r[0].strip("`") for r in rows] == list(METHODS)
    for row in rows:
        assert row[2] == f"`{METHODS[row[0].strip('`')].path.removeprefix('seatrack.')}`"


@pytest.mark.parametrize("page", ["defaults.md", "../README.md"])
def test_every_method_is_named(page):
    names = _ticked((DOCS / page).read_text(encoding="utf-8"))
    missing = [m for m in METHODS if m not in names]
    assert not missing, f"{page} does not name {missing}"


def test_every_spec_method_is_on_its_source_page():
    pages = {"turning": "turning.md", "robust": "robust.md", "mm": "multimodel.md"}
    for name in METHODS:
        if name.endswith("-spec"):
            page = next(p for k, p in pages.items() if name.startswith(k))
            assert f"`{name}`" in _read(page), (name, page)


@pytest.mark.parametrize("method", list(METHODS))
def test_every_configuration_key_is_documented(method):
    page = METHODS[method].docs
    names = _ticked(_read(page))
    missing = [key for key, *_ in describe_method(method) if key not in names]
    assert not missing, f"{page} lacks keys of {method}: {missing}"


@pytest.mark.parametrize("page", ["defaults.md", "formats.md", "../README.md"])
def test_sensor_keys_and_their_one_default(page):
    text = (DOCS / page).read_text(encoding="utf-8")
    assert f"`{TARGET_KEY}`" in text or f"{TARGET_KEY} =" in text
    for key, default, _, _ in describe(SensorNoise):
        hit = re.search(rf"`{key}`[^0-9\n]*?([0-9.]+)", text)
        assert hit, f"{page}: no default given for {key}"
        assert float(hit.group(1)) == pytest.approx(default), (page, key)


def _numbers(cell: str) -> list[float]:
    """The numbers of a table cell, in order, outside brackets (``6.17 / 15.4 (12 kn)``)."""
    return [float(v) for v in re.findall(r"\d+(?:\.\d+)?", re.sub(r"\(.*?\)", "", cell))]


def _close(doc: float, value: float) -> bool:
    """``doc`` is ``value`` as written with 2-3 significant digits."""
    return math.isclose(doc, value, rel_tol=0.006, abs_tol=1e-9)


def test_target_classes_table_matches_the_code():
    rows = _table(_read("defaults.md"), "## Target classes")
    header = [h.strip("`") for h in rows[0][1:]]
    assert header == list(TARGET_CLASSES)
    deg = 180.0 / math.pi
    fields = {
        "speed typical / max, m/s": lambda c: (c.speed_typical, c.speed_max),
        "steady random acceleration": lambda c: (c.accel_steady,),
        "manoeuvre acceleration typical": lambda c: (c.accel_typical, c.accel_max),
        "tangential acceleration": lambda c: (c.accel_tangential,),
        "turn rate typical / max, deg/s": lambda c: (
            c.turn_rate_typical * deg,
            c.turn_rate_max * deg,
        ),
        "manoeuvre time": lambda c: (c.manoeuvre_time,),
        "time between manoeuvres": lambda c: (c.straight_time,),
        "turn onset": lambda c: (c.turn_onset_time,),
        "Singer $P_{max}$": lambda c: (c.p_max_accel,),
    }
    seen = set()
    for row in rows[1:]:
        label = next((f for f in fields if row[0].startswith(f)), None)
        if label is None:
            continue
        seen.add(label)
        for cell, tc in zip(row[1:], TARGET_CLASSES.values(), strict=True):
            want = fields[label](tc)
            got = _numbers(cell)[: len(want)]
            assert len(got) == len(want) and all(map(_close, got, want)), (label, tc.name, cell)
    assert seen == set(fields)


def test_docs_index_links_every_page():
    index = _read("README.md")
    for page in sorted(DOCS.glob("*.md")):
        if page.name != "README.md":
            assert f"({page.name})" in index, page.name
    assert "(docs/defaults.md)" in (ROOT / "README.md").read_text(encoding="utf-8")
