"""Validated reading of CSV measurement files.

Every reader in seatrack goes through :func:`read_csv_table`, so every file gets the same
guarantees: required columns are checked by exact header name (extra columns are kept
but ignored), numeric fields are parsed, and each bad row is reported by file, line and
reason. Rows are never dropped silently: a row that cannot be used is either an error
(``on_error="raise"``, the default for measurement files) or listed in
:attr:`Table.rejected` with its reason (``on_error="collect"``).

Line numbers are 1-based and count the header as line 1, as in a text editor.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["InputError", "Rejected", "Table", "read_csv_table", "check_times"]


class InputError(ValueError):
    """A user-supplied file or value is malformed. The message names the file, row and problem."""


@dataclass(frozen=True)
class Rejected:
    """One rejected input row: ``line`` (1-based, header = 1) and the reason."""

    line: int
    reason: str


@dataclass
class Table:
    """Columns of a CSV file.

    Attributes
    ----------
    path : str
    columns : dict of name -> ndarray
        Numeric columns as float64 (missing optional values as NaN); text columns as str.
    lines : ndarray of int
        Source line number of each kept row.
    rejected : list of Rejected
        Rows that were not kept, with reasons (only with ``on_error="collect"``).
    n_read : int
        Number of data rows read.
    """

    path: str
    columns: dict[str, NDArray]
    lines: NDArray[np.int64]
    rejected: list[Rejected] = field(default_factory=list)
    n_read: int = 0

    def __getitem__(self, name: str) -> NDArray:
        return self.columns[name]

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def __len__(self) -> int:
        return int(self.lines.size)

    def subset(self, mask: NDArray[np.bool_]) -> Table:
        """Rows where ``mask`` is true (same path, no rejected rows carried)."""
        return Table(
            self.path,
            {k: v[mask] for k, v in self.columns.items()},
            self.lines[mask],
            [],
            int(mask.sum()),
        )


def read_csv_table(
    path: str | Path,
    required: Sequence[str],
    optional: Sequence[str] = (),
    text: Iterable[str] = (),
    on_error: str = "raise",
) -> Table:
    """Read a CSV file with a header row into validated columns.

    Parameters
    ----------
    path : path to the file.
    required : column names that must be present and non-empty, finite numbers
        (unless listed in ``text``).
    optional : column names that may be absent; empty cells become NaN ("" for text).
    text : names among required/optional kept as strings.
    on_error : "raise" (first bad row raises :class:`InputError`) or "collect"
        (bad rows go to ``Table.rejected``).

    Raises
    ------
    InputError
        Missing file, missing columns, empty file, or (``on_error="raise"``) a bad value.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: file not found")
    text_cols = set(text)
    try:
        fh = p.open(newline="", encoding="utf-8-sig")
    except OSError as exc:  # pragma: no cover - permissions
        raise InputError(f"{p}: cannot open ({exc.strerror})") from exc
    with fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise InputError(f"{p}: file is empty (expected a header row)") from None
        except csv.Error as exc:
            raise InputError(f"{p}, line 1: not valid CSV ({exc})") from None
        header = [h.strip() for h in header]
        missing = [c for c in required if c not in header]
        if missing:
            raise InputError(
                f"{p}: missing required column(s) {', '.join(missing)}; "
                f"found {', '.join(header) or 'no columns'}"
            )
        wanted = list(required) + [c for c in optional if c in header]
        idx = {c: header.index(c) for c in wanted}
        req = set(required)
        data: dict[str, list] = {c: [] for c in wanted}
        lines: list[int] = []
        rejected: list[Rejected] = []
        n_read = 0
        try:
            for row in reader:
                line = reader.line_num
                if not row or all(not c.strip() for c in row):
                    continue
                n_read += 1
                values: dict[str, object] = {}
                problem = None
                for c in wanted:
                    j = idx[c]
                    cell = row[j].strip() if j < len(row) else ""
                    if c in text_cols:
                        if cell == "" and c in req:
                            problem = f"column {c} is empty"
                            break
                        values[c] = cell
                        continue
                    if cell == "":
                        if c in req:
                            problem = f"column {c} is empty"
                            break
                        values[c] = math.nan
                        continue
                    try:
                        v = float(cell)
                    except ValueError:
                        problem = f"column {c} = {cell!r} is not a number"
                        break
                    if not math.isfinite(v):
                        problem = f"column {c} = {cell!r} is not a finite number"
                        break
                    values[c] = v
                if problem is not None:
                    if on_error == "raise":
                        raise InputError(f"{p}, line {line}: {problem}")
                    rejected.append(Rejected(line, problem))
                    continue
                for c in wanted:
                    data[c].append(values[c])
                lines.append(line)
        except csv.Error as exc:
            raise InputError(f"{p}, line {reader.line_num}: not valid CSV ({exc})") from None
    if n_read == 0:
        raise InputError(f"{p}: no data rows after the header")
    cols: dict[str, NDArray] = {}
    for c in wanted:
        cols[c] = np.array(data[c], dtype=str if c in text_cols else float)
    return Table(str(p), cols, np.array(lines, dtype=np.int64), rejected, n_read)


def check_times(
    table: Table, column: str = "time_s", group: str | None = None, strict: bool = True
) -> None:
    """Raise :class:`InputError` unless times are sorted (strictly, if ``strict``) per group.

    The message names the first offending line and both times.
    """
    t = table[column]
    keys = table[group] if group and group in table else np.zeros(len(table), dtype=str)
    last: dict[str, tuple[float, int]] = {}
    for ti, k, ln in zip(t, keys, table.lines, strict=True):
        prev = last.get(k)
        if prev is not None:
            if ti < prev[0]:
                raise InputError(
                    f"{table.path}, line {ln}: {column} = {ti:g} is earlier than {prev[0]:g} on "
                    f"line {prev[1]}{_grp(group, k)}; sort the file by time"
                )
            if strict and ti == prev[0]:
                raise InputError(
                    f"{table.path}, line {ln}: duplicate {column} = {ti:g} (also on line "
                    f"{prev[1]}){_grp(group, k)}"
                )
        last[k] = (float(ti), int(ln))


def _grp(group: str | None, key: str) -> str:
    return f" for {group} {str(key)!r}" if group and key != "" else ""
