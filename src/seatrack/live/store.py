"""The live process's store (``--store PATH``): an embedded DuckDB database.

Tables (the schema of docs/live.md; times are Unix seconds, angles degrees, speeds
knots, as in the API):

* ``ais_reports``: every decoded AIS position report used by the tracker -- ``mmsi``,
  ``time_s``, ``lat_deg``, ``lon_deg``, ``sog_kn``, ``cog_deg`` (NULL = not available),
  ``source`` (the receiver: ``udp://...``, ``tcp://...`` or the file), ``received_s``;
* ``ais_track_points``: every estimate of the AIS filter -- ``mmsi``, ``time_s``,
  ``lat_deg``, ``lon_deg``, ``sog_kn``, ``cog_deg``, ``std_m``, ``segment``,
  ``outlier_kind`` (0 none, else :data:`seatrack.filters.ais.OUTLIER_KINDS`); a vessel re-run
  after an out-of-order report writes its re-run points again (the last row of a
  ``(mmsi, time_s)`` is the current one);
* ``radar_plots``: ``time_s``, ``range_m``, ``azimuth_deg`` of every plot of a closed scan;
* ``radar_track_points``: per scan, every reported radar track -- ``time_s``, ``track``,
  ``status`` (``confirmed`` | ``coasting``), ``lat_deg``, ``lon_deg``, ``x_m``, ``y_m``
  (East, North of the radar), ``vx_mps``, ``vy_mps``, ``sog_kn``, ``cog_deg``, ``std_m``;
* ``ais_vessel_state``, ``radar_state``, ``counters``: the process's state for a restart
  (one row per vessel: plane origin, name, filter state and last estimate as numbers; the
  radar tracker pickled; the counters as JSON).

Everything gathered since the last commit is written in one transaction at least once a
second (:meth:`Store.commit`, in a worker thread so that ingestion goes on); a restart on
the same file restores every vessel's filter and the radar tracker as last committed and
carries on (DuckDB's write-ahead log keeps every committed transaction through a kill).
"""

from __future__ import annotations

import json
import pickle
from dataclasses import dataclass
from dataclasses import field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Batch", "Store", "SCHEMA"]

SCHEMA = """
CREATE TABLE IF NOT EXISTS ais_reports (
    mmsi BIGINT, time_s DOUBLE, lat_deg DOUBLE, lon_deg DOUBLE, sog_kn DOUBLE,
    cog_deg DOUBLE, source VARCHAR, received_s DOUBLE);
CREATE TABLE IF NOT EXISTS ais_track_points (
    mmsi BIGINT, time_s DOUBLE, lat_deg DOUBLE, lon_deg DOUBLE, sog_kn DOUBLE,
    cog_deg DOUBLE, std_m DOUBLE, segment INTEGER, outlier_kind SMALLINT);
CREATE TABLE IF NOT EXISTS radar_plots (time_s DOUBLE, range_m DOUBLE, azimuth_deg DOUBLE);
CREATE TABLE IF NOT EXISTS radar_track_points (
    time_s DOUBLE, track BIGINT, status VARCHAR, lat_deg DOUBLE, lon_deg DOUBLE,
    x_m DOUBLE, y_m DOUBLE, vx_mps DOUBLE, vy_mps DOUBLE, sog_kn DOUBLE, cog_deg DOUBLE,
    std_m DOUBLE);
CREATE TABLE IF NOT EXISTS ais_vessel_state (
    mmsi BIGINT PRIMARY KEY, lat0_deg DOUBLE, lon0_deg DOUBLE, name VARCHAR,
    t_last DOUBLE, filter DOUBLE[], estimate DOUBLE[]);
CREATE TABLE IF NOT EXISTS radar_state (id INTEGER PRIMARY KEY, last_t DOUBLE, tracker BLOB,
    views BLOB);
CREATE TABLE IF NOT EXISTS counters (id INTEGER PRIMARY KEY, body VARCHAR);
"""


@dataclass
class Batch:
    """What one commit writes: table name -> pyarrow table (appended, or upserted for the
    state tables), and the counters JSON."""

    tables: dict[str, Any] = field(default_factory=dict)
    counters: str = ""

    @property
    def rows(self) -> int:
        return sum(int(t.num_rows) for t in self.tables.values())


_UPSERT = {"ais_vessel_state", "radar_state"}


