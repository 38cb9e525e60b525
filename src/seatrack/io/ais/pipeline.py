"""Track AIS files of any size within a memory budget: read, group vessels, track, write.

1. **Read** every file in blocks (:func:`~seatrack.io.ais.read.file_blocks`), in file then
   line order; the blocks are kept in memory, or spilled to a temporary folder once they pass
   a share of the budget. Each vessel's first appearance and row count are noted.
2. **Group** the vessels in order of first appearance into groups of at most
   ``group_rows`` rows (a vessel is never split; rows without a readable MMSI form the last
   group), and split every block by group (one pass).
3. **Track** group by group (duplicates marked within the group, which holds all rows of its
   vessels); the refinement pass runs step by step over all groups
   (:func:`seatrack.filters.ais.refine.drive`), the groups' states spilled between steps,
   so that the offset prior is that of all reports and the result does not depend on the
   grouping. The compiled tracker runs the vessels of a group on all cores.
4. **Write** each group's rows in output order (vessels by first appearance, input order
   within a vessel) to one TRACKS file (CSV or Parquet) through :mod:`seatrack.io.atomic`.

The peak memory is about the baseline of the process plus ``group_rows`` times the tracker's
bytes per row (:data:`TRACK_BYTES_PER_ROW`) plus the kept blocks; :func:`group_rows_for`
sizes groups from a memory limit.
"""

from __future__ import annotations

import resource
import tempfile
from collections.abc import Callable
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais import AisTrackerConfig
from seatrack.filters.ais.refine import InMemory
from seatrack.filters.ais.refine import Refinement
from seatrack.filters.ais.refine import drive
from seatrack.filters.ais.tracker import first_track
from seatrack.filters.ais.tracker import prepare_rows
from seatrack.filters.ais.tracker import track_states
from seatrack.filters.ais.tracker import track_vessel_groups
from seatrack.filters.ais.tracks import AisTracks
from seatrack.filters.ais.tracks import ReportPlanes
from seatrack.filters.ais.tracks import prepare_reports
from seatrack.filters.ais.tracks import tracks_from_states
from seatrack.io.ais.output import TracksWriter
from seatrack.io.ais.output import track_columns
from seatrack.io.ais.park import Parked
from seatrack.io.ais.park import ParkedGroups
from seatrack.io.ais.park import dump
from seatrack.io.ais.park import undump
from seatrack.io.ais.read import file_blocks
from seatrack.io.ais.reports import REASON_LABELS
from seatrack.io.ais.reports import AisReports
from seatrack.io.ais.reports import concat_reports
from seatrack.io.ais.reports import mark_duplicates
from seatrack.io.ais.reports import rejection_counts
from seatrack.io.compressed import open_input
from seatrack.progress import Progress

__all__ = [
    "DEFAULT_MEMORY_LIMIT",
    "TRACK_BYTES_PER_ROW",
    "RunSummary",
    "group_rows_for",
    "track_files",
]

#: default ``--memory-limit`` (bytes of peak resident memory)
DEFAULT_MEMORY_LIMIT = 2 << 30
#: peak bytes per row of tracking a group and writing its TRACKS (measured: 1.11 GB above
#: the baseline for one group of 1 million reports, 26-column DMA file)
TRACK_BYTES_PER_ROW = 1150
#: bytes per row of a kept block (canonical columns)
BLOCK_BYTES_PER_ROW = 73
#: seconds per report of a whole run, reading to writing (``benchmarks/ais.py``: a
#: DMA-shaped day of 15,000,000 reports in 168 s with other jobs on the 2-core development
#: machine, 89k reports/s, docs/ais.md; 200,000-report files take 3.5-3.9 s there)
SECONDS_PER_REPORT = 1.2e-5
#: decompressed / compressed size assumed for a compressed log (the bundled AIS logs gzip
#: 4.4 to 6.4 times)
COMPRESSION_RATIO = 6.0
#: share of a run's time spent reading (the rest: grouping, tracking, writing; cProfile of
#: the hourly files: CSV parsing 9.8 s of 79 s, docs/ais.md)
READ_SHARE = 0.2
#: bytes sampled at the start of a text file to estimate its bytes per line
SAMPLE_BYTES = 1 << 20


