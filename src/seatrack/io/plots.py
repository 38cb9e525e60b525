"""Radar / sonar plot files (``PLOTS.csv``) for ``seatrack track``.

Columns (header names exact; extra columns allowed):

* ``track`` (optional): run / track id; rows of one id form one track. Without the column
  the file is one track labelled ``1``; with it, an empty id is an error.
* ``time_s``: seconds, strictly increasing within a track.
* ``range_m``: slant range, m (> 0).
* ``azimuth_deg``: true azimuth / bearing, degrees clockwise from North, in [0, 360).
* ``elevation_deg`` (optional): degrees up; absent -> 2-D plots.
* ``range_rate_mps`` (optional): m/s, positive opening.
* ``sensor_x_m``, ``sensor_y_m``, ``sensor_z_m`` (optional): sensor position (East, North,
  Up); absent -> sensor at the origin. Sensor velocity (for range rate) is taken from the
  finite differences of its positions.

Values must be physically plausible (:data:`LIMITS`): a range of 1e308 m or a time gap of
1e15 s within a track is refused with its file and line, not tracked. Inside seatrack
angles are radians (converted here, at the edge); the result is a
:class:`seatrack.filters.base.Plots` with the track label of every plot.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import Plots
from seatrack.filters.registry import compact_labels
from seatrack.filters.registry import track_index
from seatrack.io.suspect import km_warning
from seatrack.io.suspect import ms_warning
from seatrack.io.suspect import radians_warning
from seatrack.io.suspect import warn
from seatrack.io.table import MAX_DISTANCE_M
from seatrack.io.table import MAX_TEXT_CHARS
from seatrack.io.table import MAX_TIME_S
from seatrack.io.table import InputError
from seatrack.io.table import Table
from seatrack.io.table import check_times
from seatrack.io.table import read_csv_table
from seatrack.io.table import read_input_bytes

FloatArray = NDArray[np.float64]

__all__ = [
    "read_plots",
    "read_plot_tracks",
    "split_tracks",
    "unit_warnings",
    "PLOT_COLUMNS",
    "LIMITS",
]

PLOT_COLUMNS = ("time_s", "range_m", "azimuth_deg")
_OPTIONAL = (
    "track",
    "elevation_deg",
    "range_rate_mps",
    "sensor_x_m",
    "sensor_y_m",
    "sensor_z_m",
)
_SENSOR = ("sensor_x_m", "sensor_y_m", "sensor_z_m")

#: plausibility limits (absolute values): beyond them a value is an input error
LIMITS = {
    "range_m": 1e7,  # 10,000 km: beyond any radar or sonar
    "min_range_m": 1e-3,  # 1 mm: below any radar or sonar (a denormal number is a bug)
    "time_s": MAX_TIME_S,  # seconds: Unix time of 2100-01-01
    "gap_s": 1e6,  # 11.6 days between two plots of one track
    "range_rate_mps": 1e4,  # 10 km/s
    "sensor_m": MAX_DISTANCE_M,  # 100,000 km from the origin of the local frame
}


def read_plots(path: str | Path) -> Plots:
    """Read and validate a PLOTS.csv file: all plots, each with its track label.

    Raises
    ------
    InputError
        Naming the file, line and problem: missing columns, NaN/inf or empty values,
        non-positive or implausible range, azimuth outside [0, 360), elevation outside
        [-90, 90], implausible times or time gaps, unsorted or duplicate times within a
        track, an empty track id, a column present for only some rows.
    """
    tab = _read_fast(Path(path))
    if tab is None:  # anything unusual: the row-by-row reader, with its exact messages
        tab = read_csv_table(path, PLOT_COLUMNS, _OPTIONAL, text=("track",))
    _check_values(tab)
    if not _times_increase(tab):
        check_times(tab, "time_s", group="track", strict=True)
    n = len(tab)
    labels = compact_labels(tab["track"]) if "track" in tab else np.full(n, "1")
    _check_gaps(tab, labels)
    unit_warnings(tab, labels)
    t = tab["time_s"]
    sensor = np.zeros((n, 3))
    for k, c in enumerate(_SENSOR):
        if c in tab:
            sensor[:, k] = tab[c]
    return Plots(
        t=t,
        range=tab["range_m"],
        azimuth=np.radians(tab["azimuth_deg"]),
        elevation=np.radians(tab["elevation_deg"]) if "elevation_deg" in tab else None,
        range_rate=tab["range_rate_mps"] if "range_rate_mps" in tab else None,
        sensor=sensor,
        sensor_vel=_sensor_velocity(t, sensor, labels),
        line=tab.lines,
        track=labels,
    )


def unit_warnings(tab: Table, labels: NDArray[Any] | None = None) -> None:
    """Warn (one line each, :mod:`seatrack.io.suspect`) when azimuths look like radians,
    ranges like kilometres or times like milliseconds."""
    codes = None if labels is None else track_index(labels)[0]
    warn(
        (
            radians_warning(tab.path, "azimuth_deg", tab["azimuth_deg"]),
            km_warning(tab.path, "range_m", tab["range_m"]),
            ms_warning(tab.path, "time_s", tab["time_s"], None if labels is None else codes),
        )
    )


def _read_fast(path: Path) -> Table | None:
    """Columnar read (pyarrow) of a well-formed file, or None for anything unusual (blank
    lines, quoted line breaks, padded or empty required cells, text in number columns,
    literal NaN/inf...), which the row-by-row reader then reports with its line."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.csv as pacsv

    data = read_input_bytes(path)  # within the memory budget, decompressed
    head = data.split(b"\n", 1)[0].decode("utf-8-sig", "replace").rstrip("\r").split(",")
    if any(h != h.strip() for h in head) or not set(PLOT_COLUMNS) <= set(head):
        return None
    if len(set(head)) != len(head):  # a column named twice: reported by the row reader
        return None
    present = [c for c in (*PLOT_COLUMNS, *_OPTIONAL) if c in head]
    types = {c: (pa.string() if c == "track" else pa.float64()) for c in present}
    try:
        table = pacsv.read_csv(
            pa.BufferReader(data),
            convert_options=pacsv.ConvertOptions(
                include_columns=present, column_types=types, strings_can_be_null=False
            ),
        )
    except (pa.ArrowException, UnicodeDecodeError):
        return None
    n = table.num_rows
    if n == 0 or data.count(b"\n") + (not data.endswith(b"\n")) != n + 1:
        return None
    cols: dict[str, NDArray[np.generic]] = {}
    for c in present:
        col = table.column(c)
        if c == "track":
            longest = pc.max(pc.utf8_length(col)).as_py() or 0
            if longest > MAX_TEXT_CHARS:  # reported with its line by the row reader
                return None
            enc = pc.dictionary_encode(col).combine_chunks()
            names = enc.dictionary.to_pylist()
            if any(s.strip() != s for s in names):
                return None
            table_of_names = np.empty(len(names), dtype=object)
            table_of_names[:] = names  # one str per distinct id: 8 bytes per row
            codes = enc.indices.to_numpy(zero_copy_only=False)
            cols[c] = table_of_names[codes]
            continue
        a = col.to_numpy(zero_copy_only=False).astype(float)
        given = ~np.asarray(col.is_null().to_numpy(zero_copy_only=False), dtype=bool)
        if not np.isfinite(a[given]).all() or (c in PLOT_COLUMNS and not given.all()):
            return None
        cols[c] = np.where(given, a, np.nan)
    return Table(str(path), cols, np.arange(2, n + 2, dtype=np.int64), [], n)


