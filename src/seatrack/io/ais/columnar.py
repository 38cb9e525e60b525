"""Columnar AIS readers (pyarrow): CSV of the three schemas, gzip/zstd/bz2-compressed CSV,
and Parquet, streamed in blocks of rows.

Three CSV schemas are recognised by their header (extra columns are ignored and not parsed):

* **common** (the schema of the bundled samples, ``seatrack/data/ais``): ``mmsi, time_utc,
  lat, lon`` and optional ``sog_kn, cog_deg, heading_deg``; ``time_utc`` ISO 8601
  (``2022-09-01T20:27:05Z``).
* **DMA** (Danish Maritime Authority ``aisdk`` exports, 26 columns): ``# Timestamp, MMSI,
  Latitude, Longitude`` and optional ``SOG, COG, Heading``; ``dd/mm/yyyy HH:MM:SS`` (UTC).
* **NOAA MarineCadastre**: ``MMSI, BaseDateTime, LAT, LON`` and optional ``SOG, COG,
  Heading``; ``BaseDateTime`` ISO 8601 (UTC).

Line numbers. pyarrow does not report them, so a CSV file is read on the fast path only when
every line is one row: the reader counts the line ends of the (decompressed) stream while
pyarrow parses it, and a file whose row count is not its line count minus the header (blank
lines, quoted line breaks), or that pyarrow cannot parse (a wrong number of fields, bytes
that are not UTF-8 in a parsed column) raises :class:`NotColumnar`; the caller then reads it
line by line (:mod:`seatrack.io.ais.lines`), which accounts for every line. A cell that is
not a number in a numeric column switches the file to text columns converted by NumPy, with
the same reasons as the line reader.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.io.ais.reports import AisReports
from seatrack.io.ais.reports import check_rows
from seatrack.io.ais.reports import mark
from seatrack.io.ais.reports import mmsi_codes
from seatrack.io.ais.reports import parse_times
from seatrack.io.table import MAX_TEXT_CHARS
from seatrack.io.table import InputError
from seatrack.io.table import describe_header

FloatArray = NDArray[np.float64]

__all__ = [
    "SCHEMAS",
    "REQUIRED",
    "NotColumnar",
    "detect_schema",
    "read_header",
    "open_input",
    "is_parquet",
    "iter_csv_blocks",
    "iter_parquet_blocks",
    "from_text_columns",
]

#: schema name -> canonical field -> column name in the file
SCHEMAS: dict[str, dict[str, str]] = {
    "common": {
        "mmsi": "mmsi",
        "time": "time_utc",
        "lat": "lat",
        "lon": "lon",
        "sog": "sog_kn",
        "cog": "cog_deg",
        "heading": "heading_deg",
    },
    "dma": {
        "mmsi": "MMSI",
        "time": "# Timestamp",
        "lat": "Latitude",
        "lon": "Longitude",
        "sog": "SOG",
        "cog": "COG",
        "heading": "Heading",
    },
    "noaa": {
        "mmsi": "MMSI",
        "time": "BaseDateTime",
        "lat": "LAT",
        "lon": "LON",
        "sog": "SOG",
        "cog": "COG",
        "heading": "Heading",
    },
}
REQUIRED = ("mmsi", "time", "lat", "lon")
_NUMERIC = ("mmsi", "lat", "lon", "sog", "cog", "heading")
#: time formats tried by pyarrow before the general parser (:func:`parse_times`)
_TIME_FORMATS = (
    "%Y-%m-%dT%H:%M:%SZ",
    "%Y-%m-%dT%H:%M:%S",
    "%d/%m/%Y %H:%M:%S",
    "%Y-%m-%d %H:%M:%S",
)


class NotColumnar(Exception):
    """The file cannot be read on the columnar fast path with exact line numbers."""


def detect_schema(header: Sequence[str]) -> str:
    """Name of the schema in :data:`SCHEMAS` whose required columns are all in ``header``.

    Raises
    ------
    InputError
        If none matches (the message lists what each schema needs).
    """
    cols = set(header)
    for name, mapping in SCHEMAS.items():
        if all(mapping[f] in cols for f in REQUIRED):
            return name
    needs = "; ".join(f"{name}: {', '.join(m[f] for f in REQUIRED)}" for name, m in SCHEMAS.items())
    raise InputError(
        f"not a recognised AIS CSV header ({describe_header(header)}); "
        f"expected the columns of one of: {needs}"
    )


def open_input(path: Path, whole: bool = False) -> Any:
    """A binary stream of ``path``, decompressed when it holds gzip, zstd or bzip2 data
    (by its magic bytes, whatever its suffix), in bounded chunks
    (:func:`seatrack.io.compressed.open_input`)."""
    from seatrack.io.compressed import open_input as open_bounded

    return open_bounded(path, whole)


def is_parquet(path: Path) -> bool:
    """True for a Parquet file (by its ``PAR1`` magic)."""
    with path.open("rb") as fh:
        return fh.read(4) == b"PAR1"


def read_header(path: Path) -> list[str]:
    """The first line of a (maybe compressed) CSV file as column names, as written (BOM
    removed, white space kept: pyarrow selects columns by their exact names)."""
    with open_input(path) as stream:
        head = stream.read(1 << 16)
    lines = head.splitlines()  # LF, CRLF or CR line ends
    first = lines[0] if lines else b""
    if not first.strip():
        raise InputError(f"{path}: file is empty (expected a header row)")
    text = first.decode("utf-8", errors="replace").lstrip("\ufeff")
    try:
        row = next(csv.reader([text]))
    except csv.Error as exc:
        raise InputError(f"{path}, line 1: not valid CSV ({exc})") from None
    return row


class _CountingReader(io.RawIOBase):
    """A file object over a pyarrow stream that counts line ends as pyarrow reads it."""

    def __init__(self, stream: Any) -> None:
        self.stream = stream
        self.newlines = 0
        self.nbytes = 0
        self.last = b""

    def readable(self) -> bool:
        return True

    def readinto(self, b: Any) -> int:
        data = self.stream.read(len(b))
        n = len(data)
        if n:
            b[:n] = data
            self.newlines += data.count(b"\n")
            self.nbytes += n
            self.last = data[-1:]
        return n

    def lines(self) -> int:
        """Number of lines read (a last line without its line end counts)."""
        return self.newlines + (1 if self.nbytes and self.last != b"\n" else 0)


def _time_column(col: Any) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Times (epoch s; NaN unparsable) and the missing mask of a pyarrow string column."""
    import pyarrow as pa
    import pyarrow.compute as pc

    if pa.types.is_timestamp(col.type):
        missing = col.is_null().to_numpy(zero_copy_only=False)
        ms = pc.cast(pc.cast(col, pa.timestamp("ms")), pa.int64()).to_numpy(zero_copy_only=False)
        return np.where(missing, np.nan, ms / 1000.0), missing
    if not pa.types.is_string(col.type) and not pa.types.is_large_string(col.type):
        col = pc.cast(col, pa.string())
    text = pc.fill_null(col, "")
    missing = pc.equal(text, "").to_numpy(zero_copy_only=False)
    t = np.full(len(text), np.nan)
    todo = ~missing
    for fmt in _TIME_FORMATS:
        if not todo.any():
            break
        ts = pc.strptime(text, format=fmt, unit="ms", error_is_null=True)
        ms = pc.cast(ts, "int64")
        got = todo & ~ms.is_null().to_numpy(zero_copy_only=False)
        t[got] = ms.to_numpy(zero_copy_only=False)[got] / 1000.0
        todo &= ~got
    if todo.any():  # fractional seconds, offsets, epoch seconds
        idx = np.flatnonzero(todo)
        cells = [bounded_cell(c) for c in text.take(idx).to_pylist()]
        t[idx] = parse_times(np.asarray(cells, dtype=str))
    return t, missing


