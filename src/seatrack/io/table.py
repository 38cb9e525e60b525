"""Validated reading of CSV measurement files.

Every reader in seatrack goes through :func:`read_csv_table`, so every file gets the same
guarantees: required columns are checked by exact header name (extra columns are kept
but ignored), numeric fields are parsed, and each bad row is reported by file, line and
reason. Rows are never dropped silently: a row that cannot be used is either an error
(``on_error="raise"``, the default for measurement files) or listed in
:attr:`Table.rejected` with its reason (``on_error="collect"``).

Line numbers are 1-based and count the header as line 1, as in a text editor.

Encoding
--------
Files are read as UTF-8; a UTF-8 byte-order mark is ignored. Gzip, zstd and bzip2 data are
decompressed whatever the file's name (:mod:`seatrack.io.compressed`), within the memory
budget (:mod:`seatrack.io.budget`), checked from the file's size before it is read. A text
cell (a track id) holds at most :data:`MAX_TEXT_CHARS` characters, and a column name
appears once in the header. A file that is not valid
UTF-8 is decoded line by line: each line that is not valid UTF-8 is read as Latin-1
(ship names in AIS exports often are) and listed in :attr:`Table.latin1_lines`. A
non-ASCII character can then only end up in a text column: in a numeric column it is
reported as "not a number" with the file and line. CR, LF and CRLF line ends are all
accepted.

Declaring per-column checks
---------------------------
Beyond "a finite number", a reader states what each numeric column must hold with a
tuple of :class:`Check` objects, built with the helpers below, and passes it as
``checks=`` to :func:`read_csv_table`::

    read_csv_table(path, ["time_s", "range_m", "azimuth_deg"],
                   checks=(seconds("time_s"), positive("range_m"), angle_deg("azimuth_deg")))

A value outside its range is a bad row like any other (an error naming the file, the
line, the column, the value and the allowed range, or a rejected row with that reason).
The helpers encode the physical limits used across seatrack:

* :func:`seconds` -- a time in seconds, relative or Unix, ``|t| <=`` :data:`MAX_TIME_S`
  (the Unix time of 2100-01-01);
* :func:`unix_seconds` -- an absolute Unix time between 1970 and 2100;
* :func:`positive` -- a range or other length ``> 0`` and at most :data:`MAX_DISTANCE_M`;
* :func:`coordinate` -- an East/North/Up coordinate, ``|x| <=`` :data:`MAX_DISTANCE_M`;
* :func:`sigma` -- a standard deviation, ``> 0``;
* :func:`angle_deg` -- a bearing, azimuth, course or heading in ``[0, 360)`` degrees;
* :func:`latitude`, :func:`longitude` -- degrees in ``[-90, 90]`` and ``[-180, 180]``;
* :func:`between` -- any closed or half-open interval.

Times must also be ordered: :func:`check_times` checks that per group after reading.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from seatrack.errors import InputError
from seatrack.io.budget import require
from seatrack.io.compressed import check_ratio
from seatrack.io.compressed import read_input

__all__ = [
    "InputError",
    "Rejected",
    "Table",
    "Check",
    "read_csv_table",
    "check_input_file",
    "read_input_bytes",
    "MAX_TEXT_CHARS",
    "describe_header",
    "check_times",
    "between",
    "positive",
    "coordinate",
    "seconds",
    "unix_seconds",
    "sigma",
    "angle_deg",
    "latitude",
    "longitude",
    "MAX_TIME_S",
    "MAX_DISTANCE_M",
    "MIN_SIGMA",
]

#: largest accepted |time| in seconds: Unix time of 2100-01-01T00:00:00Z
MAX_TIME_S = 4_102_444_800.0
#: largest accepted distance or |coordinate| in metres (about 15 Earth radii)
MAX_DISTANCE_M = 1e8
#: smallest accepted noise sigma, in the unit of the file or option (deg, m, m/s): below
#: it the covariance and its inverse leave the floating-point range (no sensor is that
#: precise)
MIN_SIGMA = 1e-6


@dataclass(frozen=True)
class Rejected:
    """One rejected input row: ``line`` (1-based, header = 1) and the reason."""

    line: int
    reason: str


@dataclass(frozen=True)
class Check:
    """The allowed values of one numeric column: an interval, closed unless ``*_open``.

    Build one with :func:`between`, :func:`positive`, :func:`seconds`, ... rather than
    directly. :meth:`problem` returns ``None`` for a good value, else the reason.
    """

    column: str
    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    note: str = ""

    def problem(self, value: float, cell: str | None = None) -> str | None:
        """Why ``value`` (written as ``cell`` in the file) is not allowed, or ``None``."""
        lo, hi = self.lo, self.hi
        shown = cell if cell is not None else f"{value:g}"
        if not math.isfinite(value):
            return f"{self.column} = {_short(shown)} is not a finite number"
        if (
            lo < value < hi
            or (value == lo and not self.lo_open)
            or (value == hi and not self.hi_open)
        ):
            return None
        return f"{self.column} = {_short(shown)} {self.rule()}"

    def rule(self) -> str:
        """The allowed range in words, e.g. ``must be > 0`` or ``must be in [0, 360)``."""
        if math.isinf(self.hi):
            return f"must be {'>' if self.lo_open else '>='} {self.lo:g}"
        if math.isinf(self.lo):
            return f"must be {'<' if self.hi_open else '<='} {self.hi:g}"
        a = "(" if self.lo_open else "["
        b = ")" if self.hi_open else "]"
        note = f" ({self.note})" if self.note else ""
        return f"must be in {a}{self.lo:g}, {self.hi:g}{b}{note}"


def between(
    column: str, lo: float, hi: float, *, lo_open: bool = False, hi_open: bool = False
) -> Check:
    """``lo <= value <= hi`` (``<`` where ``lo_open`` / ``hi_open``)."""
    return Check(column, lo, hi, lo_open, hi_open)


def positive(column: str, hi: float = MAX_DISTANCE_M) -> Check:
    """A length, range or period: ``0 < value <= hi`` (default :data:`MAX_DISTANCE_M`)."""
    return Check(column, 0.0, hi, lo_open=True)


def coordinate(column: str) -> Check:
    """An East/North/Up coordinate in metres: ``|value| <=`` :data:`MAX_DISTANCE_M`."""
    return Check(column, -MAX_DISTANCE_M, MAX_DISTANCE_M)


def seconds(column: str) -> Check:
    """A time in seconds (relative, or Unix before 2100): ``|value| <=`` :data:`MAX_TIME_S`."""
    return Check(column, -MAX_TIME_S, MAX_TIME_S, note="s, relative or Unix time before 2100")


def unix_seconds(column: str) -> Check:
    """An absolute Unix time (s) from 1970-01-01 to before 2100-01-01."""
    return Check(column, 0.0, MAX_TIME_S, hi_open=True, note="Unix time, 1970 to 2100")


def sigma(column: str, hi: float = math.inf) -> Check:
    """A standard deviation: ``0 < value <= hi``."""
    return Check(column, 0.0, hi, lo_open=True)


def angle_deg(column: str) -> Check:
    """A bearing, azimuth, course or heading in degrees: ``[0, 360)``."""
    return Check(column, 0.0, 360.0, hi_open=True)


def latitude(column: str) -> Check:
    """Latitude in degrees: ``[-90, 90]``."""
    return Check(column, -90.0, 90.0)


def longitude(column: str) -> Check:
    """Longitude in degrees: ``[-180, 180]``."""
    return Check(column, -180.0, 180.0)


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
        Number of data rows read (blank lines not counted).
    latin1_lines : tuple of int
        Lines that were not valid UTF-8 and were decoded as Latin-1.
    blank_lines : tuple of int
        Data lines that were empty or held only empty cells (skipped, not counted).
    """

    path: str
    columns: dict[str, NDArray]
    lines: NDArray[np.int64]
    rejected: list[Rejected] = field(default_factory=list)
    n_read: int = 0
    latin1_lines: tuple[int, ...] = ()
    blank_lines: tuple[int, ...] = ()

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


