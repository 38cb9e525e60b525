"""Work budgets: the memory and time a command may use, checked before the work starts.

Every command estimates what a run will need from its inputs and options -- file sizes,
rows x columns, scenario targets x samples, Monte-Carlo runs x methods x scans, filter
cycles -- and calls :func:`require` before allocating anything. A run over a budget is
refused with one line naming the cause, the estimate and how to raise the budget::

    error: evaluate: 100000 runs x 12 methods x 101 scans needs about 19.4 GB of memory,
    over the budget of 1.5 GB (raise it: seatrack --memory-limit SIZE ...)

A run estimated at more than a minute says so when it starts and shows its progress: the
command passes the same estimate to a :class:`seatrack.progress.Progress`.

The budget of the process is set once, by the command line (``seatrack --memory-limit
4G --time-limit 2h COMMAND ...``, or ``seatrack ais --memory-limit``); library callers may
use :func:`set_budget` or the :func:`budget` context manager. The estimates are upper
bounds of the data a run holds (the interpreter and its libraries, about 300 MB, come on
top), measured per unit on this code and stated beside each constant where it is used.
"""

from __future__ import annotations

import contextlib
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass

from seatrack.errors import InputError
from seatrack.progress import format_duration

__all__ = [
    "Budget",
    "DEFAULT_MEMORY_BYTES",
    "DEFAULT_TIME_S",
    "budget",
    "current",
    "format_bytes",
    "parse_duration",
    "parse_size",
    "require",
    "set_budget",
]

#: default memory budget of the data of one run, bytes (1.5 GiB: with the interpreter and
#: its libraries a run stays under 2 GB)
DEFAULT_MEMORY_BYTES = 3 << 29
#: default time budget of one run, seconds
DEFAULT_TIME_S = 3600.0


@dataclass(frozen=True)
class Budget:
    """The memory (bytes) and time (seconds) one run may use."""

    memory_bytes: int = DEFAULT_MEMORY_BYTES
    time_s: float = DEFAULT_TIME_S


_CURRENT = [Budget()]


def current() -> Budget:
    """The budget of this process."""
    return _CURRENT[-1]


def set_budget(memory_bytes: int | None = None, time_s: float | None = None) -> Budget:
    """Replace the process budget (``None`` keeps a value); returns the new budget."""
    old = current()
    new = Budget(
        old.memory_bytes if memory_bytes is None else int(memory_bytes),
        old.time_s if time_s is None else float(time_s),
    )
    _CURRENT[-1] = new
    return new


@contextlib.contextmanager
def budget(memory_bytes: int | None = None, time_s: float | None = None) -> Iterator[Budget]:
    """A budget for the ``with`` block only."""
    old = current()
    _CURRENT.append(old)
    try:
        yield set_budget(memory_bytes, time_s)
    finally:
        _CURRENT.pop()


def format_bytes(n: float) -> str:
    """``1.5 GB``, ``800 MB``, ``12 kB`` (powers of 1000, as ``ls -h --si``)."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def require(what: str, memory_bytes: float = 0.0, seconds: float = 0.0) -> None:
    """Refuse the run if ``what`` needs more than the budget.

    Parameters
    ----------
    what : the cause, for the message (``"evaluate: 100000 runs x 12 methods x 101 scans"``).
    memory_bytes : estimated peak memory of the data, bytes.
    seconds : estimated run time, seconds.

    Raises
    ------
    InputError
        ``WHAT needs about X of memory, over the budget of Y (raise it: seatrack
        --memory-limit SIZE ...)``, or the same for time.
    """
    b = current()
    if not math.isfinite(memory_bytes) or memory_bytes > b.memory_bytes:
        raise InputError(
            f"{what} needs about {format_bytes(memory_bytes)} of memory, over the budget of "
            f"{format_bytes(b.memory_bytes)} (raise it: seatrack --memory-limit SIZE ...)"
        )
    if not math.isfinite(seconds) or seconds > b.time_s:
        raise InputError(
            f"{what} would take about {format_duration(seconds, 3)}, over the budget of "
            f"{format_duration(b.time_s, 3)} (raise it: seatrack --time-limit DURATION ...)"
        )


_SIZE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:e[0-9]+)?)\s*([kmgt]?)i?b?\s*$", re.IGNORECASE)
_DURATION = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(s|min|m|h|d)?\s*$", re.IGNORECASE)


def parse_size(text: str, option: str = "--memory-limit", least: int = 64 << 20) -> int:
    """``"1.5G"``, ``"800M"``, ``"2GB"`` or a number of bytes -> bytes (at least ``least``).

    Raises
    ------
    InputError
        Naming ``option``, for text that is not a size or a size below ``least``.
    """
    m = _SIZE.match(text)
    if m is None:
        raise InputError(f"{option}: expected a size such as 2G or 800M, got {text!r}")
    scale = {"": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}
    value = float(m.group(1)) * scale[m.group(2).lower()]
    if not math.isfinite(value) or value < least:
        raise InputError(f"{option}: must be at least {format_bytes(least)}, got {text!r}")
    return int(min(value, 1 << 60))


def parse_duration(text: str, option: str = "--time-limit") -> float:
    """``"90"``, ``"90s"``, ``"30min"``, ``"2h"``, ``"1d"`` -> seconds (> 0).

    Raises
    ------
    InputError
        Naming ``option``, for text that is not a positive duration.
    """
    m = _DURATION.match(text)
    if m is None or float(m.group(1)) <= 0:
        raise InputError(f"{option}: expected a duration such as 90s, 30min or 2h, got {text!r}")
    unit = (m.group(2) or "s").lower()
    return float(m.group(1)) * {"s": 1, "m": 60, "min": 60, "h": 3600, "d": 86400}[unit]
