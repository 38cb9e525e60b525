"""One configuration layer for every method: frozen dataclasses parsed from TOML tables.

Each method's parameters are a frozen dataclass whose fields are in SI units and radians.
The user-facing key of a field (its name in a TOML file or on the command line) may differ
from the field name and carry a unit suffix; :func:`param` declares it::

    @dataclass(frozen=True)
    class EKFConfig:
        q: float = param(1.0, unit="m^2/s^3", doc="white-noise acceleration PSD", min=0)
        sigma_azimuth: float = param(0.5, key="sigma_azimuth_deg", unit="deg", doc="...")

:func:`parse_config` turns a mapping (a parsed TOML table) into such a dataclass:

* edge units are converted once, here: ``deg`` -> rad, ``deg/s`` -> rad/s, ``kn`` -> m/s,
  ``g`` -> m/s^2 (the defaults given to :func:`param` are in the edge unit too, so a
  dataclass reads like its documentation);
* a key may be given by its user key, its field name (SI value) or an alias;
* an unknown key is an error listing the valid keys; a value of the wrong type is an error
  ``source: key: expected ...``; numbers must be finite and within ``min``/``max``;
* the dataclass's own ``__post_init__`` checks cross-field constraints.

A config dataclass derives from :class:`Checked`, so that an instance built directly
(``EKFConfig(q=-1.0)``) is checked against the same bounds as a parsed one; a subclass
with cross-field constraints calls ``super().__post_init__()`` first.

Errors are :class:`ConfigError` (a ``ValueError``), whose message starts with the source
(file name) so that the command line prints ``error: FILE: key: problem``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import tomllib
from collections.abc import Callable
from collections.abc import Hashable
from collections.abc import Iterable
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from typing import TypeVar
from typing import get_type_hints

import numpy as np

from seatrack.errors import UserError
from seatrack.geometry import G0

__all__ = [
    "ConfigError",
    "param",
    "redefault",
    "parse_config",
    "config_keys",
    "field_types",
    "describe",
    "load_toml",
    "to_edge",
    "check_fields",
    "require",
    "is_positive_number",
    "is_positive_integer",
    "Checked",
]

T = TypeVar("T")

#: edge unit -> factor to SI (radians for angles)
_FACTORS: dict[str, float] = {
    "deg": math.pi / 180.0,
    "deg/s": math.pi / 180.0,
    "deg/s^2": math.pi / 180.0,
    "kn": 1852.0 / 3600.0,
    "g": G0,
}


class ConfigError(UserError, ValueError):
    """A configuration value or key is invalid; the message names the source and the key."""


def param(
    default: Any,
    *,
    key: str | None = None,
    unit: str = "",
    doc: str = "",
    min: float | None = None,  # noqa: A002 - reads like the documentation
    max: float | None = None,  # noqa: A002
    exclusive_min: bool = False,
    choices: Iterable[Any] | None = None,
    aliases: Iterable[str] = (),
) -> Any:
    """Declare a configuration field.

    Parameters
    ----------
    default : value in the *edge* unit (``unit``); stored converted to SI.
    key : user-facing key (default: the field name).
    unit : edge unit: ``deg``, ``deg/s``, ``deg/s^2``, ``kn`` and ``g`` are converted to SI;
        any other string (``m``, ``m^2/s^3``, ``s``...) is documentation only.
    doc : one line for the generated documentation and error messages.
    min, max : bounds in the edge unit (``exclusive_min`` for ``> min``).
    choices : allowed values (strings).
    aliases : other accepted keys.
    """
    factor = _FACTORS.get(unit, 1.0)
    si_default = _scale(default, factor)
    meta = {
        "key": key,
        "unit": unit,
        "doc": doc,
        "min": min,
        "max": max,
        "exclusive_min": exclusive_min,
        "choices": None if choices is None else tuple(choices),
        "aliases": tuple(aliases),
        "factor": factor,
    }
    if isinstance(si_default, (list, dict, set)):
        raise TypeError("mutable defaults are not allowed in frozen configs; use a tuple")
    return dataclasses.field(default=si_default, metadata=meta)


def redefault(cls: type, name: str, default: Any) -> Any:
    """The :func:`param` field ``name`` of the config class ``cls`` with another ``default``
    (edge unit), its key, unit, documentation and bounds unchanged: for a subclass that
    only changes a default."""
    meta = {f.name: f for f in dataclasses.fields(cls)}[name].metadata
    return dataclasses.field(default=_scale(default, meta["factor"]), metadata=meta)


def _scale(v: Any, factor: float) -> Any:
    if factor == 1.0 or v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, tuple):
        return tuple(_scale(e, factor) for e in v)
    return float(v) * factor


def _user_key(f: dataclasses.Field[Any]) -> str:
    return str(f.metadata.get("key") or f.name)


def config_keys(cls: type) -> dict[str, str]:
    """Every accepted key of config class ``cls`` -> field name (user keys, names, aliases)."""
    out: dict[str, str] = {}
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        out[_user_key(f)] = f.name
        out.setdefault(f.name, f.name)
        for a in f.metadata.get("aliases", ()):
            out[a] = f.name
    return out


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp))


def _convert(value: Any, tp: Any, f: dataclasses.Field[Any], where: str, si: bool) -> Any:
    """Check the type of one value and convert it from the edge unit (unless ``si``)."""
    meta = f.metadata
    origin = getattr(tp, "__origin__", None)
    text = str(tp)
    if tp is bool or text == "bool":
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: expected true or false, got {value!r}")
        return value
    if tp is float or text == "float" or tp is int or text == "int":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{where}: expected a number, got {value!r}")
        if tp is int or text == "int":
            if not isinstance(value, int):
                raise ConfigError(f"{where}: expected an integer, got {value!r}")
            _check_bounds(float(value), meta, where)
            return int(value)
        if not math.isfinite(value):
            raise ConfigError(f"{where}: must be finite, got {value!r}")
        _check_bounds(float(value), meta, where)
        return float(value) if si else float(value) * meta.get("factor", 1.0)
    if tp is str or text == "str":
        if not isinstance(value, str):
            raise ConfigError(f"{where}: expected a string, got {value!r}")
        ch = meta.get("choices")
        if ch is not None and value not in ch:
            raise ConfigError(f"{where}: must be one of {', '.join(map(str, ch))}, got {value!r}")
        return value
    if origin is tuple or text.startswith("tuple"):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"{where}: expected a list, got {value!r}")
        return tuple(_tuple_item(v, f, f"{where}[{i}]", si) for i, v in enumerate(value))
    if "None" in text and value is None:
        return None
    if "float" in text:  # float | None
        return _convert(value, float, f, where, si)
    if "str" in text:  # str | None
        return _convert(value, str, f, where, si)
    return value


def _tuple_item(v: Any, f: dataclasses.Field[Any], where: str, si: bool) -> Any:
    if isinstance(v, (list, tuple)):
        return tuple(_tuple_item(e, f, f"{where}[{i}]", si) for i, e in enumerate(v))
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        raise ConfigError(f"{where}: expected numbers or strings, got {v!r}")
    if isinstance(v, str):
        return v
    if not math.isfinite(v):
        raise ConfigError(f"{where}: must be finite, got {v!r}")
    return float(v) if si else float(v) * f.metadata.get("factor", 1.0)


def _check_bounds(v: float, meta: Mapping[str, Any], where: str) -> None:
    lo, hi = meta.get("min"), meta.get("max")
    unit = meta.get("unit", "")
    if lo is not None:
        if meta.get("exclusive_min") and not v > lo:
            raise ConfigError(f"{where}: must be > {lo:g} {unit}".rstrip() + f", got {v!r}")
        if v < lo:
            raise ConfigError(f"{where}: must be >= {lo:g} {unit}".rstrip() + f", got {v!r}")
    if hi is not None and v > hi:
        raise ConfigError(f"{where}: must be <= {hi:g} {unit}".rstrip() + f", got {v!r}")


def check_fields(config: Any) -> None:
    """Check the numeric fields of a config instance against their :func:`param` bounds.

    For a config dataclass built directly (``SensorNoise(sigma_range=-1.0)``) rather than
    through :func:`parse_config`: call it from ``__post_init__``. Values are SI (the field
    unit); the bounds of :func:`param` are in the edge unit and are scaled to SI here, so a
    value given at a bound passes.

    Raises
    ------
    ConfigError
        ``Class.field (key): must be ..., got VALUE UNIT`` for the first number that is not
        finite or lies outside its bounds (the value shown in the edge unit).
    """
    for f in dataclasses.fields(config):
        meta = f.metadata
        v = getattr(config, f.name)
        if not f.init or "factor" not in meta or isinstance(v, bool):
            continue
        if not isinstance(v, (int, float)):
            continue
        factor = meta["factor"]
        unit = meta.get("unit", "")
        where = f"{type(config).__name__}.{f.name}"
        if _user_key(f) != f.name:
            where += f" ({_user_key(f)})"
        shown = f"{v / factor:g} {unit}".rstrip()
        if not math.isfinite(v):
            raise ConfigError(f"{where}: must be finite, got {v!r}")
        lo, hi = meta.get("min"), meta.get("max")
        if lo is not None and (v <= lo * factor if meta.get("exclusive_min") else v < lo * factor):
            op = ">" if meta.get("exclusive_min") else ">="
            raise ConfigError(f"{where}: must be {op} {lo:g} {unit}".rstrip() + f", got {shown}")
        if hi is not None and v > hi * factor:
            raise ConfigError(f"{where}: must be <= {hi:g} {unit}".rstrip() + f", got {shown}")


def require(
    config: object,
    names: Iterable[str],
    test: Callable[[Any], bool],
    rule: str,
    *,
    prefix: str = "",
) -> None:
    """Check fields of a config instance against one rule (a constraint :func:`param`
    bounds do not state, or a config that does not use :func:`param`).

    Parameters
    ----------
    config : the instance (usually ``self`` in ``__post_init__``).
    names : the fields to check, in order.
    test : true for a valid value (a NaN should fail it: write ``v > 0``, not
        ``not v <= 0``).
    rule : what a valid value is, for the message (``"> 0"``, ``"in (0, 1)"``...).
    prefix : start of the message, e.g. the class name and a dot.

    Raises
    ------
    ValueError
        ``{prefix}{name} must be {rule}, got {value}`` for the first field that fails
        ``test`` (:func:`parse_config` prefixes the source).
    """
    for name in names:
        value = getattr(config, name)
        if not test(value):
            raise ValueError(f"{prefix}{name} must be {rule}, got {value}")


def is_positive_number(v: float) -> bool:
    """A finite number > 0 (NaN and infinity fail): a ``test`` of :func:`require`."""
    return bool(np.isfinite(v) and v > 0)


def is_positive_integer(v: float) -> bool:
    """A whole number >= 1 (``int(v)`` raises for NaN and infinity): a ``test`` of
    :func:`require`."""
    return bool(int(v) == v and v >= 1)


class Checked:
    """Base of the config dataclasses: ``__post_init__`` runs :func:`check_fields`.

    A subclass that defines its own ``__post_init__`` (cross-field constraints) calls
    ``super().__post_init__()`` first.

    Raises
    ------
    ConfigError
        From :func:`check_fields`: a number that is not finite or lies outside the bounds of
        its :func:`param`, the message naming the field and its key.
    """

    def __post_init__(self) -> None:
        check_fields(self)


def field_types(cls: type) -> dict[str, Any]:
    """The evaluated type hints of a config dataclass (cached: evaluating the string
    annotations costs about a millisecond per field, on every run of a method)."""
    return _field_types(cls)


@functools.cache
def _field_types(cls: Hashable) -> dict[str, Any]:
    return get_type_hints(cls)


def parse_config(
    cls: type[T],
    table: Mapping[str, Any] | None = None,
    *,
    source: str = "config",
    base: T | None = None,
    ignore: Iterable[str] = (),
) -> T:
    """Build config dataclass ``cls`` from a mapping of user keys (a TOML table).

    Parameters
    ----------
    cls : frozen dataclass whose fields are declared with :func:`param`.
    table : keys -> values in edge units (user keys) or SI (field names).
    source : prefix of error messages (usually the file name).
    base : start from this instance instead of the defaults (e.g. a preset).
    ignore : keys accepted and ignored (e.g. another section's keys).

    Raises
    ------
    ConfigError
        Unknown key (the message lists the valid ones), wrong type, non-finite or
        out-of-range value, or a constraint of the dataclass itself.
    """
    keys = config_keys(cls)
    hints = field_types(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    skip = set(ignore)
    kw: dict[str, Any] = {}
    given: dict[str, str] = {}
    for key, value in (table or {}).items():
        if key in skip:
            continue
        name = keys.get(key)
        if name is None:
            valid = sorted({_user_key(f) for f in fields.values() if f.init})
            raise ConfigError(f"{source}: unknown key {key!r}; valid keys: {', '.join(valid)}")
        if name in given:
            raise ConfigError(f"{source}: {key!r} and {given[name]!r} set the same parameter")
        given[name] = key
        f = fields[name]
        si = key == name and _user_key(f) != name  # the SI field name was used
        kw[name] = _convert(value, hints[name], f, f"{source}: {key}", si)
    try:
        if base is not None:
            return dataclasses.replace(base, **kw)  # type: ignore[type-var]
        return cls(**kw)
    except (ValueError, TypeError) as exc:  # the constructor's checks: name the source
        text = str(exc)
        raise ConfigError(text if text.startswith(f"{source}:") else f"{source}: {text}") from None


def to_edge(config: Any) -> dict[str, Any]:
    """The user keys and edge-unit values of a config instance (inverse of parse_config)."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(config):
        v = getattr(config, f.name)
        out[_user_key(f)] = _scale(v, 1.0 / f.metadata.get("factor", 1.0))
    return out


def describe(cls: type) -> list[tuple[str, Any, str, str]]:
    """``(key, default in edge unit, unit, doc)`` per field: for docs and ``--help``."""
    rows = []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        d = f.default if f.default is not dataclasses.MISSING else None
        rows.append(
            (
                _user_key(f),
                _scale(d, 1.0 / f.metadata.get("factor", 1.0)),
                str(f.metadata.get("unit", "")),
                str(f.metadata.get("doc", "")),
            )
        )
    return rows


def load_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file; errors name the file (:class:`ConfigError`)."""
    p = Path(path)
    if p.is_dir():
        raise ConfigError(f"{p}: is a directory, expected a TOML file")
    if not p.is_file():
        raise ConfigError(f"{p}: configuration file not found")
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML ({exc})") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{p}: not valid UTF-8 text ({exc.reason})") from None
