"""AIS position reports from CSV exports: readers, validation, local frame, TRACKS.csv.

Three CSV schemas are recognised by their header (extra columns are ignored):

* **common** (the schema of the bundled samples, ``seatrack/data/ais``): ``mmsi, time_utc,
  lat, lon`` and optional
  ``sog_kn, cog_deg, heading_deg``; ``time_utc`` ISO 8601 (``2022-09-01T20:27:05Z``).
* **DMA** (Danish Maritime Authority ``aisdk`` exports): ``# Timestamp, MMSI, Latitude,
  Longitude`` and optional ``SOG, COG, Heading``; timestamps ``dd/mm/yyyy HH:MM:SS`` (UTC).
* **NOAA MarineCadastre**: ``MMSI, BaseDateTime, LAT, LON`` and optional ``SOG, COG,
  Heading``; ``BaseDateTime`` ISO 8601 (UTC).

Every data row of every file becomes one row of :class:`AisReports`. A row that cannot be
used keeps its place and gets a categorical ``reject`` reason (see :data:`REJECT_REASONS`);
nothing is dropped silently. AIS "not available" codes are handled as the ITU-R M.1371
message definitions give them: latitude 91 and longitude 181 reject the row (no position),
SOG 102.3 kn, COG 360 deg and heading 511 become NaN (the row stays usable).

Times are seconds since the Unix epoch (UTC, float). The local East-North frames of the
tracker are :func:`seatrack.geometry.local_frames` and
:func:`seatrack.geometry.local_to_geodetic`.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from seatrack.io.table import InputError, read_csv_table

FloatArray = NDArray[np.float64]

__all__ = [
    "AisReports",
    "SCHEMAS",
    "REJECT_REASONS",
    "detect_schema",
    "read_ais_csv",
    "read_ais",
    "concat_reports",
    "validate_reports",
    "rejection_counts",
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
_REQUIRED = ("mmsi", "time", "lat", "lon")

#: every reason a row can be rejected for (categorical; the line number is kept separately)
REJECT_REASONS = (
    "missing mmsi",
    "invalid mmsi",
    "missing time",
    "unparsable time",
    "missing position",
    "position not a number",
    "position NaN",
    "lat not available (91)",
    "lon not available (181)",
    "lat out of range",
    "lon out of range",
    "bad checksum",
    "incomplete multi-sentence message",
    "undecodable message",
    "duplicate report",
)

#: ITU-R M.1371 "not available" values of the optional fields
SOG_NOT_AVAILABLE_KN = 102.3
COG_NOT_AVAILABLE_DEG = 360.0
HEADING_NOT_AVAILABLE_DEG = 511.0


@dataclass
class AisReports:
    """AIS position reports, one entry per input row (rejected rows included).

    Attributes
    ----------
    sources : tuple of str
        Input files; ``source`` indexes into it.
    source : ndarray of int (N,)
    line : ndarray of int (N,)
        1-based line in the source file (CSV header = line 1).
    mmsi : ndarray of int64 (N,)
        Vessel identifier; -1 where it could not be read.
    t : ndarray (N,)
        Time, seconds since 1970-01-01T00:00:00Z (NaN if unparsable).
    lat, lon : ndarray (N,)
        WGS84 degrees (NaN if missing).
    sog_kn, cog_deg, heading_deg : ndarray (N,)
        Reported speed (kn), course and heading (deg true); NaN if absent/not available.
    reject : ndarray of str (N,)
        ``""`` for a usable row, otherwise one of :data:`REJECT_REASONS`.
    skipped : dict of str -> int
        Input lines that are not position reports and so have no row (NMEA logs only:
        continuation fragments, other message types, non-AIS sentences, blank lines),
        counted by kind. Rows + skipped lines = all lines of the inputs.
    """

    sources: tuple[str, ...]
    source: NDArray[np.int64]
    line: NDArray[np.int64]
    mmsi: NDArray[np.int64]
    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    sog_kn: FloatArray
    cog_deg: FloatArray
    heading_deg: FloatArray
    reject: NDArray[np.str_]
    skipped: dict[str, int] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def valid(self) -> NDArray[np.bool_]:
        """Rows that can be used (no reject reason)."""
        return self.reject == ""


# ---------------------------------------------------------------------------
# Parsing helpers (vectorised with a per-cell fallback for the rare bad cell)
# ---------------------------------------------------------------------------
def _to_float(cells: NDArray[np.str_]) -> tuple[FloatArray, NDArray[np.bool_], NDArray[np.bool_]]:
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


_DMA_TIME = re.compile(r"^(\d{2})/(\d{2})/(\d{4})[ T](\d{2}:\d{2}:\d{2}(?:\.\d+)?)$")


def _parse_time_cell(s: str) -> float:
    """One timestamp (ISO 8601, DMA ``dd/mm/yyyy HH:MM:SS`` or epoch seconds) -> epoch s."""
    m = _DMA_TIME.match(s)
    if m:
        s = f"{m.group(3)}-{m.group(2)}-{m.group(1)}T{m.group(4)}"
    try:
        return float(s)  # epoch seconds
    except ValueError:
        pass
    try:
        d = datetime.fromisoformat(s.replace("Z", "+00:00").replace("z", "+00:00"))
    except ValueError:
        return float("nan")
    if d.tzinfo is None:
        d = d.replace(tzinfo=UTC)  # documented as UTC in all three schemas
    return d.timestamp()


def parse_times(cells: NDArray[np.str_]) -> FloatArray:
    """Timestamps as text -> seconds since the Unix epoch (NaN where unparsable).

    Accepts ISO 8601 (``Z``, an offset, or naive = UTC), DMA ``dd/mm/yyyy HH:MM:SS`` and
    epoch seconds. Fast path: NumPy ``datetime64`` parsing of a whole ISO column.
    """
    cells = np.asarray(cells, dtype=str)
    out = np.full(cells.shape, np.nan)
    if cells.size == 0:
        return out
    nonempty = np.flatnonzero(cells != "")
    sub = cells[nonempty]
    try:
        stripped = np.char.rstrip(sub, "Z")
        if (
            not bool(np.all(np.char.str_len(stripped) >= 19))
            or bool(np.any(np.char.find(stripped, "+") >= 0))
            or bool(np.any(np.char.rfind(stripped, "-") > 9))  # a UTC offset
        ):
            raise ValueError("not plain ISO")
        dt = stripped.astype("datetime64[ms]")
        out[nonempty] = dt.astype(np.int64) / 1000.0
        return out
    except ValueError:
        pass
    out[nonempty] = [_parse_time_cell(s) for s in sub]
    return out


def _header(path: Path) -> list[str]:
    if not path.is_file():
        raise InputError(f"{path}: file not found")
    with path.open(newline="", encoding="utf-8-sig") as fh:
        try:
            row = next(csv.reader(fh))
        except StopIteration:
            raise InputError(f"{path}: file is empty (expected a header row)") from None
        except csv.Error as exc:
            raise InputError(f"{path}, line 1: not valid CSV ({exc})") from None
    return [h.strip() for h in row]


def detect_schema(header: Sequence[str]) -> str:
    """Name of the schema in :data:`SCHEMAS` whose required columns are all in ``header``.

    Raises
    ------
    InputError
        If none matches (the message lists what each schema needs).
    """
    cols = set(header)
    for name, mapping in SCHEMAS.items():
        if all(mapping[f] in cols for f in _REQUIRED):
            return name
    needs = "; ".join(
        f"{name}: {', '.join(m[f] for f in _REQUIRED)}" for name, m in SCHEMAS.items()
    )
    raise InputError(
        f"not a recognised AIS CSV header ({', '.join(header) or 'no columns'}); "
        f"expected the columns of one of: {needs}"
    )


def read_ais_csv(path: str | Path) -> AisReports:
    """Read one AIS CSV file (schema detected from the header), every row accounted for.

    Rows are validated by :func:`validate_reports` (duplicates are marked across the whole
    file). Raises :class:`InputError` for a missing/empty file or an unknown header.
    """
    p = Path(path)
    try:
        schema = detect_schema(_header(p))
    except InputError as exc:
        if str(exc).startswith(str(p)):
            raise
        raise InputError(f"{p}: {exc}") from None
    mapping = SCHEMAS[schema]
    cols = list(mapping.values())
    table = read_csv_table(p, required=(), optional=cols, text=cols, on_error="collect")
    n = len(table)

    def col(field: str) -> NDArray[np.str_]:
        name = mapping[field]
        if name in table:
            return np.asarray(table[name], dtype=str)
        return np.full(n, "", dtype=str)

    reports = _from_text(
        str(p),
        table.lines,
        col("mmsi"),
        col("time"),
        col("lat"),
        col("lon"),
        col("sog"),
        col("cog"),
        col("heading"),
    )
    return validate_reports(reports)


def _from_text(
    source: str,
    lines: NDArray[np.int64],
    mmsi_s: NDArray[np.str_],
    time_s: NDArray[np.str_],
    lat_s: NDArray[np.str_],
    lon_s: NDArray[np.str_],
    sog_s: NDArray[np.str_],
    cog_s: NDArray[np.str_],
    hdg_s: NDArray[np.str_],
) -> AisReports:
    n = lines.size
    reject = np.full(n, "", dtype=object)

    def mark(mask: NDArray[np.bool_], reason: str) -> None:
        m = mask & (reject == "")
        reject[m] = reason

    mm, m_empty, m_bad = _to_float(mmsi_s)
    m_bad |= ~m_empty & ~m_bad & ((mm != np.floor(mm)) | (mm < 0) | ~np.isfinite(mm))
    mark(m_empty, "missing mmsi")
    mark(m_bad, "invalid mmsi")
    mmsi = np.where(m_empty | m_bad, -1, np.nan_to_num(mm, nan=-1.0)).astype(np.int64)

    t = parse_times(time_s)
    mark(time_s == "", "missing time")
    mark(~np.isfinite(t), "unparsable time")

    lat, la_empty, la_bad = _to_float(lat_s)
    lon, lo_empty, lo_bad = _to_float(lon_s)
    mark(la_empty | lo_empty, "missing position")
    mark(la_bad | lo_bad, "position not a number")
    sog, _, sog_bad = _to_float(sog_s)
    cog, _, cog_bad = _to_float(cog_s)
    hdg, _, hdg_bad = _to_float(hdg_s)
    # optional fields that are not numbers are treated as unknown (NaN), not as rejections
    sog[sog_bad] = np.nan
    cog[cog_bad] = np.nan
    hdg[hdg_bad] = np.nan
    return AisReports(
        sources=(source,),
        source=np.zeros(n, dtype=np.int64),
        line=np.asarray(lines, dtype=np.int64),
        mmsi=mmsi,
        t=t,
        lat=lat,
        lon=lon,
        sog_kn=sog,
        cog_deg=cog,
        heading_deg=hdg,
        reject=reject.astype(str) if n else np.zeros(0, dtype=str),
    )


def validate_reports(r: AisReports) -> AisReports:
    """Mark unusable rows (in place) and return ``r``.

    Checks, in order (a row keeps its first reason): NaN position, latitude 91 / longitude
    181 ("not available"), latitude outside [-90, 90], longitude outside [-180, 180], and
    exact duplicates (same mmsi, time, lat and lon as an earlier usable row -- the later
    one is marked). Optional fields with their "not available" codes (SOG 102.3, COG 360,
    heading 511) or out of range are set to NaN.
    """
    reject = r.reject.astype(object)

    def mark(mask: NDArray[np.bool_], reason: str) -> None:
        m = mask & (reject == "")
        reject[m] = reason

    lat, lon = r.lat, r.lon
    mark(np.isnan(lat) | np.isnan(lon), "position NaN")
    mark(lat == 91.0, "lat not available (91)")
    mark(lon == 181.0, "lon not available (181)")
    mark(~(np.abs(lat) <= 90.0), "lat out of range")
    mark(~(np.abs(lon) <= 180.0), "lon out of range")
    r.sog_kn[(r.sog_kn >= SOG_NOT_AVAILABLE_KN - 1e-9) | (r.sog_kn < 0)] = np.nan
    r.cog_deg[(r.cog_deg >= COG_NOT_AVAILABLE_DEG) | (r.cog_deg < 0)] = np.nan
    r.heading_deg[(r.heading_deg >= 360.0) | (r.heading_deg < 0)] = np.nan
    ok = np.flatnonzero(reject == "")
    if ok.size:
        keys = (r.lon[ok], r.lat[ok], r.t[ok], r.mmsi[ok])
        order = np.lexsort(keys)
        srt = [k[order] for k in keys]
        same = np.ones(ok.size - 1, dtype=bool)
        for k in srt:
            same &= k[1:] == k[:-1]
        # lexsort is stable: within a run of equal keys the first in input order comes first
        dup = np.zeros(ok.size, dtype=bool)
        dup[order[1:][same]] = True
        mark(np.isin(np.arange(len(r)), ok[dup]), "duplicate report")
    r.reject = reject.astype(str) if len(r) else np.zeros(0, dtype=str)
    return r


def concat_reports(parts: Sequence[AisReports]) -> AisReports:
    """Concatenate reports of several files (source indices renumbered)."""
    if not parts:
        raise InputError("no AIS input files given")
    sources: list[str] = []
    src = []
    for p in parts:
        src.append(p.source + len(sources))
        sources.extend(p.sources)

    def cat(name: str) -> NDArray:
        return np.concatenate([getattr(p, name) for p in parts])

    skipped: dict[str, int] = {}
    for p in parts:
        for k, v in p.skipped.items():
            skipped[k] = skipped.get(k, 0) + v
    return AisReports(
        tuple(sources),
        np.concatenate(src),
        cat("line"),
        cat("mmsi"),
        cat("t"),
        cat("lat"),
        cat("lon"),
        cat("sog_kn"),
        cat("cog_deg"),
        cat("heading_deg"),
        cat("reject"),
        skipped,
    )


def read_ais(paths: Sequence[str | Path]) -> AisReports:
    """Read AIS files (CSV by header, NMEA logs by content) and concatenate them.

    A file whose first non-empty line starts with ``!``, ``\\`` or ``$`` after an optional
    timestamp is read as NMEA by :func:`seatrack.io.nmea.read_nmea`. Duplicates are marked
    across all files together.
    """
    from seatrack.io.nmea import looks_like_nmea, read_nmea

    parts = []
    for p in paths:
        pp = Path(p)
        parts.append(read_nmea(pp) if looks_like_nmea(pp) else read_ais_csv(pp))
    r = concat_reports(parts)
    if len(parts) > 1:
        # duplicates across files (e.g. overlapping exports); reasons already set stay
        r.reject = np.where(r.reject == "duplicate report", "", r.reject)
        validate_reports(r)
    return r


def rejection_counts(r: AisReports) -> dict[str, int]:
    """Number of rejected rows per reason (only reasons that occur), in a stable order."""
    out: dict[str, int] = {}
    reasons, counts = np.unique(r.reject[r.reject != ""], return_counts=True)
    found = dict(zip(reasons.tolist(), counts.tolist(), strict=True))
    for reason in REJECT_REASONS:
        if reason in found:
            out[reason] = int(found.pop(reason))
    out.update({k: int(v) for k, v in found.items()})
    return out


# ---------------------------------------------------------------------------
# TRACKS.csv
# ---------------------------------------------------------------------------
def format_times(t: FloatArray) -> list[str]:
    """Epoch seconds -> ISO 8601 UTC text (``...Z``; milliseconds only when needed)."""
    t = np.asarray(t, dtype=float)
    out = [""] * t.size
    ok = np.isfinite(t)
    if ok.any():
        ms = np.round(t[ok] * 1000.0).astype(np.int64)
        unit = "s" if bool(np.all(ms % 1000 == 0)) else "ms"
        txt = np.datetime_as_string(ms.astype("datetime64[ms]"), unit=unit)  # type: ignore[call-overload]
        for i, s in zip(np.flatnonzero(ok).tolist(), txt.tolist(), strict=True):
            out[i] = s + "Z"
    return out


def output_order(r: AisReports) -> NDArray[np.int64]:
    """Row order of TRACKS.csv: vessels in order of first appearance, input order within
    each vessel (file, then line); rows without a readable MMSI last, in input order."""
    n = len(r)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    key_in = r.source * (int(r.line.max()) + 1) + r.line
    order_in = np.argsort(key_in, kind="stable")
    m_in = r.mmsi[order_in]
    vessels, first_pos = np.unique(m_in, return_index=True)
    rank = np.empty(vessels.size, dtype=np.int64)
    rank[np.argsort(first_pos, kind="stable")] = np.arange(vessels.size)
    vr = rank[np.searchsorted(vessels, r.mmsi)]
    vr[r.mmsi < 0] = vessels.size + 1
    return np.lexsort((key_in, vr)).astype(np.int64)


def _fmt_block(cols: list[NDArray], specs: list[str]) -> list[str]:
    """Comma-joined fixed-point text of float columns, one string per row (NaN -> empty)."""
    if not cols:
        return []
    fmt = ",".join("%" + sp for sp in specs)
    m = np.column_stack([np.asarray(c, dtype=float) for c in cols])
    return [(fmt % tuple(row)).replace("nan", "") for row in m.tolist()]


def _text(a: NDArray) -> list[str]:
    """CSV-quoted text of a column with few distinct values (one quote per value)."""
    vals, inv = np.unique(np.asarray(a).astype(str), return_inverse=True)
    q = [_quote(v) for v in vals.tolist()]
    return [q[i] for i in inv.ravel().tolist()]


def _quote(text: str) -> str:
    if any(ch in text for ch in ',"\n\r'):
        return '"' + text.replace('"', '""') + '"'
    return text


#: TRACKS.csv columns -> format spec of the value (text columns are given as strings)
TRACK_COLUMNS: dict[str, str] = {
    "lat": ".7f",
    "lon": ".7f",
    "course_deg": ".2f",
    "speed_kn": ".3f",
    "turn_rate_dps": ".4f",
    "std_pos_m": ".2f",
    "std_course_deg": ".2f",
    "std_speed_kn": ".3f",
    "std_turn_rate_dps": ".4f",
    "x_m": ".2f",
    "y_m": ".2f",
    "time_offset_s": ".0f",
}


def write_tracks_csv(path: str | Path, r: AisReports, columns: dict[str, NDArray]) -> int:
    """Write TRACKS.csv: one row per input row of ``r`` (order of :func:`output_order`).

    Columns: ``mmsi, time_utc``, the numeric ``columns`` given (named as in
    :data:`TRACK_COLUMNS`, one value per row of ``r``, NaN written empty), ``outlier``
    (0/1, from ``columns["outlier"]``), ``outlier_reason`` and ``segment`` (if given),
    ``raw_lat, raw_lon, reject_reason, source, line``. Returns the number of rows written.
    """
    order = output_order(r)
    n = order.size
    names = [c for c in TRACK_COLUMNS if c in columns]
    block = _fmt_block(
        [np.asarray(columns[c])[order] for c in names], [TRACK_COLUMNS[c] for c in names]
    )
    raw = _fmt_block([r.lat[order], r.lon[order]], [".6f", ".6f"])
    mmsi = [str(v) if v >= 0 else "" for v in r.mmsi[order].tolist()]
    times = format_times(r.t[order])
    out = np.asarray(columns.get("outlier", np.zeros(len(r), bool)), dtype=bool)[order]
    extra_h: list[str] = []
    extra: list[list[str]] = [["1" if v else "0" for v in out.tolist()]]
    if "outlier_reason" in columns:
        extra_h.append("outlier_reason")
        extra.append(_text(np.asarray(columns["outlier_reason"])[order]))
    if "segment" in columns:
        extra_h.append("segment")
        seg = np.asarray(columns["segment"])[order].tolist()
        extra.append([str(v) if v >= 0 else "" for v in seg])
    mid = [",".join(t) for t in zip(*extra, strict=True)]
    srcs = [_quote(s) for s in r.sources]
    tail = [
        f"{reason},{srcs[k]},{ln}"
        for reason, k, ln in zip(
            _text(r.reject[order]),
            r.source[order].tolist(),
            r.line[order].tolist(),
            strict=True,
        )
    ]
    header = [
        "mmsi",
        "time_utc",
        *names,
        "outlier",
        *extra_h,
        "raw_lat",
        "raw_lon",
        "reject_reason",
        "source",
        "line",
    ]
    if names:
        lines = [
            f"{a},{b},{c},{d},{e},{f}\n"
            for a, b, c, d, e, f in zip(mmsi, times, block, mid, raw, tail, strict=True)
        ]
    else:
        lines = [
            f"{a},{b},{d},{e},{f}\n"
            for a, b, d, e, f in zip(mmsi, times, mid, raw, tail, strict=True)
        ]
    p = Path(path)
    try:
        with p.open("w", newline="", encoding="utf-8") as fh:
            fh.write(",".join(header) + "\n")
            fh.writelines(lines)
    except OSError as exc:
        raise InputError(f"{p}: cannot write ({exc.strerror})") from exc
    return n
