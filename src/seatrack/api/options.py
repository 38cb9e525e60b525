"""Checks shared by the API and the commands: argument values and output paths first.

Every numeric option is finite and in range, and a bad one is an
:class:`~seatrack.io.table.InputError` naming the option (``--skip = 1000 must be in
[0, 100]``); every output file or folder is checked (and its folder created) with
:mod:`seatrack.io.atomic` before the inputs are read, so a bad path costs no computation:
:func:`prepare_outputs` also refuses an output that is one of the inputs or another output,
and a picture option without a picture suffix.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from collections.abc import Iterable
from collections.abc import Mapping
from pathlib import Path

from seatrack.io.atomic import OutputError
from seatrack.io.atomic import check_output_dir
from seatrack.io.atomic import check_output_path
from seatrack.io.table import InputError
from seatrack.io.table import between

__all__ = ["IMAGE_SUFFIXES", "option_in", "option_positive", "prepare_outputs"]


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


#: picture formats an image option accepts (each written by matplotlib from the suffix)
IMAGE_SUFFIXES = (".png", ".svg", ".pdf")


def prepare_outputs(
    files: Iterable[Path | None] | Mapping[str, Path | None] = (),
    folders: Iterable[Path | None] | Mapping[str, Path | None] = (),
    *,
    inputs: Iterable[Path | str | None] = (),
    images: Iterable[str] = (),
) -> None:
    """Check every output of a run before any input is read; ``None`` entries are skipped.

    Parameters
    ----------
    files, folders : the output files and folders (folders are created when missing), as a
        list or as a mapping from the option that names each one (``{"--out": out}``), so
        that a message names the option.
    inputs : the run's input files: no output may be one of them (same resolved path, or
        the same file under another name: a hard link).
    images : the options among ``files`` that are pictures: their suffix must be one of
        :data:`IMAGE_SUFFIXES`.

    Raises
    ------
    OutputError
        Naming the option (when known) and the first path that cannot be written and why:
        a folder that cannot be created, a directory, a device node or pipe, a name too
        long, an image suffix that is not a picture format, an output that is an input, or
        two outputs that are the same file. See :mod:`seatrack.io.atomic` for the rules.
    """
    named_files = _named(files)
    named_dirs = _named(folders)
    for opt, d in named_dirs:
        _checked(opt, d, check_output_dir)
    seen: dict[str, str] = {}
    ins = [Path(i) for i in inputs if i is not None and str(i) != ""]
    for opt, f in named_files:
        _checked(opt, f, check_output_path)
        who = f"{opt} {f}" if opt else str(f)
        for i in ins:
            if _same_file(f, i):
                raise OutputError(f"{who}: is the input file {i}; it would be overwritten")
        key = os.path.realpath(f)
        if key in seen:
            raise OutputError(f"{who}: the same file as {seen[key]}; give different names")
        seen[key] = who
        if opt in set(images) and f.suffix.lower() not in IMAGE_SUFFIXES:
            raise OutputError(
                f"{who}: not a picture file name; give a "
                f"{', '.join(IMAGE_SUFFIXES[:-1])} or {IMAGE_SUFFIXES[-1]} file"
            )


def _named(paths: Iterable[Path | None] | Mapping[str, Path | None]) -> list[tuple[str, Path]]:
    items = paths.items() if isinstance(paths, Mapping) else (("", p) for p in paths)
    return [(opt, Path(p)) for opt, p in items if p is not None]


def _checked(opt: str, path: Path, check: Callable[[Path], Path]) -> None:
    try:
        check(path)
    except OutputError as exc:
        raise OutputError(f"{opt} {exc}" if opt else str(exc)) from None


def _same_file(a: Path, b: Path) -> bool:
    """``a`` and ``b`` name one file: same resolved path, or the same inode."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet)
        return False
