"""The README's "Python" section: each snippet at most 5 lines of code, and each runs."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _snippets() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_the_section_has_the_four_snippets():
    assert len(_snippets()) == 4


@pytest.mark.parametrize("index", range(4))
def test_snippet_runs_in_at_most_five_lines(index, tmp_path, capsys):
    code = _snippets()[index]
    lines = [ln for ln in code.splitlines() if ln.strip()]
    assert len(lines) <= 5, code
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        exec(compile(code, f"README.md snippet {index + 1}", "exec"), {})
    finally:
        os.chdir(old)
    assert capsys.readouterr().out.strip()  # every snippet prints its result
