"""Registry of the filters ``seatrack track --method NAME`` can run.

Each method is a function ``run(plots: PlotTrack, config: Mapping) -> dict[str, ndarray]``
returning output columns with one value per plot (the common ones ``x_m``, ``y_m``,
``z_m``, ``vx_mps``, ``vy_mps``, ``vz_mps``, ``std_x_m``, ``std_y_m``, ``std_z_m`` plus
method-specific ones). Methods are imported lazily by module path so that ``--help`` stays
fast and a method's dependencies load only when it runs.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

#: method name -> (module, function, one-line description)
METHODS: dict[str, tuple[str, str, str]] = {
    "ekf": ("seatrack.filters.ekf", "track_plots", "constant-velocity EKF on polar plots"),
}

COMMON_COLUMNS = (
    "x_m",
    "y_m",
    "z_m",
    "vx_mps",
    "vy_mps",
    "vz_mps",
    "std_x_m",
    "std_y_m",
    "std_z_m",
)


def get_method(name: str) -> Callable[[Any, Mapping[str, Any]], dict[str, np.ndarray]]:
    """Return the runner of method ``name`` (raises ValueError listing the known ones)."""
    if name not in METHODS:
        raise ValueError(f"unknown method {name!r}; choose one of {', '.join(sorted(METHODS))}")
    module, func, _ = METHODS[name]
    return getattr(importlib.import_module(module), func)  # type: ignore[no-any-return]
