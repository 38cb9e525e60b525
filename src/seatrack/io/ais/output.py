"""TRACKS output of ``seatrack ais``: one row per input row, as CSV or Parquet.

Columns: ``mmsi, time_utc``, the track values of :data:`TRACK_COLUMNS` (fixed decimals in
CSV, NaN written empty), ``outlier`` (0/1), ``outlier_reason``, ``segment`` (number within
the vessel), ``raw_lat, raw_lon, reject_reason, source, line``. Rows are written in the order
of :func:`~seatrack.io.ais.reports.output_order`, group by group (:class:`TracksWriter`),
through :mod:`seatrack.io.atomic`: the file appears complete or not at all. The CSV text is
formatted column by column in pyarrow (no Python work per row); Parquet keeps full
precision with typed columns (``time_utc`` a UTC timestamp, missing values null).
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais import OUTLIER_KINDS
from seatrack.geometry import bearing_rad_to_deg
from seatrack.geometry import mps_to_knots
from seatrack.io.ais.reports import REASON_LABELS
from seatrack.io.ais.reports import TIME_MAX
from seatrack.io.ais.reports import TIME_MIN
from seatrack.io.ais.reports import AisReports
from seatrack.io.ais.reports import output_order
from seatrack.io.atomic import atomic_path

__all__ = [
    "TRACK_COLUMNS",
    "HEADER",
    "TracksWriter",
    "format_times",
    "track_columns",
    "tracks_csv_bytes",
    "table_csv_bytes",
    "write_table",
    "tracks_table",
    "write_tracks",
    "write_tracks_csv",
    "out_format",
]

#: TRACKS columns -> decimals in CSV
TRACK_COLUMNS: dict[str, int] = {
    "lat": 7,
    "lon": 7,
    "course_deg": 2,
    "speed_kn": 3,
    "turn_rate_dps": 4,
    "std_pos_m": 2,
    "std_course_deg": 2,
    "std_speed_kn": 3,
    "std_turn_rate_dps": 4,
    "x_m": 2,
    "y_m": 2,
    "time_offset_s": 0,
}
HEADER = [
    "mmsi",
    "time_utc",
    *TRACK_COLUMNS,
    "outlier",
    "outlier_reason",
    "segment",
    "raw_lat",
    "raw_lon",
    "reject_reason",
    "source",
    "line",
]


#: outlier kind -> reason written (0: not an outlier)
_OUTLIER_LABELS = ["", *(OUTLIER_KINDS[k] for k in sorted(OUTLIER_KINDS))]


def track_columns(tracks: Any) -> dict[str, NDArray]:
    """TRACKS value columns (degrees / knots) from :class:`~seatrack.filters.ais.AisTracks`."""
    course = np.asarray(tracks.course, float)
    course_deg = np.full(course.shape, np.nan)
    ok = np.isfinite(course)
    course_deg[ok] = bearing_rad_to_deg(course[ok])
    return {
        "lat": tracks.lat,
        "lon": tracks.lon,
        "course_deg": course_deg,
        "speed_kn": mps_to_knots(tracks.speed),
        "turn_rate_dps": np.degrees(tracks.turn_rate),
        "std_pos_m": tracks.std_pos_m,
        "std_course_deg": np.degrees(tracks.std_course),
        "std_speed_kn": mps_to_knots(tracks.std_speed),
        "std_turn_rate_dps": np.degrees(tracks.std_turn_rate),
        "x_m": tracks.x_m,
        "y_m": tracks.y_m,
        "time_offset_s": tracks.time_offset_s,
        "outlier": tracks.outlier,
        "outlier_kind": tracks.outlier_kind,
        "segment": tracks.segment,
    }


def out_format(path: str | Path) -> str:
    """``"parquet"`` for a ``.parquet``/``.pq`` path, else ``"csv"``."""
    return "parquet" if Path(path).suffix.lower() in (".parquet", ".pq") else "csv"


def _times(t: NDArray[np.float64]) -> Any:
    """ISO 8601 UTC text (``...Z``; milliseconds only where not whole seconds); null for
    rows without a time in 1970-2100."""
    import pyarrow as pa
    import pyarrow.compute as pc

    ok = np.isfinite(t) & (t >= TIME_MIN) & (t < TIME_MAX)
    ms = np.rint(np.where(ok, t, 0.0) * 1000.0).astype(np.int64)
    whole = ms % 1000 == 0
    # pyarrow's cast writes "YYYY-MM-DD HH:MM:SS[.mmm]" (strftime is 25x slower)
    text = pc.cast(pa.array(ms // 1000, pa.timestamp("s")), pa.string())
    if not whole.all():
        frac = pc.cast(pa.array(ms, pa.timestamp("ms")), pa.string())
        text = pc.if_else(pa.array(whole), text, frac)
    text = pc.replace_substring(text, " ", "T", max_replacements=1)
    text = pc.binary_join_element_wise(text, "Z", "")
    return pc.if_else(pa.array(ok), text, pa.scalar(None, pa.string()))


def format_times(t: NDArray[np.float64]) -> list[str]:
    """Epoch seconds -> ISO 8601 UTC text (``...Z``; milliseconds only where needed; ``""``
    outside 1970-2100)."""
    return [s or "" for s in _times(np.asarray(t, dtype=float)).to_pylist()]


def _quote(text: str) -> str:
    if any(ch in text for ch in ',"\n\r'):
        return '"' + text.replace('"', '""') + '"'
    return text


def _prepare(r: AisReports, columns: dict[str, NDArray]) -> tuple[AisReports, dict[str, NDArray]]:
    """Rows and columns in output order."""
    order = output_order(r)
    return r.take(order), {k: np.asarray(v)[order] for k, v in columns.items()}


def _ms(t: NDArray[np.float64]) -> NDArray[np.int64]:
    """Epoch milliseconds of times in 1970-2100, -1 elsewhere."""
    ok = np.isfinite(t) & (t >= TIME_MIN) & (t < TIME_MAX)
    return np.where(ok, np.rint(np.where(ok, t, 0.0) * 1000.0), -1).astype(np.int64)


def _csv_body(r: AisReports, columns: dict[str, NDArray]) -> NDArray[np.uint8]:
    """CSV rows of ``r`` in output order (compiled; no copies of the columns)."""
    from seatrack.io.ais.csvtext import csv_rows

    n = len(r)
    order = output_order(r)
    nan = np.full(n, np.nan)

    def take(a: NDArray) -> NDArray:  # gathered column by column: the writer reads in order
        return np.asarray(a)[order]

    cols = {k: np.asarray(v) for k, v in columns.items()}
    return csv_rows(
        np.arange(n),
        take(r.mmsi),
        take(_ms(r.t)),
        [take(cols[c]) if c in cols else nan for c in TRACK_COLUMNS],
        np.array(list(TRACK_COLUMNS.values()), dtype=np.int64),
        take(cols.get("outlier", np.zeros(n, dtype=bool))),
        take(cols.get("outlier_kind", np.zeros(n, dtype=np.int64))),
        take(cols.get("segment", np.full(n, -1, dtype=np.int64))),
        [take(r.lat), take(r.lon)],
        take(r.code),
        take(r.source),
        take(r.line),
        _OUTLIER_LABELS,
        list(REASON_LABELS),
        list(r.sources),
    )


def tracks_csv_bytes(r: AisReports, columns: dict[str, NDArray], header: bool = True) -> bytes:
    """TRACKS CSV text of the rows of ``r`` (in output order) and their track ``columns``
    (:func:`track_columns`: one value per row of ``r``)."""
    body = _csv_body(r, columns).tobytes()
    return (",".join(HEADER) + "\n").encode() + body if header else body


def _numpy(col: Any, dtype: Any, fill: Any) -> NDArray:
    return np.asarray(col.fill_null(fill).to_numpy(zero_copy_only=False), dtype=dtype)


def _codes(col: Any) -> tuple[NDArray[np.int64], list[str]]:
    """Dictionary codes and labels of a string column (null -> the label "")."""
    import pyarrow as pa

    enc = col.fill_null("").dictionary_encode()
    if isinstance(enc, pa.ChunkedArray):
        enc = pa.concat_arrays(enc.chunks) if enc.num_chunks else pa.array([], enc.type)
    idx = np.asarray(enc.indices.to_numpy(zero_copy_only=False), dtype=np.int64)
    return idx, [str(v) for v in enc.dictionary.to_pylist()]


def table_csv_bytes(table: Any, header: bool = True) -> bytes:
    """CSV text of a TRACKS table (:func:`tracks_table`): fixed decimals of
    :data:`TRACK_COLUMNS` (raw positions 6), ``outlier`` 0/1, times ISO 8601, missing
    values empty (compiled: :func:`seatrack.io.ais.csvtext.csv_rows`)."""
    import pyarrow as pa

    from seatrack.io.ais.csvtext import csv_rows

    def col(name: str, dtype: Any, fill: Any) -> NDArray:
        return _numpy(table.column(name), dtype, fill)

    ms = col("time_utc", np.int64, -1) if table.num_rows else np.zeros(0, np.int64)
    if table.num_rows:
        ms = _numpy(
            table.column("time_utc").cast(pa.timestamp("ms")).cast(pa.int64()), np.int64, -1
        )
    values = [col(c, np.float64, np.nan) for c in TRACK_COLUMNS]
    kind, kinds = _codes(table.column("outlier_reason"))
    code, reasons = _codes(table.column("reject_reason"))
    source, sources = _codes(table.column("source"))
    body = csv_rows(
        np.arange(table.num_rows),
        col("mmsi", np.int64, -1),
        ms,
        values,
        np.array(list(TRACK_COLUMNS.values()), dtype=np.int64),
        col("outlier", np.bool_, False),
        kind,
        col("segment", np.int64, -1),
        [col("raw_lat", np.float64, np.nan), col("raw_lon", np.float64, np.nan)],
        code,
        source,
        col("line", np.int64, 0),
        kinds,
        reasons,
        sources,
    )
    return (",".join(HEADER) + "\n").encode() + body.tobytes() if header else body.tobytes()


def write_table(writer: TracksWriter, table: Any) -> None:
    """Append a TRACKS table (rows already in output order) to an open writer."""
    writer.write_table(table)


def tracks_table(r: AisReports, columns: dict[str, NDArray]) -> Any:
    """TRACKS as a typed pyarrow table (output order; full precision; null = missing)."""
    import pyarrow as pa

    r, cols = _prepare(r, columns)
    n = len(r)

    def num(x: NDArray) -> Any:
        x = np.asarray(x, dtype=float)
        return pa.array(x, pa.float64(), mask=~np.isfinite(x))

    ok_t = np.isfinite(r.t) & (r.t >= TIME_MIN) & (r.t < TIME_MAX)
    ms = np.rint(np.where(ok_t, r.t, 0.0) * 1000.0).astype(np.int64)
    data: dict[str, Any] = {
        "mmsi": pa.array(r.mmsi, pa.int64(), mask=r.mmsi < 0),
        "time_utc": pa.array(ms, pa.timestamp("ms", tz="UTC"), mask=~ok_t),
    }
    for c in TRACK_COLUMNS:
        data[c] = num(cols[c]) if c in cols else pa.nulls(n, pa.float64())
    data["outlier"] = pa.array(np.asarray(cols.get("outlier", np.zeros(n, bool)), dtype=bool))
    kind = np.asarray(cols.get("outlier_kind", np.zeros(n, np.int8)), dtype=np.int64)
    labels = _OUTLIER_LABELS
    data["outlier_reason"] = pa.array(np.asarray(labels, dtype=object)[kind], pa.string())
    seg = np.asarray(cols.get("segment", np.full(n, -1)), dtype=np.int64)
    data["segment"] = pa.array(seg, pa.int64(), mask=seg < 0)
    data["raw_lat"] = num(r.lat)
    data["raw_lon"] = num(r.lon)
    data["reject_reason"] = pa.array(REASON_LABELS[r.code], pa.string())
    data["source"] = pa.array(np.asarray(r.sources, dtype=object)[r.source], pa.string())
    data["line"] = pa.array(r.line, pa.int64())
    return pa.table(data)


class TracksWriter(contextlib.AbstractContextManager["TracksWriter"]):
    """Write TRACKS group by group to ``path`` (CSV or Parquet by its suffix) atomically:
    the file replaces ``path`` only when the ``with`` block ends without an error."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.format = out_format(path)
        self.rows = 0
        self._ctx = atomic_path(self.path)
        self._fh: Any = None
        self._pq: Any = None

    def __enter__(self) -> TracksWriter:
        tmp = self._ctx.__enter__()
        self._tmp = tmp
        if self.format == "csv":
            self._fh = open(tmp, "wb")  # noqa: SIM115 - closed in __exit__
            self._fh.write((",".join(HEADER) + "\n").encode())
        return self

    def write(self, r: AisReports, columns: dict[str, NDArray]) -> None:
        """Append the rows of ``r`` (a group of whole vessels) in output order."""
        if self.format == "csv":
            self._fh.write(_csv_body(r, columns).data)
            self.rows += len(r)
        else:
            self.write_table(tracks_table(r, columns))

    def write_table(self, table: Any) -> None:
        """Append a TRACKS table (:func:`tracks_table`, rows in output order)."""
        if self.format == "csv":
            self._fh.write(table_csv_bytes(table, header=False))
        else:
            import pyarrow.parquet as pq

            if self._pq is None:
                self._pq = pq.ParquetWriter(str(self._tmp), table.schema, compression="zstd")
            self._pq.write_table(table)
        self.rows += table.num_rows

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> bool | None:
        try:
            if self._fh is not None:
                self._fh.close()
            if self.format == "parquet":
                if self._pq is None:  # no rows: an empty table with the columns
                    import pyarrow.parquet as pq

                    empty = tracks_table(AisReports.empty(), {})
                    pq.write_table(empty, str(self._tmp), compression="zstd")
                else:
                    self._pq.close()
        except BaseException as err:
            return self._ctx.__exit__(type(err), err, err.__traceback__)
        return self._ctx.__exit__(exc_type, exc, tb)


def write_tracks(path: str | Path, r: AisReports, columns: dict[str, NDArray]) -> int:
    """Write all rows of ``r`` to ``path`` (CSV or Parquet); returns the rows written."""
    with TracksWriter(path) as w:
        w.write(r, columns)
    return w.rows


def write_tracks_csv(path: str | Path, r: AisReports, columns: dict[str, NDArray]) -> int:
    """:func:`write_tracks` under its CSV-only name (the format follows the suffix)."""
    return write_tracks(path, r, columns)
