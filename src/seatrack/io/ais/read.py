"""Reading AIS files of any supported kind: CSV (plain or compressed), Parquet, NMEA logs.

:func:`file_blocks` chooses the reader of a file: Parquet by its magic bytes; NMEA logs (first
non-blank line an NMEA sentence) and CSV files that are not one row per line line by line
(:mod:`seatrack.io.ais.lines`); other CSV files through pyarrow in blocks
(:mod:`seatrack.io.ais.columnar`), with text columns when a numeric cell is not a number.
Every line gets a row (or a count in ``skipped``) with its line number either way.
"""

from __future__ import annotations

from collections.abc import Iterator
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from seatrack.io.ais.columnar import NotColumnar
from seatrack.io.ais.columnar import is_parquet
from seatrack.io.ais.columnar import iter_csv_blocks
from seatrack.io.ais.columnar import iter_parquet_blocks
from seatrack.io.ais.columnar import open_input
from seatrack.io.ais.lines import read_lines
from seatrack.io.ais.nmea import is_nmea_line
from seatrack.io.ais.reports import AisReports
from seatrack.io.ais.reports import concat_reports
from seatrack.io.ais.reports import mark_duplicates
from seatrack.io.table import InputError
from seatrack.io.table import check_input_file

__all__ = ["file_blocks", "read_file", "read_ais", "read_ais_csv", "looks_like_nmea"]


def looks_like_nmea(path: str | Path) -> bool:
    """True if the first non-blank line of ``path`` is an NMEA sentence (maybe time-prefixed)."""
    p = Path(path)
    with open_input(p) as stream:
        head = stream.read(1 << 16)
    for raw in head.splitlines():
        line = raw.strip().lstrip(b"\xef\xbb\xbf")
        if line:
            return is_nmea_line(line)
    return False


def _check_file(p: Path) -> None:
    check_input_file(p, "an AIS file")
    if p.stat().st_size == 0:
        raise InputError(f"{p}: file is empty")


def file_blocks(path: str | Path, block_bytes: int = 64 << 20) -> Iterator[list[AisReports]]:
    """The rows of one file as lists of blocks (one list per attempt: a caller keeps only
    the last list it receives; on the columnar path a file that turns out not to be one row
    per line is read again line by line and yields a second list). Rows are row-checked, not
    for duplicates."""
    p = Path(path)
    _check_file(p)
    if is_parquet(p):
        yield list(iter_parquet_blocks(p))
        return
    if looks_like_nmea(p):
        yield [read_lines(p)]
        return
    for text in (False, True):
        blocks: list[AisReports] = []
        try:
            for b in iter_csv_blocks(p, block_bytes, text=text):
                blocks.append(b)
            yield blocks
            return
        except NotColumnar as exc:
            if not text and "conversion error" in str(exc).lower():
                continue  # a cell that is not a number: read the columns as text
            break
    yield [read_lines(p)]


def read_file(path: str | Path) -> AisReports:
    """All rows of one file (not checked for duplicates)."""
    blocks: list[AisReports] = []
    for attempt in file_blocks(path):
        blocks = attempt
    if not blocks:
        return AisReports.empty((str(path),))
    r = concat_reports(blocks)
    r.sources = (str(path),)
    r.source[:] = 0
    r.skipped = blocks[0].skipped if len(blocks) == 1 else r.skipped
    return r


def read_ais_csv(path: str | Path) -> AisReports:
    """Read one AIS file (schema detected from the header), every row accounted for and
    duplicates marked. Raises :class:`InputError` for a missing/empty file or an unknown
    header."""
    return mark_duplicates(read_file(path))


def read_ais(paths: Sequence[str | Path]) -> AisReports:
    """Read AIS files of any supported kind and concatenate them; duplicates are marked
    across all files together (the later report of the same vessel, time and position)."""
    if not paths:
        raise InputError("no AIS input files given")
    r = concat_reports([read_file(p) for p in paths])
    if len(r):
        # input order within each vessel is (source, line): the concatenation order
        mark_duplicates(r)
    return r


def rows_by_line(r: AisReports) -> AisReports:
    """``r`` sorted by (source, line)."""
    return r.take(np.lexsort((r.line, r.source)))
