"""Registry of the filters ``seatrack track --method NAME`` can run.

Each method is a function ``run(plots: PlotTrack, config: Mapping) -> dict[str, ndarray]``
returning output columns with one value per plot (the common ones ``x_m``, ``y_m``,
``z_m``, ``vx_mps``, ``vy_mps``, ``vz_mps``, ``std_x_m``, ``std_y_m``, ``std_z_m`` plus
method-specific ones). Methods are imported lazily by module path so that ``--help`` stays
fast and a method's dependencies load only when it runs.

Every method accepts the measurement-noise keys of :data:`COMMON_CONFIG_KEYS` in its
configuration (ignoring those it has no use for), so one configuration describing the
sensor drives any method; method-specific keys are documented by each runner.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

#: method name -> (module, function, one-line description)
METHODS: dict[str, tuple[str, str, str]] = {
    "ekf": ("seatrack.filters.ekf", "track_plots", "constant-velocity EKF on polar plots"),
    "robust": (
        "seatrack.filters.robust",
        "track_plots_robust",
        "Ramazanov robust beam-frame filter (algorithm R), 2-D range/bearing",
    ),
    "robust-adaptive": (
        "seatrack.filters.robust",
        "track_plots_robust_adaptive",
        "Ramazanov adaptive-robust beam-frame filter (algorithm A), 2-D range/bearing",
    ),
    "huber": (
        "seatrack.filters.robust_baselines",
        "track_plots_huber",
        "Huber M-estimation EKF (IRLS), 2-D range/bearing",
    ),
    "student-t": (
        "seatrack.filters.robust_baselines",
        "track_plots_student_t",
        "variational-Bayes Student-t EKF, 2-D range/bearing",
    ),
    "ekf-rb": (
        "seatrack.filters.robust_baselines",
        "track_plots_ekf",
        "2-D range/bearing CV EKF with outlier diagnostics (baseline of robust)",
    ),
    "turning": (
        "seatrack.filters.turning",
        "track_plots",
        "turning-target CV-EKF, Q raised by a fuzzy turn-rate vote (CN 104407337)",
    ),
    "mm-rangerate": (
        "seatrack.filters.multimodel",
        "track_plots_rangerate",
        "multiple-model filter, reliabilities from position and range rate (JP H06-95138)",
    ),
    "mm": (
        "seatrack.filters.multimodel",
        "track_plots_position",
        "multiple-model filter, position-only reliabilities (Gholson & Moose prior art)",
    ),
    "imm": (
        "seatrack.filters.multimodel",
        "track_plots_imm",
        "standard IMM, CV + coordinated turn",
    ),
}

#: configuration keys every method accepts (and uses where it has such a measurement):
#: the measurement noise of the plots, in the units the names say
COMMON_CONFIG_KEYS = (
    "sigma_range_m",
    "sigma_azimuth_deg",
    "sigma_elevation_deg",
    "sigma_range_rate_mps",
)

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