def rss_bytes() -> int:
    """Current resident memory of this process (bytes; Linux ``/proc``, else peak)."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * resource.getpagesize()
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def group_rows_for(memory_limit: int) -> int:
    """Rows per vessel group for a peak-memory budget: what is left above the current
    resident memory (which holds the blocks read), with a 10 % margin; at least 50,000."""
    free = 0.9 * memory_limit - rss_bytes()
    return max(50_000, int(free / TRACK_BYTES_PER_ROW))


@dataclass
class RunSummary:
    """Counts of one run (see :meth:`lines`)."""

    rows: int = 0
    used: int = 0
    outliers: int = 0
    codes: NDArray[np.int64] = field(default_factory=lambda: np.zeros(len(REASON_LABELS), np.int64))
    skipped: dict[str, int] = field(default_factory=dict)
    vessels: int = 0
    segments: int = 0
    offsets: int = 0
    groups: int = 0

    def add(self, r: AisReports, tr: AisTracks) -> None:
        """Count a tracked group."""
        valid = r.valid
        n_out = int(np.count_nonzero(tr.outlier))
        self.rows += len(r)
        self.used += int(np.count_nonzero(valid)) - n_out
        self.outliers += n_out
        self.codes += np.bincount(r.code, minlength=len(REASON_LABELS))
        self.vessels += int(np.unique(r.mmsi[valid]).size)
        has = tr.segment >= 0
        if has.any():  # segments are numbered 1..K within each vessel
            _, inv = np.unique(r.mmsi[has], return_inverse=True)
            top = np.zeros(int(inv.max()) + 1, dtype=np.int64)
            np.maximum.at(top, inv, tr.segment[has])
            self.segments += int(top.sum())
        off = np.asarray(tr.time_offset_s, float)
        self.offsets += int(np.count_nonzero(np.isfinite(off) & (off != 0)))
        self.groups += 1

    def lines(self) -> list[str]:
        """Rows read / used / rejected by reason, outliers, vessels, segments, offsets."""
        rejected = self.rows - int(self.codes[0])
        out = [
            f"rows read: {self.rows}",
            f"rows used: {self.used}",
            f"outliers (flagged, not used): {self.outliers}",
            f"rows rejected: {rejected}",
        ]
        out += [f"  {reason}: {k}" for reason, k in rejection_counts(self.codes).items()]
        if self.skipped:
            out.append(f"lines that are not position reports: {sum(self.skipped.values())}")
            out += [f"  {k}: {v}" for k, v in sorted(self.skipped.items())]
        out.append(f"vessels: {self.vessels}, track segments: {self.segments}")
        if self.used:
            share = 100 * self.offsets / self.used
            out.append(
                f"reports with a whole-second timestamp offset: {self.offsets} ({share:.1f} %)"
            )
        return out


class _Store:
    """Blocks of rows kept in memory or, past ``budget`` bytes, in .npz files."""

    def __init__(self, budget: int, folder: Path) -> None:
        self.budget, self.folder = budget, folder
        self.items: list[AisReports | Path] = []
        self.bytes = 0

    def add(self, r: AisReports) -> None:
        size = len(r) * BLOCK_BYTES_PER_ROW
        if self.bytes + size <= self.budget:
            self.items.append(r)
            self.bytes += size
            return
        path = self.folder / f"block{len(self.items)}.pkl"
        dump(r, path)
        self.items.append(path)

    def blocks(self) -> Any:
        """The blocks in order, each released by the store once yielded."""
        self.items.reverse()
        while self.items:
            it = self.items.pop()
            if isinstance(it, Path):
                yield undump(it)
                it.unlink()
            else:
                yield it
        self.bytes = 0


@dataclass
class _Registry:
    """First appearance (rank) and row count of every vessel, in reading order."""

    rank: dict[int, int] = field(default_factory=dict)
    count: dict[int, int] = field(default_factory=dict)
    no_mmsi: int = 0

    def add(self, mmsi: NDArray[np.int64]) -> None:
        known = mmsi >= 0
        self.no_mmsi += int(np.count_nonzero(~known))
        u, first, cnt = np.unique(mmsi[known], return_index=True, return_counts=True)
        for m in u[np.argsort(first, kind="stable")].tolist():
            if m not in self.rank:
                self.rank[m] = len(self.rank)
        for m, c in zip(u.tolist(), cnt.tolist(), strict=True):
            self.count[m] = self.count.get(m, 0) + c

    def groups(self, group_rows: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Sorted vessel ids and the group of each (by first appearance, groups of at most
        ``group_rows`` rows unless one vessel has more)."""
        ids = np.array(sorted(self.rank, key=self.rank.__getitem__), dtype=np.int64)
        cnt = np.array([self.count[m] for m in ids.tolist()], dtype=np.int64)
        gid = np.zeros(ids.size, dtype=np.int64)
        g, acc = 0, 0
        for k, c in enumerate(cnt.tolist()):
            if acc and acc + c > group_rows:
                g, acc = g + 1, 0
            gid[k] = g
            acc += c
        order = np.argsort(ids)
        return ids[order], gid[order]


