"""Shared by the API tests: running docstring examples, a small plot table."""

from __future__ import annotations

import doctest
import importlib

import numpy as np


def run_examples(module: str) -> None:
    """Every example of ``module`` runs and prints what its docstring shows."""
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0


def labelled_plots() -> dict[str, np.ndarray]:
    """One track ``A`` of 20 plots, 2 s apart, moving out along 45 degrees."""
    t = np.arange(0.0, 40.0, 2.0)
    return {
        "track": np.array(["A"] * t.size),
        "time_s": t,
        "range_m": 5000.0 + 10.0 * t,
        "azimuth_deg": np.full(t.size, 45.0),
    }
