"""seatrack.evaluate: the docstring examples (the command's values: test_cli_equivalence)."""

from __future__ import annotations

from tests.api.examples import run_examples


def test_examples():
    run_examples("seatrack.api.evaluate")