def estimate_reports(paths: Sequence[str | Path]) -> float:
    """The number of reports in ``paths``, estimated before reading them: the rows of a
    Parquet file; a text file's size over its bytes per line in the first
    :data:`SAMPLE_BYTES` (a compressed file's size times :data:`COMPRESSION_RATIO`)."""
    from seatrack.io.ais.columnar import is_parquet
    from seatrack.io.compressed import compression_of

    total = 0.0
    for path in paths:
        p = Path(path)
        try:
            if is_parquet(p):
                import pyarrow.parquet as pq

                total += pq.ParquetFile(p).metadata.num_rows
                continue
            size = float(p.stat().st_size)
            if compression_of(p) is not None:
                size *= COMPRESSION_RATIO
            with open_input(p) as fh:
                head = fh.read(SAMPLE_BYTES)
        except Exception:  # an unreadable file is reported, with its name, by the reader
            continue
        total += size * max(head.count(b"\n"), 1) / max(len(head), 1)
    return total


def ais_progress(paths: Sequence[str | Path]) -> Progress:
    """The progress of ``seatrack ais`` on ``paths`` (:func:`estimate_reports` reports at
    :data:`SECONDS_PER_REPORT`)."""
    n = estimate_reports(paths)
    return Progress("seatrack ais", n, "reports", n * SECONDS_PER_REPORT)


def _read_all(
    paths: Sequence[str | Path], store: _Store, block_bytes: int, progress: Progress
) -> tuple[_Registry, dict[str, int], tuple[str, ...]]:
    reg = _Registry()
    skipped: dict[str, int] = {}
    rows = 0
    for s, p in enumerate(paths):
        blocks: list[AisReports] = []
        for attempt in file_blocks(p, block_bytes):
            blocks = attempt
        for b in blocks:
            b.source[:] = s
            for k, v in b.skipped.items():
                skipped[k] = skipped.get(k, 0) + v
            b.skipped = {}
            reg.add(b.mmsi)
            store.add(b)
            rows += len(b)
        total = max(progress.total, rows) if s + 1 < len(paths) else rows
        progress.update(rows, total, "read", READ_SHARE * rows / max(total, 1))
    return reg, skipped, tuple(str(p) for p in paths)


def _split(
    store: _Store, ids: NDArray[np.int64], gid: NDArray[np.int64], n_groups: int, folder: Path
) -> list[list[AisReports | Path]]:
    """Every block split by vessel group (rows without an MMSI: group ``n_groups``)."""
    pieces: list[list[AisReports | Path]] = [[] for _ in range(n_groups + 1)]
    spill = any(isinstance(it, Path) for it in store.items)
    for k, b in enumerate(store.blocks()):
        g = np.full(len(b), n_groups, dtype=np.int64)
        known = b.mmsi >= 0
        g[known] = gid[np.searchsorted(ids, b.mmsi[known])]
        order = np.argsort(g, kind="stable")
        bounds = np.searchsorted(g[order], np.arange(n_groups + 2))
        for j in range(n_groups + 1):
            if bounds[j + 1] > bounds[j]:
                piece = b.take(order[bounds[j] : bounds[j + 1]])
                if spill:
                    path = folder / f"g{j}_b{k}.pkl"
                    dump(piece, path)
                    pieces[j].append(path)
                else:
                    pieces[j].append(piece)
    return pieces


def _load(items: list[AisReports | Path], sources: tuple[str, ...]) -> AisReports:
    """The pieces of one group as one table (the list is emptied)."""
    parts = []
    items.reverse()
    while items:
        it = items.pop()
        if isinstance(it, Path):
            parts.append(undump(it))
            it.unlink()
        else:
            parts.append(it)
    if not parts:
        return AisReports.empty(sources)
    r = concat_reports(parts)
    r.sources = sources
    r.source = np.concatenate([p.source for p in parts])
    return r


@dataclass
class GroupState:
    """One vessel group between the tracking steps: its reports, where the tracker's rows
    sit in them (``planes``, ``order``), and either its refinement (``ref``) or, without
    one, its first track (``rows``, ``out``)."""

    reports: AisReports
    planes: ReportPlanes
    order: NDArray[np.int64] | None
    ref: Refinement | None = None
    rows: Any = None
    out: Any = None


def start_group(r: AisReports, cfg: AisTrackerConfig) -> GroupState:
    """Duplicates marked, tracker inputs, the first track and the refinement's start."""
    r = mark_duplicates(r)
    prep = prepare_reports(r)
    rows, order = prepare_rows(prep.inputs, cfg)
    out = first_track(rows, cfg)
    if cfg.refine and rows.t.size:
        return GroupState(r, prep.planes, order, Refinement(rows, out, cfg))
    return GroupState(r, prep.planes, order, None, rows, out)


