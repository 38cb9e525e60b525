"""Typed, validated access to a parsed TOML document (scenario files).

:class:`TomlReader` reads numbers, integers, strings, vectors and tables out of the dicts
:mod:`tomllib` returns, and every problem is an :class:`~seatrack.io.table.InputError`
naming the file, the key path (``targets[1].legs[2].turn_rate_dps``) and what is wrong.

Every number is checked to be finite and physically plausible: besides the bounds a
caller gives, a key's unit suffix sets the largest magnitude accepted
(:data:`SUFFIX_LIMITS`: ``_m`` 1e8 m, ``_s`` the Unix time of 2100, ``_mps`` 1e4 m/s,
``_kn`` about 2e4 kn, ``_dps`` 3600 deg/s, ``_deg`` 36000 deg, ``_mps2`` 1e3 m/s^2), so
no later computation overflows or allocates without bound because of a typo like
``1e30``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.geometry import KNOT_MPS
from seatrack.io.table import MAX_DISTANCE_M
from seatrack.io.table import MAX_TIME_S
from seatrack.io.table import InputError

__all__ = ["SUFFIX_LIMITS", "TomlReader", "join_key", "describe", "suffix_limit"]

#: largest speed accepted, m/s
MAX_SPEED_MPS = 1e4

#: key suffix -> largest magnitude accepted (first match wins; longest suffixes first)
SUFFIX_LIMITS: tuple[tuple[str, float], ...] = (
    ("_mps2", 1e3),
    ("_mps", MAX_SPEED_MPS),
    ("_kn", MAX_SPEED_MPS / KNOT_MPS),
    ("_dps", 3600.0),
    ("_deg", 36000.0),
    ("_m", MAX_DISTANCE_M),
    ("_s", MAX_TIME_S),
)


def suffix_limit(key: str) -> float:
    """Largest magnitude accepted for ``key`` by its unit suffix (inf when it has none)."""
    for suffix, limit in SUFFIX_LIMITS:
        if key.endswith(suffix):
            return limit
    return math.inf


def join_key(prefix: str, key: str) -> str:
    """Key path ``prefix.key`` (just ``key`` at the top level)."""
    return f"{prefix}.{key}" if prefix else key


def describe(v: Any) -> str:
    """A TOML value in words, for messages (``number 3``, ``string 'x'``, ``a table``)."""
    if isinstance(v, bool):
        return f"boolean {str(v).lower()}"
    if isinstance(v, (int, float)):
        return f"number {v!r}"
    if isinstance(v, str):
        return f"string {v!r}"
    if isinstance(v, list):
        return f"a list of {len(v)} items"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


class TomlReader:
    """Typed access to a TOML table with errors naming the file and key path."""

    def __init__(self, path: str):
        self.path = path

    def error(self, key: str, problem: str) -> InputError:
        """An :class:`InputError` ``FILE: KEY: problem``."""
        where = f"{self.path}: {key}" if key else self.path
        return InputError(f"{where}: {problem}")

    def table(self, value: Any, key: str) -> dict[str, Any]:
        """``value`` if it is a table, else an error."""
        if not isinstance(value, dict):
            raise self.error(key, f"expected a table, got {describe(value)}")
        return value

    def check_keys(self, tab: Mapping[str, Any], prefix: str, allowed: Sequence[str]) -> None:
        """Unknown keys are errors (they are usually typos)."""
        for k in tab:
            if k not in allowed:
                raise self.error(
                    join_key(prefix, k), f"unknown key; allowed keys are {', '.join(allowed)}"
                )

    def number(
        self,
        tab: Mapping[str, Any],
        prefix: str,
        key: str,
        default: float | None = None,
        required: bool = False,
        minimum: float | None = None,
        positive: bool = False,
        maximum: float | None = None,
    ) -> float | None:
        """A finite number within the given bounds and the key's unit limit."""
        kp = join_key(prefix, key)
        if key not in tab:
            if required:
                raise self.error(kp, "missing required key")
            return default
        v = tab[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.error(kp, f"expected a number, got {describe(v)}")
        try:
            v = float(v)
        except OverflowError:
            raise self.error(kp, f"number {v} is too large") from None
        if not math.isfinite(v):
            raise self.error(kp, f"must be finite, got {v}")
        if positive and v <= 0:
            raise self.error(kp, f"must be > 0, got {v:g}")
        if minimum is not None and v < minimum:
            raise self.error(kp, f"must be >= {minimum:g}, got {v:g}")
        if maximum is not None and v > maximum:
            raise self.error(kp, f"must be <= {maximum:g}, got {v:g}")
        limit = suffix_limit(key)
        if abs(v) > limit:
            raise self.error(kp, f"{v:g} is implausibly large (at most {limit:g} in magnitude)")
        return v

    def req(self, tab: Mapping[str, Any], prefix: str, key: str, **kw: Any) -> float:
        """A required number (see :meth:`number`)."""
        v = self.number(tab, prefix, key, required=True, **kw)
        assert v is not None
        return v

    def integer(
        self,
        tab: Mapping[str, Any],
        prefix: str,
        key: str,
        default: int,
        minimum: int,
        maximum: int | None = None,
    ) -> int:
        """An integer in ``[minimum, maximum]``."""
        kp = join_key(prefix, key)
        if key not in tab:
            return default
        v = tab[key]
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(kp, f"expected an integer, got {describe(v)}")
        if v < minimum:
            raise self.error(kp, f"must be >= {minimum}, got {v}")
        if maximum is not None and v > maximum:
            raise self.error(kp, f"must be <= {maximum}, got {v}")
        return v

    def string(
        self, tab: Mapping[str, Any], prefix: str, key: str, default: str | None = None
    ) -> str:
        """A string (required when ``default`` is None)."""
        kp = join_key(prefix, key)
        if key not in tab:
            if default is None:
                raise self.error(kp, "missing required key")
            return default
        v = tab[key]
        if not isinstance(v, str):
            raise self.error(kp, f"expected a string, got {describe(v)}")
        return v

    def vector(
        self, tab: Mapping[str, Any], prefix: str, key: str, sizes: tuple[int, ...]
    ) -> NDArray[np.float64]:
        """A list of ``sizes`` finite numbers, each within the key's unit limit."""
        kp = join_key(prefix, key)
        v = tab[key]
        if not isinstance(v, list) or len(v) not in sizes:
            want = " or ".join(str(s) for s in sizes)
            raise self.error(kp, f"expected a list of {want} numbers, got {describe(v)}")
        limit = suffix_limit(key)
        out = []
        for i, e in enumerate(v):
            ok = isinstance(e, (int, float)) and not isinstance(e, bool)
            if ok:
                try:
                    ok = math.isfinite(float(e)) and abs(float(e)) <= limit
                except OverflowError:
                    ok = False
            if not ok:
                raise self.error(
                    f"{kp}[{i}]",
                    f"expected a finite number of magnitude <= {limit:g}, got {describe(e)}",
                )
            out.append(float(e))
        return np.asarray(out)
