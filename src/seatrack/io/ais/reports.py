"""AIS position reports as columns (:class:`AisReports`), their validation and reject reasons.

Every input line that can hold a report becomes one row; a row that cannot be used keeps its
place and gets a categorical reject code (:data:`REJECT_REASONS`); nothing is dropped
silently. AIS "not available" codes are handled as the ITU-R M.1371 message definitions give
them: latitude 91 and longitude 181 reject the row (no position), SOG 102.3 kn, COG 360 deg
and heading 511 become NaN (the row stays usable). An MMSI must be an integer of at most nine
digits (small integers, as in anonymised exports, are accepted); a time must lie in
1970-2100.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from datetime import UTC
from datetime import datetime

import numpy as np
from numpy.typing import NDArray

from seatrack.geometry import LocalFrame
from seatrack.geometry import local_frames
from seatrack.io.table import InputError

FloatArray = NDArray[np.float64]

__all__ = [
    "AisReports",
    "REJECT_REASONS",
    "reject_code",
    "concat_reports",
    "check_rows",
    "mark_duplicates",
    "validate_reports",
    "rejection_counts",
    "output_order",
    "parse_times",
    "MMSI_MAX",
    "TIME_MIN",
    "TIME_MAX",
    "to_local",
]

#: every reason a row can be rejected for (categorical; the line number is kept separately)
REJECT_REASONS = (
    "missing mmsi",
    "invalid mmsi",
    "missing time",
    "unparsable time",
    "time out of range",
    "missing position",
    "position not a number",
    "position NaN",
    "lat not available (91)",
    "lon not available (181)",
    "lat out of range",
    "lon out of range",
    "bad checksum",
    "truncated sentence",
    "incomplete multi-sentence message",
    "undecodable message",
    "blank line",
    "empty row",
    "wrong number of fields",
    "not an AIS line",
    "duplicate report",
)
#: label of each reject code (code 0 = usable row: empty)
REASON_LABELS = np.array(("",) + REJECT_REASONS, dtype=object)
_CODE = {r: k for k, r in enumerate(REASON_LABELS.tolist())}

#: largest MMSI (nine digits)
MMSI_MAX = 999_999_999
#: accepted times, s since the epoch: 1970-01-01 .. 2100-01-01
TIME_MIN = 0.0
TIME_MAX = 4_102_444_800.0

#: ITU-R M.1371 "not available" values of the optional fields
SOG_NOT_AVAILABLE_KN = 102.3
COG_NOT_AVAILABLE_DEG = 360.0


def reject_code(reason: str) -> int:
    """Code of a reject reason (0 = usable row)."""
    return _CODE[reason]


@dataclass
class AisReports:
    """AIS position reports, one entry per input row (rejected rows included).

    Attributes
    ----------
    sources : tuple of str
        Input files; ``source`` indexes into it.
    source : ndarray of int (N,)
    line : ndarray of int (N,)
        1-based line in the source file (CSV header = line 1; for Parquet the row + 1).
    mmsi : ndarray of int64 (N,)
        Vessel identifier; -1 where it could not be read.
    t : ndarray (N,)
        Time, seconds since 1970-01-01T00:00:00Z (NaN if unparsable).
    lat, lon : ndarray (N,)
        WGS84 degrees (NaN if missing).
    sog_kn, cog_deg, heading_deg : ndarray (N,)
        Reported speed (kn), course and heading (deg true); NaN if absent/not available.
    code : ndarray of int8 (N,)
        0 for a usable row, else ``k`` for ``REJECT_REASONS[k - 1]`` (see :attr:`reject`).
    skipped : dict of str -> int
        Input lines that are valid but hold no position report (NMEA: continuation
        fragments, other message types, other NMEA sentences; CSV header lines after the
        first), counted by kind. Rows + skipped lines + the first header = all lines.
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
    code: NDArray[np.int8]
    skipped: dict[str, int] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def valid(self) -> NDArray[np.bool_]:
        """Rows that can be used (no reject reason)."""
        return self.code == 0

    @property
    def reject(self) -> NDArray[np.str_]:
        """Reject reason per row (``""`` for a usable row)."""
        return REASON_LABELS[self.code].astype(str) if len(self) else np.zeros(0, dtype=str)

    def take(self, rows: NDArray[np.int64] | NDArray[np.bool_]) -> AisReports:
        """The rows ``rows`` (same sources; no skipped counts)."""
        return AisReports(
            self.sources,
            self.source[rows],
            self.line[rows],
            self.mmsi[rows],
            self.t[rows],
            self.lat[rows],
            self.lon[rows],
            self.sog_kn[rows],
            self.cog_deg[rows],
            self.heading_deg[rows],
            self.code[rows],
        )

    @staticmethod
    def empty(sources: tuple[str, ...] = ()) -> AisReports:
        """A table without rows."""
        f = np.zeros(0)
        i = np.zeros(0, dtype=np.int64)
        return AisReports(sources, i, i, i, f, f, f, f, f, f, np.zeros(0, dtype=np.int8))


