"""Registry of the filters ``seatrack track --method NAME`` can run.

Every method is a class honouring :class:`seatrack.filters.base.RecursiveFilter` with

* ``Config`` -- its frozen parameter dataclass (fields declared with
  :func:`seatrack.config.param`; each has ``initial_speed_sigma``, the velocity standard
  deviation of a new track);
* ``dims`` -- the plot dimensions it tracks in (``(2,)``: 3-D plots are tracked in the
  horizontal plane, :meth:`Plots.horizontal`);
* ``needs_range_rate`` (optional, default false);
* a constructor ``(config, sensor, d, range_rate)``.

:func:`build` turns a configuration table (a parsed TOML file: flat method keys plus the
sensor keys, flat or in a ``[sensor]`` table) into a ready :class:`Method`, :func:`run` runs
one over every labelled track of a set of plots, all tracks as one batch per step
(:func:`seatrack.filters.driver.run_tracks`; plots beyond a NIS of
:data:`~seatrack.filters.driver.GROSS_NIS` are rejected as gross errors, except by the
``-spec`` methods, which run as their sources describe). Methods are imported lazily by
module path so that ``--help`` stays fast.

The sensor section (:class:`~seatrack.filters.base.SensorNoise`) is shared by every
method with one documented default; so is the ``target`` key (``ship``, ``submarine``,
``aircraft``, ``fighter``: :mod:`seatrack.models.targets`), which gives every method the
process noise and manoeuvre parameters of the class (``Config.for_target``; keys given
beside it win). Without a target the methods built on the level IMM tune their process
noise online (:mod:`seatrack.filters.levels`); a method that has no use for a sensor key (e.g. range
rate in a method that ignores it) accepts and ignores it, so one configuration describing
the sensor drives any method.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.config import ConfigError
from seatrack.config import config_keys
from seatrack.config import parse_config
from seatrack.filters.base import COMMON_COLUMNS
from seatrack.filters.base import Plots
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import plot_gaussian
from seatrack.filters.driver import GROSS_NIS
from seatrack.filters.driver import run_tracks

if TYPE_CHECKING:
    from seatrack.models.targets import TargetClass

__all__ = [
    "METHODS",
    "COMMON_COLUMNS",
    "SENSOR_KEYS",
    "Method",
    "method_class",
    "split_config",
    "split_target",
    "TARGET_KEY",
    "build",
    "run",
    "track_index",
    "describe_method",
]

_LV = "seatrack.filters.levels"
_RT = "seatrack.filters.robust_track"
_MM = "seatrack.filters.multimodel"

#: method name -> (module, class, one-line description). A ``-spec`` name runs a method
#: exactly as its source describes; the name without it is the best version of the same
#: idea (docs/turning.md, docs/robust.md, docs/multimodel.md give the departures and the
#: evidence).
METHODS: dict[str, tuple[str, str, str]] = {
    "ekf": ("seatrack.filters.ekf", "EKF", "constant-velocity EKF on polar plots (fixed q)"),
    "imm": ("seatrack.filters.cvct_imm", "CVCTIMM", "standard IMM, CV + coordinated turn"),
    "turning": (
        "seatrack.filters.turning_imm",
        "TurningLevels",
        "turning-target filter: turn decision as a mode probability (level IMM), heading "
        "filter and fuzzy vote for the output",
    ),
    "turning-spec": (
        "seatrack.filters.turning",
        "Turning",
        "CN 104407337 as written: CV-EKF, Q raised by a fuzzy turn-rate vote",
    ),
    "robust": (_LV, "RamazanovLevels", "algorithm R's robust update in a level IMM, 2-D"),
    "robust-spec": (_RT, "Robust", "Ramazanov algorithm R as written (beam frame), 2-D"),
    "robust-adaptive": (
        _LV,
        "ContaminatedLevels",
        "robust and adaptive: level IMM with the exact contaminated-Gaussian update",
    ),
    "robust-adaptive-spec": (
        _RT,
        "RobustAdaptive",
        "Ramazanov algorithm A as written (beam frame, injected P/3, P/10), 2-D",
    ),
    "huber": (_LV, "HuberLevels", "Huber M-estimation update in a level IMM, 2-D"),
    "student-t": (_LV, "StudentTLevels", "VB Student-t update in a level IMM, 2-D"),
    "ekf-rb": (
        _RT,
        "RangeBearingEKF",
        "2-D range/bearing CV EKF with outlier diagnostics (baseline of robust)",
    ),
    "mm": (
        _LV,
        "LevelIMM",
        "multiple-model filter: IMM of process-noise levels (self-tuning), position only",
    ),
    "mm-spec": (
        _MM,
        "MultiModel",
        "Gholson & Moose bank as in JP H06-95138's prior art: 10 g hypotheses, position only",
    ),
    "mm-rangerate": (
        "seatrack.filters.cvct_imm",
        "RangeRateIMM",
        "multiple-model filter, range rate in the update (IMM: CV, CT, agile CV)",
    ),
    "mm-rangerate-spec": (
        _MM,
        "MultiModelRangeRate",
        "JP H06-95138 as written: reliabilities from position and range rate",
    ),
}

#: the key of the target class every method accepts (``ship``, ``submarine``, ...)
TARGET_KEY = "target"

#: the sensor keys every method accepts (flat or in a ``[sensor]`` table)
SENSOR_KEYS = tuple(k for k, name in config_keys(SensorNoise).items() if k != name)


def method_class(name: str) -> Any:
    """The class of method ``name`` (ValueError listing the known ones)."""
    if name not in METHODS:
        raise ValueError(f"unknown method {name!r}; choose one of {', '.join(sorted(METHODS))}")
    module, cls, _ = METHODS[name]
    return getattr(importlib.import_module(module), cls)


def split_config(
    table: Mapping[str, Any] | None, source: str = "config"
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Split a configuration table into ``(sensor keys, method keys)``.

    Sensor keys may be flat or in a ``[sensor]`` table, not both for the same key.
    """
    tab = dict(table or {})
    sensor = tab.pop("sensor", None)
    if sensor is not None and not isinstance(sensor, Mapping):
        raise ConfigError(f"{source}: sensor: expected a table, got {sensor!r}")
    out = dict(sensor or {})
    for key in SENSOR_KEYS:
        if key in tab:
            if key in out:
                raise ConfigError(f"{source}: {key} is given both flat and in [sensor]")
            out[key] = tab.pop(key)
    return out, tab