#: what a cell longer than :data:`~seatrack.io.table.MAX_TEXT_CHARS` is read as: no number,
#: no time (its row is rejected for the field, with its line), and a text of one character
#: instead of a copy as wide as the longest cell on every row of the block
TOO_LONG = "#"


def bounded_cell(text: str) -> str:
    """``text``, or :data:`TOO_LONG` when it has more than ``MAX_TEXT_CHARS`` characters."""
    return text if len(text) <= MAX_TEXT_CHARS else TOO_LONG


def _bounded_column(col: Any) -> NDArray[np.object_]:
    """A text column (pyarrow) as an object array of its cells (empty for a null), cells
    over ``MAX_TEXT_CHARS`` characters replaced by :data:`TOO_LONG`."""
    import pyarrow.compute as pc

    col = col.fill_null("")
    if (pc.max(pc.utf8_length(col)).as_py() or 0) > MAX_TEXT_CHARS:
        col = pc.if_else(pc.greater(pc.utf8_length(col), MAX_TEXT_CHARS), TOO_LONG, col)
    return np.asarray(col.to_numpy(zero_copy_only=False), dtype=object)


def _to_float(cells: NDArray[Any]) -> tuple[FloatArray, NDArray[np.bool_], NDArray[np.bool_]]:
    """Text cells -> (values, empty mask, not-a-number mask). Empty/bad cells are NaN."""
    empty = cells == ""
    out = np.full(cells.shape, np.nan)
    bad = np.zeros(cells.shape, dtype=bool)
    idx = np.flatnonzero(~empty)
    try:
        out[idx] = cells[idx].astype(np.float64)
    except ValueError:
        for i in idx:
            try:
                out[i] = float(cells[i])
            except ValueError:
                bad[i] = True
    return out, empty, bad