def _times_increase(tab: Table) -> bool:
    """True when times strictly increase within every track (vectorised)."""
    keys = track_index(tab["track"])[0] if "track" in tab else np.zeros(len(tab), np.int64)
    order = np.argsort(keys, kind="stable")
    same = keys[order][1:] == keys[order][:-1]
    return bool(np.all(np.diff(tab["time_s"][order])[same] > 0))


def split_tracks(plots: Plots) -> list[Plots]:
    """The plots of each track (order of first appearance), each a :class:`Plots`."""
    labels = plots.track if plots.track is not None else np.full(len(plots), "1")
    codes, names = track_index(labels)
    order = np.argsort(codes, kind="stable")
    bounds = np.searchsorted(codes[order], np.arange(len(names) + 1))
    return [plots.take(order[bounds[k] : bounds[k + 1]]) for k in range(len(names))]


def read_plot_tracks(path: str | Path) -> list[Plots]:
    """:func:`read_plots` split by track (:func:`split_tracks`)."""
    return split_tracks(read_plots(path))


def _sensor_velocity(t: FloatArray, s: FloatArray, labels: NDArray[Any]) -> FloatArray:
    """Finite-difference sensor velocity, per track (``np.gradient``, 2nd order inside)."""
    v = np.zeros_like(s)
    if not s.any():
        return v
    codes, names = track_index(labels)
    order = np.argsort(codes, kind="stable")
    bounds = np.searchsorted(codes[order], np.arange(len(names) + 1))
    for k in range(len(names)):
        ix = order[bounds[k] : bounds[k + 1]]
        if ix.size >= 2:
            v[ix] = np.gradient(s[ix], t[ix], axis=0)
    return v