def split_target(
    table: Mapping[str, Any], source: str = "config"
) -> tuple[TargetClass | None, dict[str, Any]]:
    """The target class named by the ``target`` key (None without one) and the other keys.

    A class sets the method's process noise and manoeuvre parameters (each method's
    ``Config.for_target``); keys given beside it override the class's values.
    """
    from seatrack.models.targets import TARGET_CLASSES

    tab = dict(table)
    if TARGET_KEY not in tab:
        return None, tab
    value = tab.pop(TARGET_KEY)
    if not isinstance(value, str) or value not in TARGET_CLASSES:
        raise ConfigError(
            f"{source}: {TARGET_KEY}: must be one of {', '.join(TARGET_CLASSES)}, got {value!r}"
        )
    return TARGET_CLASSES[value], tab


@dataclass(frozen=True)
class Method:
    """A configured method: its filter and its initiator (plots -> Cartesian ``x, P``)."""

    name: str
    filter: RecursiveFilter
    initiate: Callable[[Plots], tuple[Any, Any]]
    horizontal: bool  #: plots are reduced to the horizontal plane before use

    def prepare(self, plots: Plots) -> Plots:
        """The plots as the filter takes them (2-D methods: horizontal)."""
        return plots.horizontal() if self.horizontal else plots


def build(
    name: str,
    table: Mapping[str, Any] | None = None,
    *,
    d: int = 2,
    range_rate: bool = False,
    source: str = "config",
) -> Method:
    """Configure method ``name`` from a configuration table for ``d``-D plots.

    Raises
    ------
    ConfigError
        Unknown key (listing the valid method and sensor keys), wrong type, bad value.
    ValueError
        Unknown method, or the plots lack a column the method needs.
    """
    cls = method_class(name)
    sensor_tab, method_tab = split_config(table, source)
    target, method_tab = split_target(method_tab, source)
    base = cls.Config.for_target(target) if target is not None else None
    try:
        cfg = parse_config(cls.Config, method_tab, source=source, base=base)
    except ConfigError as exc:
        if "unknown key" in str(exc):
            extra = ", ".join((*SENSOR_KEYS, TARGET_KEY))
            raise ConfigError(f"{exc}; sensor keys: {extra}") from None
        raise
    sensor = parse_config(SensorNoise, sensor_tab, source=source)
    if getattr(cls, "needs_range_rate", False) and not range_rate:
        raise ValueError(f"method {name} needs a range_rate_mps column in the plots")
    dd = d if d in cls.dims else max(cls.dims)
    flt = cls(cfg, sensor, dd, range_rate)
    speed = float(cfg.initial_speed_sigma)
    use_rr = bool(flt.range_rate)

    def initiate(p: Plots) -> tuple[Any, Any]:
        return plot_gaussian(p, sensor, speed, use_rr)

    return Method(name, flt, initiate, dd != d)


def track_index(labels: NDArray[Any]) -> tuple[NDArray[np.int64], list[str]]:
    """Track number ``0..T-1`` of each plot (in order of first appearance) and the labels."""
    names, first, inv = np.unique(labels, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    return rank[inv.reshape(-1)], [str(n) for n in names[order]]


def run(
    name: str, plots: Plots, table: Mapping[str, Any] | None = None, source: str = "config"
) -> dict[str, NDArray[Any]]:
    """Run method ``name`` over every labelled track of ``plots`` (one batch per step).

    Returns the output columns (one value per plot, input order):
    :data:`COMMON_COLUMNS`, ``status``, ``nis``, then the method's own columns.
    """
    labels = plots.track if plots.track is not None else np.zeros(len(plots), dtype=str)
    ti, _ = track_index(labels)
    m = build(name, table, d=plots.d, range_rate=plots.has_range_rate, source=source)
    gate = math.inf if name.endswith("-spec") else GROSS_NIS
    cols = run_tracks(m.filter, m.prepare(plots), ti, m.initiate, gate=gate)
    first = [*COMMON_COLUMNS, "status", "nis"]
    return {c: cols[c] for c in first} | {c: v for c, v in cols.items() if c not in first}


def describe_method(name: str) -> list[tuple[str, Any, str, str]]:
    """``(key, default, unit, doc)`` of a method's own keys (for docs and tests)."""
    from seatrack.config import describe

    return describe(method_class(name).Config)
