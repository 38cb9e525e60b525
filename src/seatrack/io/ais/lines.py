"""The line-by-line AIS reader: every line of a file accounted for, CSV and NMEA mixed.

Used for NMEA logs and for CSV files the columnar reader cannot read with exact line numbers
(:class:`~seatrack.io.ais.columnar.NotColumnar`). Each line is, in this order:

* blank -> a rejected row ``"blank line"``;
* an NMEA sentence (maybe after a time prefix) -> :func:`~seatrack.io.ais.nmea.nmea_rows`;
* a CSV header of one of the schemas -> the columns of the CSV rows that follow (a header
  after the first line is counted in ``skipped`` as ``"CSV header"``);
* a CSV row after a header -> a report (``"wrong number of fields"`` if its field count is
  not the header's, ``"empty row"`` if all its cells are empty);
* anything else -> a rejected row ``"not an AIS line"``.

So a file that switches from NMEA to CSV (or back) loses no valid report. Bytes that are not
UTF-8 are read as Latin-1 (ship names of AIS exports), line by line; a file is never refused
for its encoding.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from seatrack.io.ais.columnar import SCHEMAS
from seatrack.io.ais.columnar import bounded_cell
from seatrack.io.ais.columnar import detect_schema
from seatrack.io.ais.columnar import from_text_columns
from seatrack.io.ais.columnar import open_input
from seatrack.io.ais.nmea import is_nmea_line
from seatrack.io.ais.nmea import nmea_rows
from seatrack.io.ais.reports import AisReports
from seatrack.io.ais.reports import concat_reports
from seatrack.io.ais.reports import mark
from seatrack.io.ais.reports import reject_code
from seatrack.io.table import InputError

__all__ = ["read_lines", "parse_lines", "decode_line"]


def decode_line(raw: bytes) -> str:
    """UTF-8, else Latin-1 (every byte is a Latin-1 character)."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _header_schema(fields: list[str]) -> str | None:
    try:
        return detect_schema([f.strip() for f in fields])
    except InputError:
        return None


def parse_lines(lines: list[bytes], source: str) -> AisReports:
    """Rows of the lines of one file (without line ends; line 1 first), every line
    accounted for (see the module docstring); rows in line order, not checked for
    duplicates."""
    nmea: list[tuple[int, bytes]] = []
    rejects: list[tuple[int, str]] = []
    csv_lines: list[int] = []
    csv_cells: dict[str, list[str]] = {f: [] for f in SCHEMAS["common"]}
    skipped: dict[str, int] = {}
    cols: dict[str, int] | None = None
    width = 0
    for i, raw in enumerate(lines, start=1):
        line = raw.strip()
        if i == 1 and line.startswith(b"\xef\xbb\xbf"):
            line = line[3:].strip()
        if not line:
            rejects.append((i, "blank line"))
            continue
        if is_nmea_line(line):
            nmea.append((i, line))
            continue
        try:
            fields = next(csv.reader([decode_line(line)]))
        except (csv.Error, StopIteration):
            rejects.append((i, "not an AIS line"))
            continue
        schema = _header_schema(fields)
        if schema is not None:
            names = [f.strip() for f in fields]
            cols = {f: names.index(c) for f, c in SCHEMAS[schema].items() if c in names}
            width = len(fields)
            if i > 1:
                skipped["CSV header"] = skipped.get("CSV header", 0) + 1
            continue
        if cols is None:
            rejects.append((i, "not an AIS line"))
        elif len(fields) != width:
            rejects.append((i, "wrong number of fields"))
        elif all(not f.strip() for f in fields):
            rejects.append((i, "empty row"))
        else:
            csv_lines.append(i)
            for f, cells in csv_cells.items():
                k = cols.get(f, -1)
                cells.append(bounded_cell(fields[k].strip()) if k >= 0 else "")
    parts = [_csv_part(source, csv_lines, csv_cells), _nmea_part(source, nmea, skipped)]
    parts.append(_reject_part(source, rejects))
    r = concat_reports(parts)
    r.sources = (source,)
    r.source[:] = 0
    order = np.argsort(r.line, kind="stable")
    out = r.take(order)
    out.skipped = skipped
    return out


def _csv_part(source: str, lines: list[int], cells: dict[str, list[str]]) -> AisReports:
    n = len(lines)
    cols = {f: np.asarray(v, dtype=object) for f, v in cells.items() if n}
    return from_text_columns(source, np.asarray(lines, dtype=np.int64), cols)


def _nmea_part(source: str, items: list[tuple[int, bytes]], skipped: dict[str, int]) -> AisReports:
    from seatrack.io.ais.reports import check_rows

    rows, skip = nmea_rows(items)
    for k, v in skip.items():
        skipped[k] = skipped.get(k, 0) + v
    n = len(rows)
    c = list(zip(*rows, strict=True)) if n else [()] * 9
    r = AisReports(
        (source,),
        np.zeros(n, dtype=np.int64),
        np.array(c[0], dtype=np.int64),
        np.array(c[1], dtype=np.int64),
        np.array(c[2], dtype=float),
        np.array(c[3], dtype=float),
        np.array(c[4], dtype=float),
        np.array(c[5], dtype=float),
        np.array(c[6], dtype=float),
        np.array(c[7], dtype=float),
        np.array([reject_code(x) for x in c[8]], dtype=np.int8),
    )
    # rows rejected above keep their reason; check the rest (time, ranges, n/a codes)
    mark(r.code, ~np.isfinite(r.t), "unparsable time")
    return check_rows(r)


def _reject_part(source: str, rejects: list[tuple[int, str]]) -> AisReports:
    n = len(rejects)
    nan = np.full(n, np.nan)
    return AisReports(
        (source,),
        np.zeros(n, dtype=np.int64),
        np.array([ln for ln, _ in rejects], dtype=np.int64),
        np.full(n, -1, dtype=np.int64),
        nan.copy(),
        nan.copy(),
        nan.copy(),
        nan.copy(),
        nan.copy(),
        nan.copy(),
        np.array([reject_code(x) for _, x in rejects], dtype=np.int8),
    )


def read_lines(path: Path) -> AisReports:
    """Read a whole (maybe compressed) file line by line (see the module docstring)."""
    with open_input(path, whole=True) as stream:
        data = stream.read()
    if not data.strip():
        raise InputError(f"{path}: file is empty")
    # universal line ends (LF, CRLF and the old CR alone), as Python's text files read them
    return parse_lines(data.splitlines(), str(path))
