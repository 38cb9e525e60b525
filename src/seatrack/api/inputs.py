"""Inputs of the public API: a path, a pandas DataFrame, a pyarrow Table or a dict of arrays.

Every API function reads its data with the same reader as the command line, so a table
passed from Python is checked exactly as a CSV file is (the same columns, the same limits,
the same messages). An in-memory table is written to a temporary CSV file with the CSV
column names (floats written with all their digits, missing values empty) and read back by
the command's reader; an :class:`~seatrack.io.table.InputError` then names the table
(``plots (DataFrame), row 3: range_m must be > 0``, rows counted from 0) instead of the
temporary file.

Outputs are read back the same way from the files the commands write
(:func:`read_frame`), so that a frame returned by the API holds exactly the values of the
command's output file.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from collections.abc import Iterable
from collections.abc import Iterator
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from seatrack.io.table import InputError

__all__ = ["Source", "as_file", "to_arrow", "read_frame", "describe_source"]

#: what the API accepts as a table: a file path, a DataFrame, a pyarrow Table or a mapping
#: of column name -> array
Source = Any


def describe_source(data: Source) -> str:
    """``DataFrame``, ``pyarrow Table``, ``dict`` or the path itself."""
    if isinstance(data, (str, os.PathLike)):
        return str(data)
    mod = type(data).__module__.split(".")[0]
    if mod == "pandas":
        return "DataFrame"
    if mod == "pyarrow":
        return "pyarrow Table"
    if isinstance(data, Mapping):
        return "dict"
    return type(data).__name__


def to_arrow(data: Source, what: str) -> Any:
    """A pyarrow Table of an in-memory table (DataFrame, pyarrow Table or mapping).

    Raises
    ------
    InputError
        Not a table, or a dict whose columns are not 1-D arrays of one length.
    """
    import numpy as np
    import pyarrow as pa

    if isinstance(data, pa.Table):
        return data
    if type(data).__module__.split(".")[0] == "pandas" and hasattr(data, "columns"):
        return pa.Table.from_pandas(data, preserve_index=False)
    if isinstance(data, Mapping):
        cols: dict[str, Any] = {}
        n = None
        for k, v in data.items():
            a = np.asarray(v)
            if a.ndim != 1:
                raise InputError(f"{what} (dict): column {k!r} must be 1-D, got shape {a.shape}")
            if n is not None and a.size != n:
                raise InputError(f"{what} (dict): column {k!r} has {a.size} values, the others {n}")
            n = a.size
            cols[str(k)] = a.astype(str) if a.dtype.kind in "US" else a
        return pa.table(cols)
    raise InputError(
        f"{what}: expected a file path, a pandas DataFrame, a pyarrow Table or a dict of "
        f"arrays, got {type(data).__name__}"
    )


def _write_csv(table: Any, path: Path) -> None:
    """CSV with the column names as header; NaN written empty (missing), as in the files."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.csv as pacsv

    cols = []
    for col in table.columns:
        if pa.types.is_floating(col.type):
            col = pc.if_else(pc.is_nan(col), pa.scalar(None, col.type), col)
        elif pa.types.is_dictionary(col.type):
            col = col.cast(pa.string())
        cols.append(col)
    out = pa.table(cols, names=table.column_names)
    if out.num_rows == 0:  # header only
        path.write_text(",".join(table.column_names) + "\n")
        return
    pacsv.write_csv(out, str(path), pacsv.WriteOptions(quoting_style="needed"))


def _relabel(message: str, tmp: str, label: str) -> str:
    """The message with the temporary file named ``label`` and lines as 0-based rows."""
    if tmp not in message:
        return message
    out = message.replace(tmp, label)
    return re.sub(
        re.escape(label) + r", line (\d+)", lambda m: f"{label}, row {int(m.group(1)) - 2}", out
    )


@contextlib.contextmanager
def as_file(data: Source, what: str, *, suffix: str = ".csv") -> Iterator[Path]:
    """A path holding ``data``: the path itself, or a temporary CSV file of the table.

    ``what`` names the input in messages (``plots``, ``bearings``, ...). Inside the block an
    :class:`InputError` about the temporary file is re-raised naming ``what`` and the kind
    of table, with 0-based row numbers.
    """
    if isinstance(data, (str, os.PathLike)):
        yield Path(data)
        return
    table = to_arrow(data, what)
    label = f"{what} ({describe_source(data)})"
    with tempfile.TemporaryDirectory(prefix="seatrack-") as folder:
        path = Path(folder) / f"{what}{suffix}"
        _write_csv(table, path)
        try:
            yield path
        except InputError as exc:
            raise InputError(_relabel(str(exc), str(path), label)) from None


def read_frame(path: str | Path, text: Iterable[str] = ()) -> Any:
    """A CSV file written by seatrack as a pandas DataFrame: ``text`` columns as strings
    (empty cells ``""``), every other column as float64 or int64 (empty cells NaN).

    The numbers are parsed with correct rounding, so the frame holds exactly the values of
    the file.
    """
    import pyarrow as pa
    import pyarrow.csv as pacsv

    p = Path(path)
    with p.open(encoding="utf-8-sig") as fh:
        header = fh.readline().rstrip("\r\n").split(",")
    names = [h.strip('"') for h in header]
    strings = {c: pa.string() for c in text if c in names}
    table = pacsv.read_csv(
        str(p),
        convert_options=pacsv.ConvertOptions(column_types=strings, strings_can_be_null=False),
    )
    frame = table.to_pandas()
    for c in strings:
        frame[c] = frame[c].astype(object)
    return frame