def _short(text: str, limit: int = 40) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def decode_text(data: bytes) -> tuple[str, tuple[int, ...]]:
    """Decode file content: UTF-8 (BOM dropped), else Latin-1 line by line.

    Returns the text and the 1-based numbers of the lines decoded as Latin-1.
    """
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    try:
        return data.decode("utf-8"), ()
    except UnicodeDecodeError:
        pass
    parts: list[str] = []
    latin1: list[int] = []
    for i, raw in enumerate(data.splitlines(keepends=True), start=1):
        try:
            parts.append(raw.decode("utf-8"))
        except UnicodeDecodeError:
            parts.append(raw.decode("latin-1"))
            latin1.append(i)
    return "".join(parts), tuple(latin1)


def check_input_file(path: str | Path, kind: str = "a file") -> Path:
    """The check of every input file before it is read: it exists and is a regular file.

    Parameters
    ----------
    path : the file as the user gave it.
    kind : what is expected, for the message (``"a CSV file"``, ``"an AIS file"``).

    Raises
    ------
    InputError
        ``PATH: file not found`` (also a broken or looping symbolic link, said so), ``PATH:
        is a directory, expected KIND`` or ``PATH: not a regular file (a device, pipe or
        socket), expected KIND``; a compression bomb
        (:func:`seatrack.io.compressed.check_ratio`).
    """
    p = Path(path)
    if not p.exists():
        if p.is_symlink():
            raise InputError(f"{p}: file not found (a broken or looping symbolic link)")
        raise InputError(f"{p}: file not found")
    if p.is_dir():
        raise InputError(f"{p}: is a directory, expected {kind}")
    if not p.is_file():
        raise InputError(f"{p}: not a regular file (a device, pipe or socket), expected {kind}")
    check_ratio(p)
    return p


