"""Checks shared by the API and the commands: argument values and output paths first.

Every numeric option is finite and in range, and a bad one is an
:class:`~seatrack.io.table.InputError` naming the option (``--skip = 1000 must be in
[0, 100]``); every output file or folder is checked (and its folder created) with
:mod:`seatrack.io.atomic` before the inputs are read, so a bad path costs no computation.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path

from seatrack.io.atomic import check_output_dir
from seatrack.io.atomic import check_output_path
from seatrack.io.table import InputError
from seatrack.io.table import between

__all__ = ["option_in", "option_positive", "prepare_outputs"]


def option_in(
    name: str,
    value: float,
    lo: float,
    hi: float,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
    """``value`` of option ``name`` if it lies in the interval, else :class:`InputError`."""
    problem = between(name, lo, hi, lo_open=lo_open, hi_open=hi_open).problem(value)
    if problem is not None:
        raise InputError(problem)
    return value


def option_positive(name: str, value: float, hi: float = math.inf) -> float:
    """``0 < value <= hi`` (finite) for option ``name``."""
    return option_in(name, value, 0.0, hi, lo_open=True)


def prepare_outputs(files: Iterable[Path | None] = (), folders: Iterable[Path | None] = ()) -> None:
    """Check output folders (created when missing) and files; ``None`` entries are skipped.

    Raises
    ------
    OutputError
        Naming the first path that cannot be written and why.
    """
    for d in folders:
        if d is not None:
            check_output_dir(d)
    for f in files:
        if f is not None:
            check_output_path(f)
