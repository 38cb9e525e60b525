"""Registry of the filters ``seatrack track --method NAME`` can run: one
:class:`MethodRecord` per method (its class, one-line description, when to use it, the
automatic process-noise rule of the multi-target tracker, the docs page of its keys and its
group: ``default``, ``baseline`` or ``reference`` -- a source reproduced as written). The
``--method`` help, ``seatrack track --list-methods``, the demo's advice, the rows of
``seatrack evaluate`` and the methods tables of the docs are all generated from
:data:`METHODS`: the records of ``seatrack/data/methods.toml`` (one table per method), to
which :func:`register` adds a method at run time.

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
import tomllib
from collections.abc import Callable
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from typing import TYPE_CHECKING
from typing import Any
from typing import cast

import numpy as np
from numpy.typing import NDArray

from seatrack.config import ConfigError
from seatrack.config import config_keys
from seatrack.config import parse_config
from seatrack.errors import InputError
from seatrack.filters.base import COMMON_COLUMNS
from seatrack.filters.base import Plots
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import plot_gaussian
from seatrack.filters.driver import GROSS_NIS
from seatrack.filters.driver import run_tracks
from seatrack.progress import Progress

if TYPE_CHECKING:
    from seatrack.models.targets import TargetClass

__all__ = [
    "METHODS",
    "GROUPS",
    "NOISE_RULES",
    "MethodRecord",
    "register",
    "record",
    "names",
    "method_help",
    "read_records",
    "METHODS_FILE",
    "list_methods",
    "methods_table",
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


#: groups of methods: what a user picks, the baselines they are measured against, and the
#: reproductions of source documents as written (``NAME-spec``; listed apart)
GROUPS = ("default", "baseline", "reference")
#: automatic process-noise rules of :func:`seatrack.tracking.auto.per_track_filter`
NOISE_RULES = ("levels", "wrap", "own")


@dataclass(frozen=True)
class MethodRecord:
    """One registered method: everything the tools and the docs say about it.

    Attributes
    ----------
    name : the ``--method`` name
    module, class_name : where its class lives (imported on first use)
    description : one line: what it is
    when : one sentence: when to use it (the demo's advice)
    noise : automatic process-noise rule of the multi-target tracker when the user sets no
        noise key (:func:`seatrack.tracking.auto.per_track_filter`): ``"levels"`` (its
        ``q`` is the straight-leg level inside the two-level IMM), ``"wrap"`` (its defaults
        wrapped in that IMM) or ``"own"`` (its defaults, untouched)
    docs : the page of ``docs/`` that documents its configuration keys
    group : ``"default"``, ``"baseline"`` or ``"reference"`` (a source as written)
    """

    name: str
    module: str
    class_name: str
    description: str
    when: str
    noise: str = "own"
    docs: str = "architecture.md"
    group: str = "default"

    def __post_init__(self) -> None:
        if self.group not in GROUPS:
            raise ValueError(f"group: must be one of {', '.join(GROUPS)}, got {self.group!r}")
        if self.noise not in NOISE_RULES:
            raise ValueError(f"noise: must be one of {', '.join(NOISE_RULES)}, got {self.noise!r}")
        if not self.name or any(c.isspace() for c in self.name):
            raise ValueError(f"name: a word without spaces, got {self.name!r}")

    @property
    def path(self) -> str:
        """``package.module.Class``."""
        return f"{self.module}.{self.class_name}"

    def load(self) -> Any:
        """The method's class."""
        return getattr(importlib.import_module(self.module), self.class_name)

    @property
    def config(self) -> type:
        """The method's configuration dataclass (``Class.Config``)."""
        return cast(type, self.load().Config)


#: the data file of the package's methods (``seatrack/data/methods.toml``)
METHODS_FILE = "methods.toml"
_FIELDS = {"module": "module", "class": "class_name", "description": "description",
           "when": "when", "noise": "noise", "docs": "docs", "group": "group"}  # fmt: skip


def read_records(text: str, source: str = METHODS_FILE) -> list[MethodRecord]:
    """The method records of a TOML text: one table per method, keys ``module``,
    ``class``, ``description``, ``when``, ``noise``, ``docs``, ``group`` (all required).

    Raises
    ------
    ConfigError
        Invalid TOML, a missing or unknown key, a bad group or noise rule.
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    out = []
    for name, tab in doc.items():
        keys = set(tab) if isinstance(tab, dict) else set()
        if keys != set(_FIELDS):
            missing, extra = sorted(set(_FIELDS) - keys), sorted(keys - set(_FIELDS))
            raise ConfigError(f"{source}: [{name}]: missing keys {missing}, unknown {extra}")
        try:
            out.append(MethodRecord(name, **{_FIELDS[k]: str(v) for k, v in tab.items()}))
        except ValueError as exc:
            raise ConfigError(f"{source}: [{name}]: {exc}") from None
    return out


def _package_records() -> list[MethodRecord]:
    text = (resources.files("seatrack") / "data" / METHODS_FILE).read_text("utf-8")
    return read_records(text)


#: every registered method by name (registration order: the order of ``seatrack evaluate``
#: rows and of the docs tables); :func:`register` adds one
METHODS: dict[str, MethodRecord] = {r.name: r for r in _package_records()}


def register(record: MethodRecord, *, replace: bool = False) -> MethodRecord:
    """Add a method to the registry: from then on ``seatrack track --method NAME``,
    :func:`build`, :func:`run`, the multi-target tracker and the listings take it.

    Raises
    ------
    ValueError
        The name is taken (unless ``replace``).
    """
    if record.name in METHODS and not replace:
        raise ValueError(f"method {record.name!r} is registered already")
    METHODS[record.name] = record
    return record


def record(name: str) -> MethodRecord:
    """The registry's record of method ``name`` (ValueError listing the known ones)."""
    if name not in METHODS:
        raise ValueError(f"unknown method {name!r}; choose one of {', '.join(sorted(METHODS))}")
    return METHODS[name]


def names(group: str | None = None) -> list[str]:
    """The registered names (of one group), in registration order."""
    return [n for n, r in METHODS.items() if group is None or r.group == group]


def method_help() -> str:
    """The help text of ``--method``: the methods to pick, then the baselines and the
    reproductions of the sources by name."""
    main = ", ".join(f"{n} ({METHODS[n].description})" for n in names("default"))
    return (
        f"filter: {main}; baselines: {', '.join(names('baseline'))}; sources as written: "
        f"{', '.join(names('reference'))} (seatrack track --list-methods)"
    )


def list_methods() -> str:
    """Every method, grouped (the reproductions of the sources apart), one line each:
    name, what it is and when to use it."""
    titles = {
        "default": "methods",
        "baseline": "baselines",
        "reference": "sources as written (reproductions, for comparison)",
    }
    blocks = []
    for g in GROUPS:
        group = names(g)
        if not group:
            continue
        width = max(len(n) for n in group)
        block = [f"{titles[g]}:"]
        for n in group:
            block.append(f"  {n:<{width}}  {METHODS[n].description}")
            block.append(f"  {'':<{width}}  use: {METHODS[n].when}")
        blocks.append("\n".join(block))
    return "\n\n".join(blocks)


def methods_table() -> str:
    """The Markdown table of every method (docs/architecture.md and the README carry it
    verbatim; a test regenerates it)."""
    rows = ["| name | group | class | what it is | keys in |", "|---|---|---|---|---|"]
    for n, r in METHODS.items():
        cls = r.path.removeprefix("seatrack.")
        rows.append(f"| `{n}` | {r.group} | `{cls}` | {r.description} | docs/{r.docs} |")
    return "\n".join(rows) + "\n"


#: the key of the target class every method accepts (``ship``, ``submarine``, ...)
TARGET_KEY = "target"

#: the sensor keys every method accepts (flat or in a ``[sensor]`` table)
SENSOR_KEYS = tuple(k for k, name in config_keys(SensorNoise).items() if k != name)


def method_class(name: str) -> Any:
    """The class of method ``name`` (ValueError listing the known ones)."""
    return record(name).load()


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


def check_range_rate(name: str, has_range_rate: bool, where: str) -> None:
    """Refuse plots without range rate for a method that needs it (``where``: the file).

    Raises
    ------
    InputError
        ``WHERE: method NAME needs a range_rate_mps column in the plots``.
    """
    if getattr(method_class(name), "needs_range_rate", False) and not has_range_rate:
        raise InputError(f"{where}: method {name} needs a range_rate_mps column in the plots")


def track_index(labels: NDArray[Any]) -> tuple[NDArray[np.int64], list[str]]:
    """Track number ``0..T-1`` of each plot (in order of first appearance) and the labels.

    ``labels`` are text (a fixed-width or an object array, :func:`compact_labels`); one
    hashing pass (pyarrow's dictionary encoding), no sort of the texts."""
    import pyarrow as pa
    import pyarrow.compute as pc

    values = np.asarray(labels).ravel()
    if values.size == 0:
        return np.zeros(0, np.int64), []
    try:
        enc = pc.dictionary_encode(pa.array(values))
    except (pa.ArrowException, TypeError, ValueError):  # labels of mixed types: sort them
        names, first, inv = np.unique(values.astype(str), return_index=True, return_inverse=True)
        order = np.argsort(first, kind="stable")
        rank = np.empty(order.size, np.int64)
        rank[order] = np.arange(order.size)
        return rank[inv.reshape(-1)], [str(n) for n in names[order]]
    codes = enc.indices.to_numpy(zero_copy_only=False).astype(np.int64)
    return codes, [str(n) for n in enc.dictionary.to_pylist()]


def compact_labels(labels: NDArray[Any]) -> NDArray[np.object_]:
    """``labels`` as an object array holding one ``str`` per distinct value: 8 bytes per
    row and the distinct texts once (a fixed-width array takes 4 bytes per character of
    the longest text on every row). Same values, same comparisons."""
    codes, names = track_index(labels)
    table = np.empty(len(names), dtype=object)
    table[:] = names
    return np.asarray(table[codes])


def run(
    name: str,
    plots: Plots,
    table: Mapping[str, Any] | None = None,
    source: str = "config",
    progress: Progress | None = None,
) -> dict[str, NDArray[Any]]:
    """Run method ``name`` over every labelled track of ``plots`` (one batch per step;
    ``progress`` is told of the plots done).

    Returns the output columns (one value per plot, input order):
    :data:`COMMON_COLUMNS`, ``status``, ``nis``, then the method's own columns.
    """
    labels = plots.track if plots.track is not None else np.zeros(len(plots), dtype=str)
    ti, _ = track_index(labels)
    m = build(name, table, d=plots.d, range_rate=plots.has_range_rate, source=source)
    gate = math.inf if name.endswith("-spec") else GROSS_NIS
    cols = run_tracks(m.filter, m.prepare(plots), ti, m.initiate, gate=gate, progress=progress)
    first = [*COMMON_COLUMNS, "status", "nis"]
    return {c: cols[c] for c in first} | {c: v for c, v in cols.items() if c not in first}


def describe_method(name: str) -> list[tuple[str, Any, str, str]]:
    """``(key, default, unit, doc)`` of a method's own keys (for docs and tests)."""
    from seatrack.config import describe

    return describe(method_class(name).Config)
