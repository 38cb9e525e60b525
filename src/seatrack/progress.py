"""Progress of long runs: a run estimated at more than a minute says so and shows progress.

Every command that can run long (``ais``, ``evaluate``, ``simulate``, ``track``,
``navigate``) estimates its run time from its inputs and options before it starts, with
rates measured on this code and stated beside each estimate, and opens a :class:`Progress`
with that estimate. When the estimate exceeds :func:`notice_after_s` (60 s) it prints one
line on standard error when it starts::

    seatrack ais: about 3 min for 12,400,000 reports (estimate)

then, while the loops doing the work report what they did (:meth:`Progress.update`,
:meth:`Progress.advance`), at most one line every :func:`every_s` seconds (10 s)::

    seatrack ais: 3,100,000/12,400,000 reports, 45 s elapsed, about 2.3 min remaining

A run estimated shorter prints nothing: short runs and the test suite stay silent, and a
call to :meth:`Progress.update` then costs one comparison. The remaining time is the
elapsed time scaled by the work left (the estimate, before any work is done).

Two environment variables, for tests and for users who want the lines on shorter runs:
``SEATRACK_PROGRESS_AFTER_S`` (the threshold, seconds; ``0`` shows the lines on every run)
and ``SEATRACK_PROGRESS_EVERY_S`` (the interval between lines, seconds).

This module sits below every layer (it imports nothing of seatrack): the loops of any
layer take a ``progress`` argument (a :class:`Progress` or None).
"""

from __future__ import annotations

import math
import os
import sys
import time
from typing import IO

__all__ = ["EVERY_S", "NOTICE_S", "Progress", "every_s", "format_duration", "notice_after_s"]

#: a run estimated longer than this says so when it starts and shows progress, seconds
NOTICE_S = 60.0
#: shortest interval between two progress lines, seconds
EVERY_S = 10.0


def _env_seconds(name: str, default: float) -> float:
    text = os.environ.get(name, "")
    try:
        value = float(text) if text.strip() else default
    except ValueError:
        return default
    return value if math.isfinite(value) and value >= 0 else default


def notice_after_s() -> float:
    """The threshold of a long run, seconds (``SEATRACK_PROGRESS_AFTER_S``, default 60)."""
    return _env_seconds("SEATRACK_PROGRESS_AFTER_S", NOTICE_S)


def every_s() -> float:
    """The interval between progress lines, seconds (``SEATRACK_PROGRESS_EVERY_S``, 10)."""
    return _env_seconds("SEATRACK_PROGRESS_EVERY_S", EVERY_S)


def format_duration(s: float, digits: int = 2) -> str:
    """``45 s``, ``2.3 min``, ``1.5 h`` (``digits`` significant digits)."""
    for unit, scale in (("h", 3600.0), ("min", 60.0)):
        if s >= scale:
            return f"{s / scale:.{digits}g} {unit}"
    return f"{s:.{digits}g} s"


class Progress:
    """The progress lines of one run (see the module docstring).

    Parameters
    ----------
    command : the command's name, first word of every line (``"seatrack ais"``).
    total : units of work of the run (an estimate is fine; :meth:`update` may correct it).
    unit : the unit's name, plural (``"reports"``, ``"runs"``, ``"scans"``).
    estimate_s : the estimated run time, seconds.
    stream : where the lines go (default: standard error).
    shown : ``False`` silences the lines whatever the estimate (``--no-progress``).
    """

    def __init__(
        self,
        command: str,
        total: float,
        unit: str,
        estimate_s: float,
        stream: IO[str] | None = None,
        shown: bool = True,
    ) -> None:
        self.command, self.total, self.unit = command, float(total), unit
        self.estimate_s = float(estimate_s)
        self.stream = stream
        self.active = shown and self.estimate_s > notice_after_s()
        self.done = 0.0
        self.stage = ""
        self.fraction: float | None = None
        self.start = time.monotonic()
        self.every = every_s()
        self.next_line = self.start + self.every
        if self.active:
            self._print(
                f"{command}: about {format_duration(self.estimate_s)} for "
                f"{self.total:,.0f} {unit} (estimate)"
            )

    @classmethod
    def silent(cls) -> Progress:
        """A progress that prints nothing (for library callers that pass none)."""
        return cls("", 0, "", 0.0, shown=False)

    def _print(self, line: str) -> None:
        print(line, file=self.stream if self.stream is not None else sys.stderr, flush=True)

    def update(
        self,
        done: float,
        total: float | None = None,
        stage: str = "",
        fraction: float | None = None,
    ) -> None:
        """``done`` units of work finished (and the ``total``, when it is now known better);
        prints a line when the run is long and the last line is :func:`every_s` old.

        ``stage`` names the part of the run the counts are of (``"read"``, ``"tracked"``),
        and ``fraction`` is then the share of the whole run's work done (default
        ``done / total``), from which the remaining time is computed.
        """
        self.done = float(done)
        if total is not None:
            self.total = float(total)
        self.stage = stage
        self.fraction = fraction
        if self.active:
            now = time.monotonic()
            if now >= self.next_line:
                self.next_line = now + self.every
                self._print(self.line(now - self.start))

    def advance(self, n: float = 1.0) -> None:
        """``n`` more units of work finished (see :meth:`update`)."""
        self.update(self.done + n)

    def remaining_s(self, elapsed_s: float) -> float:
        """The time left: the elapsed time scaled by the work left (before any work is
        done, what is left of the estimate), seconds."""
        f = self.fraction
        if f is None:
            f = self.done / self.total if self.total > 0 else 0.0
        if f <= 0:
            return max(self.estimate_s - elapsed_s, 0.0)
        return elapsed_s * max(1.0 - f, 0.0) / f

    def line(self, elapsed_s: float) -> str:
        """``COMMAND: DONE/TOTAL UNIT [STAGE], E elapsed, about R remaining``."""
        stage = f" {self.stage}" if self.stage else ""
        return (
            f"{self.command}: {self.done:,.0f}/{self.total:,.0f} {self.unit}{stage}, "
            f"{format_duration(elapsed_s)} elapsed, about "
            f"{format_duration(self.remaining_s(elapsed_s))} remaining"
        )