class Store:
    """A DuckDB store (see the module docstring); one connection, used by one thread at
    a time."""

    def __init__(self, path: str | Path) -> None:
        import duckdb

        self.path = Path(path)
        self.con = duckdb.connect(str(self.path))
        self.con.execute(SCHEMA)
        self.committed_rows = 0
        self.commits = 0

    def commit(self, batch: Batch) -> int:
        """Write a batch in one transaction; returns its rows."""
        con = self.con
        con.execute("BEGIN TRANSACTION")
        try:
            for k, (name, table) in enumerate(batch.tables.items()):
                if table.num_rows == 0:
                    continue
                view = f"batch_{k}"
                con.register(view, table)
                verb = "INSERT OR REPLACE" if name in _UPSERT else "INSERT"
                con.execute(f"{verb} INTO {name} SELECT * FROM {view}")
                con.unregister(view)
            if batch.counters:
                con.execute("INSERT OR REPLACE INTO counters VALUES (1, ?)", [batch.counters])
            con.execute("COMMIT")
        except Exception:
            con.execute("ROLLBACK")
            raise
        self.committed_rows += batch.rows
        self.commits += 1
        return batch.rows

    def close(self) -> None:
        self.con.close()

    # ---- restart ---------------------------------------------------------------------------
    def vessel_states(self) -> list[tuple]:
        """``(mmsi, lat0, lon0, name, t_last, filter, estimate)`` of every vessel."""
        return self.con.execute(
            "SELECT mmsi, lat0_deg, lon0_deg, name, t_last, filter, estimate FROM ais_vessel_state"
        ).fetchall()

    def vessel_columns(self) -> dict[str, Any]:
        """The columns of :meth:`vessel_states` as arrays (``filter`` and ``estimate`` as
        2-D arrays, NaN rows for a missing estimate): far faster than rows."""
        c = self.con.execute(
            "SELECT mmsi, lat0_deg, lon0_deg, name, t_last, filter, estimate FROM ais_vessel_state"
        ).fetchnumpy()
        n = len(c["mmsi"])

        def matrix(col: Any) -> np.ndarray:
            rows = [np.asarray(r, dtype=float) if r is not None and r is not np.ma.masked
                    else None for r in col]  # fmt: skip
            width = max((r.size for r in rows if r is not None), default=0)
            out = np.full((n, width), np.nan)
            for k, r in enumerate(rows):
                if r is not None:
                    out[k, : r.size] = r
            return out

        return {
            "mmsi": np.asarray(c["mmsi"], dtype=np.int64), "lat0": np.asarray(c["lat0_deg"], float),
            "lon0": np.asarray(c["lon0_deg"], float), "names": [str(x or "") for x in c["name"]],
            "t_last": np.asarray(c["t_last"], float), "filters": matrix(c["filter"]),
            "estimates": matrix(c["estimate"]),
        }  # fmt: skip

    def radar(self) -> tuple[float, Any, Any] | None:
        """``(last_t, tracker, views)`` as last committed, or None."""
        row = self.con.execute("SELECT last_t, tracker, views FROM radar_state").fetchone()
        if row is None:
            return None
        return float(row[0]), pickle.loads(row[1]), pickle.loads(row[2])

    def counters(self) -> dict[str, Any] | None:
        row = self.con.execute("SELECT body FROM counters").fetchone()
        return None if row is None else json.loads(row[0])


def radar_state_table(last_t: float, tracker: Any, views: Any) -> Any:
    """The ``radar_state`` row (the tracker pickled)."""
    import pyarrow as pa

    return pa.table(
        {"id": pa.array([1], pa.int32()), "last_t": [last_t],
         "tracker": pa.array([pickle.dumps(tracker)], pa.binary()),
         "views": pa.array([pickle.dumps(views)], pa.binary())}
    )  # fmt: skip


def nan_to_null(a: Any) -> Any:
    """A float column with NaN as NULL (pyarrow)."""
    import pyarrow as pa

    a = np.asarray(a, dtype=float)
    return pa.array(a, mask=~np.isfinite(a))


_COUNTS = ("received", "decoded", "duplicate", "late", "positions", "plots_received", "scans",
           "display_drops", "reconnects")  # fmt: skip