def to_local(r: AisReports) -> LocalFrame:
    """The usable rows in one tangent plane per vessel
    (:func:`seatrack.geometry.local_frames`)."""
    return local_frames(r.mmsi, r.lat, r.lon, r.valid)


def mark(code: NDArray[np.int8], mask: NDArray[np.bool_], reason: str) -> None:
    """Give rows in ``mask`` that have no reason yet the reason ``reason`` (in place)."""
    code[mask & (code == 0)] = _CODE[reason]


def mmsi_codes(
    value: FloatArray, missing: NDArray[np.bool_], bad: NDArray[np.bool_], code: NDArray[np.int8]
) -> NDArray[np.int64]:
    """MMSI column from its numeric value: marks missing and invalid ones (not a number, not
    an integer, negative, more than nine digits, not finite) and returns -1 for them."""
    with np.errstate(invalid="ignore"):
        bad = bad | (~missing & ~(np.isfinite(value) & (value >= 0) & (value <= MMSI_MAX)))
        bad |= ~missing & ~bad & (value != np.floor(value))
    mark(code, missing, "missing mmsi")
    mark(code, bad, "invalid mmsi")
    out = np.full(value.shape, -1, dtype=np.int64)
    ok = ~missing & ~bad
    out[ok] = value[ok].astype(np.int64)
    return out


def check_rows(r: AisReports) -> AisReports:
    """Row checks (in place; a row keeps its first reason): time 1970-2100, NaN position,
    latitude 91 / longitude 181 ("not available"), latitude outside [-90, 90], longitude
    outside [-180, 180]. Optional fields with their "not available" codes (SOG 102.3, COG
    360, heading 511) or out of range are set to NaN. Duplicates: :func:`mark_duplicates`."""
    code = r.code
    with np.errstate(invalid="ignore"):
        mark(code, np.isfinite(r.t) & ~((r.t >= TIME_MIN) & (r.t < TIME_MAX)), "time out of range")
        lat, lon = r.lat, r.lon
        mark(code, np.isnan(lat) | np.isnan(lon), "position NaN")
        mark(code, lat == 91.0, "lat not available (91)")
        mark(code, lon == 181.0, "lon not available (181)")
        mark(code, ~(np.abs(lat) <= 90.0), "lat out of range")
        mark(code, ~(np.abs(lon) <= 180.0), "lon out of range")
        r.sog_kn[(r.sog_kn >= SOG_NOT_AVAILABLE_KN - 1e-9) | (r.sog_kn < 0)] = np.nan
        r.cog_deg[(r.cog_deg >= COG_NOT_AVAILABLE_DEG) | (r.cog_deg < 0)] = np.nan
        r.heading_deg[(r.heading_deg >= 360.0) | (r.heading_deg < 0)] = np.nan
    return r


def mark_duplicates(r: AisReports) -> AisReports:
    """Mark exact duplicates (same mmsi, time, lat and lon as an earlier usable row in
    input order -- the later one is marked), in place. Rows must be in input order (file,
    then line) within each vessel."""
    ok = np.flatnonzero(r.code == 0)
    if ok.size < 2:
        return r
    keys = (r.lon[ok], r.lat[ok], r.t[ok], r.mmsi[ok])
    order = np.lexsort(keys)
    same = np.ones(ok.size - 1, dtype=bool)
    for k in keys:
        ks = k[order]
        same &= ks[1:] == ks[:-1]
    # lexsort is stable: within a run of equal keys the first in input order comes first
    r.code[ok[order[1:][same]]] = _CODE["duplicate report"]
    return r


def validate_reports(r: AisReports) -> AisReports:
    """:func:`check_rows` then :func:`mark_duplicates` (in place); returns ``r``."""
    return mark_duplicates(check_rows(r))


def concat_reports(parts: Sequence[AisReports]) -> AisReports:
    """Concatenate reports of several files (source indices renumbered)."""
    if not parts:
        raise InputError("no AIS input files given")
    sources: list[str] = []
    src = []
    skipped: dict[str, int] = {}
    for p in parts:
        src.append(p.source + len(sources))
        sources.extend(p.sources)
        for k, v in p.skipped.items():
            skipped[k] = skipped.get(k, 0) + v

    def cat(name: str) -> NDArray:
        return np.concatenate([getattr(p, name) for p in parts])

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
        cat("code").astype(np.int8),
        skipped,
    )


def rejection_counts(r: AisReports | NDArray[np.int64]) -> dict[str, int]:
    """Number of rejected rows per reason (only reasons that occur), in the order of
    :data:`REJECT_REASONS`; ``r`` may also be counts per code (``bincount`` of codes)."""
    counts = np.bincount(r.code, minlength=REASON_LABELS.size) if isinstance(r, AisReports) else r
    return {
        str(REASON_LABELS[k]): int(counts[k])
        for k in range(1, min(counts.size, REASON_LABELS.size))
        if counts[k]
    }


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


# ---------------------------------------------------------------------------
# Times
# ---------------------------------------------------------------------------
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
    try:
        return d.timestamp()
    except (OverflowError, ValueError, OSError):
        return float("nan")


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