def finish_group(grp: GroupState) -> AisTracks:
    """The group's tracks (after the refinement steps)."""
    if grp.ref is not None:
        out, toff = grp.ref.finish()
        rows = grp.ref.rows
    else:
        rows, out = grp.rows, grp.out
        toff = np.zeros(rows.t.size)
    return tracks_from_states(grp.planes, track_states(rows, out, toff, grp.order))


def _track_groups(
    groups: list[list[AisReports | Path]],
    sources: tuple[str, ...],
    cfg: AisTrackerConfig,
    parked: Parked,
    emit: Callable[[AisReports, AisTracks], None],
) -> None:
    """Track the vessel groups (see the module docstring) and pass each to ``emit``."""
    if len(groups) == 1:  # one group: in memory
        grp = start_group(_load(groups[0], sources), cfg)
        if grp.ref is not None:
            drive(InMemory([grp.ref]), cfg)
        reports, tracks = grp.reports, finish_group(grp)
        del grp  # the tracker's state is freed before the output is formatted
        emit(reports, tracks)
        return
    runner = ParkedGroups(parked)
    for j, items in enumerate(groups):
        grp = start_group(_load(items, sources), cfg)
        if grp.ref is not None:
            runner.add(j, grp.ref)
            grp.ref = None
        parked.put(f"g{j}", grp)
        del grp
    if runner.refs:
        drive(runner, cfg)
    for j in range(len(groups)):
        grp = parked.pop(f"g{j}")
        if j in runner.refs:
            grp.ref = runner.pop(j)
        reports, tracks = grp.reports, finish_group(grp)
        del grp
        emit(reports, tracks)


def track_files(
    paths: Sequence[str | Path],
    out: str | Path,
    config: AisTrackerConfig | None = None,
    memory_limit: int = DEFAULT_MEMORY_LIMIT,
    group_rows: int | None = None,
    block_bytes: int = 32 << 20,
    on_group: Callable[[AisReports, AisTracks], None] | None = None,
    progress: Progress | None = None,
) -> RunSummary:
    """Read, track and write AIS files within a memory budget (see the module docstring).

    Parameters
    ----------
    paths : input files (CSV, compressed CSV, Parquet, NMEA); a vessel seen in several
        files is one track.
    out : TRACKS file (``.csv`` or ``.parquet``); written atomically.
    config : tracker configuration.
    memory_limit : bytes; sizes the vessel groups (:func:`group_rows_for`) and the blocks
        kept in memory.
    group_rows : rows per vessel group (overrides the size from ``memory_limit``).
    on_group : called with each group's reports and tracks after it is written (e.g. to
        collect the tracks for a map).
    progress : told of the reports read (after each file) and tracked (after each group).
    """
    cfg = config or AisTrackerConfig()
    summary = RunSummary()
    bar = progress if progress is not None else Progress.silent()
    with tempfile.TemporaryDirectory(prefix="seatrack-ais-") as tmp, TracksWriter(out) as writer:
        folder = Path(tmp)
        store = _Store(max(memory_limit // 4, 1 << 26), folder)
        reg, skipped, sources = _read_all(paths, store, block_bytes, bar)
        n_rows = bar.done
        summary.skipped = skipped
        rows_per_group = group_rows or group_rows_for(memory_limit)
        ids, gid = reg.groups(rows_per_group)
        n_groups = int(gid.max()) + 1 if gid.size else 0
        pieces = _split(store, ids, gid, n_groups, folder)
        vessel_groups = pieces[:n_groups]
        no_mmsi = pieces[n_groups]
        # what is left of the budget holds the groups' state between the steps
        budget = int(0.9 * memory_limit) - rss_bytes() - rows_per_group * TRACK_BYTES_PER_ROW
        parked = Parked(folder, max(budget, 0))

        def emit(r: AisReports, tr: AisTracks) -> None:
            writer.write(r, track_columns(tr))
            summary.add(r, tr)
            share = READ_SHARE + (1 - READ_SHARE) * summary.rows / max(n_rows, 1)
            bar.update(summary.rows, n_rows, "tracked", share)
            if on_group is not None:
                on_group(r, tr)

        if vessel_groups:
            _track_groups(vessel_groups, sources, cfg, parked, emit)
        if no_mmsi:
            r = _load(no_mmsi, sources)
            prep = prepare_reports(r)
            st = track_vessel_groups([prep.inputs], cfg)[0]
            emit(r, tracks_from_states(prep.planes, st))
    return summary