class StoreWriter:
    """Gathers what the process produces between two commits and builds the
    :class:`Batch` (in the event loop's thread, so the state it copies is consistent)."""

    def __init__(self, store: Store) -> None:
        self.store = store
        self.reports: list[tuple] = []
        self.plots: list[tuple] = []
        self.radar_rows: list[tuple] = []
        self.radar_dirty = False

    def ais_reports(self, rows: list[tuple]) -> None:
        """``(mmsi, time_s, lat, lon, sog_kn, cog_deg, source, received_s)`` rows."""
        self.reports.extend(rows)

    def radar_scan(self, radar: Any) -> None:
        """After a scan: its plots and reported tracks (``radar.scan_plots``,
        ``radar.current``)."""
        t, rng, az = radar.scan_plots
        self.plots.append((np.full(rng.size, t), rng, np.degrees(az) % 360.0))
        from seatrack.geometry import KNOT_MPS

        for v, (x, y, vx, vy, st) in zip(radar.current, radar.scan_rows, strict=True):
            self.radar_rows.append((v.t, v.track_id, st, v.lat, v.lon, x, y, vx, vy,
                                    v.speed / KNOT_MPS, np.degrees(v.course), v.std_m))  # fmt: skip
        self.radar_dirty = True

    def take(self, ais: Any, radar: Any, counters: Any) -> Batch:
        """The batch of everything since the last call."""
        import pyarrow as pa

        b = Batch()
        if self.reports:
            cols = list(zip(*self.reports, strict=True))
            b.tables["ais_reports"] = pa.table({
                "mmsi": pa.array(cols[0], pa.int64()), "time_s": cols[1], "lat_deg": cols[2],
                "lon_deg": cols[3], "sog_kn": nan_to_null(cols[4]), "cog_deg": nan_to_null(cols[5]),
                "source": pa.array(cols[6], pa.string()), "received_s": cols[7],
            })  # fmt: skip
            self.reports = []
        if ais.emitted:
            b.tables["ais_track_points"] = _ais_points(ais.emitted)
            ais.emitted.clear()
        if ais.dirty:
            rows = [ais.state_row(m) for m in sorted(ais.dirty)]
            ais.dirty.clear()
            c = list(zip(*rows, strict=True))
            b.tables["ais_vessel_state"] = pa.table({
                "mmsi": pa.array(c[0], pa.int64()), "lat0_deg": c[1], "lon0_deg": c[2],
                "name": pa.array(c[3], pa.string()), "t_last": c[4],
                "filter": pa.array(c[5], pa.list_(pa.float64())),
                "estimate": pa.array(c[6], pa.list_(pa.float64())),
            })  # fmt: skip
        if self.plots:
            t, r, a = (np.concatenate(x) for x in zip(*self.plots, strict=True))
            b.tables["radar_plots"] = pa.table({"time_s": t, "range_m": r, "azimuth_deg": a})
            self.plots = []
        if self.radar_rows:
            c = list(zip(*self.radar_rows, strict=True))
            names = ("time_s", "track", "status", "lat_deg", "lon_deg", "x_m", "y_m", "vx_mps",
                     "vy_mps", "sog_kn", "cog_deg", "std_m")  # fmt: skip
            b.tables["radar_track_points"] = pa.table(
                {n: (pa.array(v, pa.string()) if n == "status" else
                     pa.array(v, pa.int64()) if n == "track" else nan_to_null(v))
                 for n, v in zip(names, c, strict=True)}
            )  # fmt: skip
            self.radar_rows = []
        if self.radar_dirty and radar is not None:
            b.tables["radar_state"] = radar_state_table(
                radar.last_t, radar.scans.tracker, radar.current
            )
            self.radar_dirty = False
        state = {k: getattr(counters, k) for k in _COUNTS}
        state["rejected"] = dict(counters.rejected)
        state["plots_rejected"] = dict(counters.plots_rejected)
        b.counters = json.dumps(state, sort_keys=True)
        return b

    def restore(self, ais: Any, radar: Any, counters: Any) -> int:
        """Load the committed state into the trackers and counters; returns the vessels
        and radar tracks restored."""
        from collections import Counter

        cols = self.store.vessel_columns()
        ais.restore_vessels(**cols)
        n = len(cols["mmsi"])
        saved = self.store.radar() if radar is not None else None
        if saved is not None:
            radar.last_t, radar.scans.tracker, radar.current = saved
            radar.changed = True
            n += len(radar.current)
        c = self.store.counters()
        if c is not None:
            for k in _COUNTS:
                setattr(counters, k, int(c.get(k, 0)))
            counters.rejected = Counter(c.get("rejected", {}))
            counters.plots_rejected = Counter(c.get("plots_rejected", {}))
        return n


def _ais_points(emitted: list) -> Any:
    """``ais_track_points`` of ``(vessel, Estimate)`` pairs (WGS84 as the picture)."""
    import pyarrow as pa

    from seatrack.filters.ais import TrackStates
    from seatrack.filters.ais.tracks import ReportPlanes
    from seatrack.filters.ais.tracks import tracks_from_states
    from seatrack.geometry import KNOT_MPS

    n = len(emitted)
    mmsi = np.array([v.mmsi for v, _ in emitted], dtype=np.int64)
    lat0 = np.array([v.lat0 for v, _ in emitted])
    lon0 = np.array([v.lon0 for v, _ in emitted])
    t = np.array([e.t for _, e in emitted])
    state = np.array([e.state for _, e in emitted]).reshape(n, 5)
    std = np.array([e.std for _, e in emitted]).reshape(n, 5)
    kind = np.array([e.kind for _, e in emitted], dtype=np.int8)
    seg = np.array([e.segment for _, e in emitted], dtype=np.int64)
    st = TrackStates(state, std, kind > 0, kind, seg, np.full(n, np.nan), np.zeros(n))
    tr = tracks_from_states(ReportPlanes(n, np.arange(n), lat0, lon0), st)
    return pa.table({
        "mmsi": mmsi, "time_s": t, "lat_deg": tr.lat, "lon_deg": tr.lon,
        "sog_kn": nan_to_null(tr.speed / KNOT_MPS),
        "cog_deg": nan_to_null(np.degrees(tr.course)), "std_m": nan_to_null(tr.std_pos_m),
        "segment": pa.array(seg.astype(np.int32)), "outlier_kind": pa.array(kind.astype(np.int16)),
    })  # fmt: skip