def _bad(tab: Table, mask: NDArray[np.bool_], what: str) -> None:
    if mask.any():
        i = int(np.argmax(mask))
        raise InputError(f"{tab.path}, line {tab.lines[i]}: {what}")


def _check_values(tab: Table) -> None:
    if "track" in tab:
        _bad(tab, tab["track"] == "", "empty track id (give every row a track id)")
    for c in _OPTIONAL[1:]:
        if c in tab:
            nan = np.isnan(tab[c])
            if nan.any() and not nan.all():
                _bad(tab, nan, f"column {c} is empty here but filled on other rows")
    rng = tab["range_m"]
    _bad(tab, rng <= 0, "range_m must be > 0")
    tiny = rng < LIMITS["min_range_m"]
    _bad(tab, tiny, f"range_m = {rng[np.argmax(tiny)]:g} is implausible (< 1e-3 m)")
    i = np.argmax(rng > LIMITS["range_m"])
    _bad(tab, rng > LIMITS["range_m"], f"range_m = {rng[i]:g} is implausible (> 1e7 m)")
    t = tab["time_s"]
    i = np.argmax(np.abs(t) > LIMITS["time_s"])
    _bad(
        tab,
        np.abs(t) > LIMITS["time_s"],
        f"time_s = {t[i]:g} is implausible (|t| > {MAX_TIME_S:.4g} s, 2100)",
    )
    az = tab["azimuth_deg"]
    _bad(tab, (az < 0) | (az >= 360), "azimuth_deg must be in [0, 360)")
    if "elevation_deg" in tab:
        _bad(tab, np.abs(tab["elevation_deg"]) > 90, "elevation_deg must be in [-90, 90]")
    if "range_rate_mps" in tab:
        rr = tab["range_rate_mps"]
        big = np.abs(rr) > LIMITS["range_rate_mps"]
        _bad(tab, big, f"range_rate_mps = {rr[np.argmax(big)]:g} is implausible (> 1e4 m/s)")
    for c in _SENSOR:
        if c in tab:
            big = np.abs(tab[c]) > LIMITS["sensor_m"]
            bad_value = tab[c][np.argmax(big)]
            _bad(tab, big, f"{c} = {bad_value:g} is implausible (> {MAX_DISTANCE_M:g} m)")


def _check_gaps(tab: Table, labels: NDArray[Any]) -> None:
    """Refuse a time gap longer than ``LIMITS["gap_s"]`` between plots of one track."""
    codes = track_index(labels)[0]
    order = np.lexsort((tab["time_s"], codes))
    t = tab["time_s"][order]
    same = codes[order][1:] == codes[order][:-1]
    gap = np.diff(t)
    bad = same & (gap > LIMITS["gap_s"])
    if bad.any():
        i = int(np.argmax(bad))
        line = tab.lines[order[i + 1]]
        raise InputError(
            f"{tab.path}, line {line}: time gap of {gap[i]:g} s after the previous plot of "
            "the track is implausible (> 1e6 s); split the track"
        )