def _assemble(
    source: str,
    lines: NDArray[np.int64],
    num: dict[str, tuple[FloatArray, NDArray[np.bool_], NDArray[np.bool_]]],
    t: FloatArray,
    t_missing: NDArray[np.bool_],
) -> AisReports:
    """Rows from parsed columns (values, missing, not-a-number per numeric field), with the
    row checks of :func:`check_rows` (not the duplicates)."""
    n = lines.size
    code = np.zeros(n, dtype=np.int8)
    mmsi = mmsi_codes(*num["mmsi"], code)
    mark(code, t_missing, "missing time")
    mark(code, ~np.isfinite(t), "unparsable time")
    lat, la_miss, la_bad = num["lat"]
    lon, lo_miss, lo_bad = num["lon"]
    mark(code, la_miss | lo_miss, "missing position")
    mark(code, la_bad | lo_bad, "position not a number")
    opt = []
    for f in ("sog", "cog", "heading"):
        v, _, bad = num[f]
        v = v.copy()
        v[bad] = np.nan  # optional fields that are not numbers are unknown, not rejections
        opt.append(v)
    r = AisReports(
        (source,),
        np.zeros(n, dtype=np.int64),
        np.asarray(lines, dtype=np.int64),
        mmsi,
        t,
        lat,
        lon,
        opt[0],
        opt[1],
        opt[2],
        code,
    )
    return check_rows(r)


def from_text_columns(
    source: str, lines: NDArray[np.int64], cols: dict[str, NDArray[Any]]
) -> AisReports:
    """Rows from text cells per canonical field (missing fields: empty cells); the cells
    are object arrays (one pointer per row, however long the longest cell)."""
    n = lines.size
    empty = np.full(n, "", dtype=object)
    num = {f: _to_float(np.asarray(cols.get(f, empty), dtype=object)) for f in _NUMERIC}
    time_s = np.asarray(cols.get("time", empty), dtype=str)
    return _assemble(source, lines, num, parse_times(time_s), time_s == "")