#: peak bytes of reading one byte of a CSV file into columns (the text, its decoded copy,
#: the parsed rows as Python objects: 11.3 measured with tracemalloc on a 4.2 MB labelled
#: PLOTS file through the row reader; 20 leaves room for files of narrower rows)
READ_BYTES_PER_BYTE = 20
#: longest text cell (a track id, a contact or landmark name), characters
MAX_TEXT_CHARS = 100


def read_input_bytes(p: Path, kind: str = "a CSV file") -> bytes:
    """The content of input file ``p`` (decompressed when gzip, zstd or bzip2 data), after
    :func:`check_input_file` and a memory-budget check from its size
    (:data:`READ_BYTES_PER_BYTE` per byte, :mod:`seatrack.io.budget`).

    Raises
    ------
    InputError
        As :func:`check_input_file`; a file too large for the memory budget, a compression
        bomb or corrupt compressed data (:mod:`seatrack.io.compressed`), naming the file.
    """
    check_input_file(p, kind)
    try:
        size = p.stat().st_size
        require(f"{p}: reading {size} bytes", memory_bytes=READ_BYTES_PER_BYTE * size)
        data = read_input(p)  # decompressed when gzip, zstd or bzip2 (bounded)
    except OSError as exc:
        raise InputError(f"{p}: cannot read ({exc.strerror})") from None
    if len(data) > size:  # was compressed: the decompressed text against the budget
        require(f"{p}: reading {len(data)} decompressed bytes", READ_BYTES_PER_BYTE * len(data))
    return data


def _read_text(p: Path) -> tuple[str, tuple[int, ...]]:
    return decode_text(read_input_bytes(p))


def describe_header(header: Sequence[str], most: int = 12) -> str:
    """The header names of a file as an error message shows them: at most ``most`` names,
    each shortened to 40 characters, a name with unprintable characters (a binary file) as
    its ``repr``; ``"no columns"`` for an empty header."""
    shown = [repr(h) if not h.isprintable() else h for h in header[:most]]
    found = ", ".join(_short(h) for h in shown) + (", ..." if len(header) > most else "")
    return found or "no columns"


def _header_problem(p: Path, header: list[str], missing: list[str]) -> InputError:
    found = describe_header(header)
    hint = ""
    if len(header) == 1 and any(s in header[0] for s in (";", "\t")):
        sep = "';'" if ";" in header[0] else "a tab"
        hint = f" (the file seems to use {sep} as separator; seatrack reads comma-separated CSV)"
    return InputError(f"{p}: missing required column(s) {', '.join(missing)}; found {found}{hint}")


def read_csv_table(
    path: str | Path,
    required: Sequence[str],
    optional: Sequence[str] = (),
    text: Iterable[str] = (),
    on_error: str = "raise",
    checks: Iterable[Check] = (),
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
    checks : allowed ranges of numeric columns (see :class:`Check`); a column without
        one only has to be a finite number. Empty optional cells are not checked.

    Raises
    ------
    InputError
        Missing or unreadable file, missing or duplicated columns, empty file, or
        (``on_error="raise"``) a bad value.
    """
    if on_error not in ("raise", "collect"):
        raise ValueError(f"on_error must be 'raise' or 'collect', got {on_error!r}")
    p = Path(path)
    content, latin1 = _read_text(p)
    text_cols = set(text)
    rules = {c.column: c for c in checks}
    reader = csv.reader(io.StringIO(content, newline=""))
    try:
        header = next(reader)
    except StopIteration:
        raise InputError(f"{p}: file is empty (expected a header row)") from None
    except csv.Error as exc:
        raise InputError(f"{p}, line 1: not valid CSV ({exc})") from None
    header = [h.strip() for h in header]
    missing = [c for c in required if c not in header]
    if missing:
        raise _header_problem(p, header, missing)
    wanted = list(dict.fromkeys(list(required) + [c for c in optional if c in header]))
    twice = [c for c in header if c and header.count(c) > 1]
    if twice:
        raise InputError(f"{p}, line 1: column {twice[0]} appears more than once in the header")
    idx = {c: header.index(c) for c in wanted}
    req = set(required)
    data: dict[str, list] = {c: [] for c in wanted}
    lines: list[int] = []
    rejected: list[Rejected] = []
    blank: list[int] = []
    n_read = 0
    try:
        for row in reader:
            line = reader.line_num
            if not row or all(not c.strip() for c in row):
                blank.append(line)
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
                    if len(cell) > MAX_TEXT_CHARS:
                        problem = (
                            f"column {c} = {_short(repr(cell))} is {len(cell)} characters "
                            f"long; at most {MAX_TEXT_CHARS}"
                        )
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
                    problem = f"column {c} = {_short(repr(cell))} is not a number"
                    break
                if not math.isfinite(v):
                    problem = f"column {c} = {_short(repr(cell))} is not a finite number"
                    break
                rule = rules.get(c)
                if rule is not None:
                    problem = rule.problem(v, cell)
                    if problem is not None:
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
    return Table(
        str(p), cols, np.array(lines, dtype=np.int64), rejected, n_read, latin1, tuple(blank)
    )


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