def _batch(
    source: str, batch: Any, mapping: dict[str, str], first_line: int, text: bool
) -> AisReports:
    """One pyarrow record batch -> rows (``text``: all columns read as strings)."""
    n = batch.num_rows
    lines = np.arange(first_line, first_line + n, dtype=np.int64)
    names = set(batch.schema.names)
    if text:
        cols = {f: _bounded_column(batch.column(c)) for f, c in mapping.items() if c in names}
        return from_text_columns(source, lines, cols)
    num = {}
    for f in _NUMERIC:
        c = mapping.get(f, "")
        if c in names:
            col = batch.column(c)
            missing = col.is_null().to_numpy(zero_copy_only=False)
            vals = col.to_numpy(zero_copy_only=False).astype(np.float64)
            num[f] = (np.where(missing, np.nan, vals), missing, np.zeros(n, dtype=bool))
        else:
            num[f] = (np.full(n, np.nan), np.ones(n, dtype=bool), np.zeros(n, dtype=bool))
    t, t_missing = _time_column(batch.column(mapping["time"]))
    return _assemble(source, lines, num, t, t_missing)


def iter_csv_blocks(
    path: Path, block_bytes: int = 64 << 20, text: bool = False
) -> Iterator[AisReports]:
    """Rows of a CSV file in blocks (one source, ``source`` 0), validated row by row (not
    for duplicates). ``text``: read the columns as strings (a cell that is not a number in
    a numeric column raises :class:`NotColumnar` otherwise).

    Raises
    ------
    NotColumnar
        When the file's rows are not one per line or pyarrow cannot parse it (the caller
        reads it line by line); raised after the blocks read so far were yielded.
    InputError
        Unknown header, empty or unreadable file.
    """
    import pyarrow as pa
    import pyarrow.csv as pcsv

    header = read_header(path)
    if any(h != h.strip() for h in header):  # the line reader strips the names
        raise NotColumnar("column names padded with white space")
    try:
        schema = detect_schema(header)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    mapping = {f: c for f, c in SCHEMAS[schema].items() if c in header}
    if len(set(header)) != len(header):
        raise NotColumnar("duplicate column names")
    types = {c: (pa.string() if text or f == "time" else pa.float64()) for f, c in mapping.items()}
    counter = _CountingReader(open_input(path))
    try:
        reader = pcsv.open_csv(
            io.BufferedReader(counter, buffer_size=1 << 20),
            read_options=pcsv.ReadOptions(block_size=block_bytes, use_threads=True),
            parse_options=pcsv.ParseOptions(newlines_in_values=False),
            convert_options=pcsv.ConvertOptions(
                column_types=types,
                include_columns=list(mapping.values()),
                null_values=[""],
                strings_can_be_null=False,
                quoted_strings_can_be_null=False,
            ),
        )
        first = 2
        for batch in reader:
            yield _batch(str(path), batch, mapping, first, text)
            first += batch.num_rows
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError, UnicodeDecodeError) as exc:
        raise NotColumnar(str(exc)) from None
    finally:
        counter.stream.close()
    if first - 1 != counter.lines():
        raise NotColumnar(f"{first - 2} rows in {counter.lines()} lines")


def iter_parquet_blocks(path: Path, batch_rows: int = 1 << 20) -> Iterator[AisReports]:
    """Rows of a Parquet file (columns named as in one of :data:`SCHEMAS`) in blocks;
    ``line`` is the row number + 1 (as if a header were line 1)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(str(path))
    except (OSError, pa.ArrowInvalid) as exc:
        raise InputError(f"{path}: not a readable Parquet file ({exc})") from None
    header = pf.schema_arrow.names
    try:
        schema = detect_schema(header)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    mapping = {f: c for f, c in SCHEMAS[schema].items() if c in header}
    first = 2
    for batch in pf.iter_batches(batch_size=batch_rows, columns=list(mapping.values())):
        numeric = all(
            pa.types.is_integer(batch.column(c).type) or pa.types.is_floating(batch.column(c).type)
            for f, c in mapping.items()
            if f != "time"
        )
        if not numeric:  # text columns: converted cell by cell with reasons
            batch = pa.record_batch(
                [batch.column(c).cast(pa.string()) for c in batch.schema.names],
                names=batch.schema.names,
            )
        rows = _batch(str(path), batch, mapping, first, text=not numeric)
        yield rows
        first += batch.num_rows
