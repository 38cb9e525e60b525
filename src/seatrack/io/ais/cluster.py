"""AIS tracking on a Dask cluster: all reports of all files shuffled by MMSI, so that each
vessel is tracked once over all files, with the output of one process.

1. **Read** each file in one task and split its rows by ``mmsi mod partitions`` (a hash
   shuffle; rows without a readable MMSI go to a last piece).
2. **Track** each partition in one task: its pieces from all files in file order (so a
   vessel's rows are in input order), duplicates marked, the kernel and the revisit passes.
   The refinement pass runs step by step on the partitions kept on the workers; between
   steps the client sums the integer offset counts of all partitions
   (:func:`seatrack.filters.ais.refine.drive`): the result does not depend on the number of
   partitions or workers, and equals one process's.
3. **Write** partitioned Parquet (``OUT.parquet/part-00000.parquet``, ...: one file per
   partition, each vessel in one file) from the workers, or one CSV/Parquet file on the
   client in the order of one process (vessels by first appearance).

``track_files_dask`` uses a running scheduler (``scheduler`` address, or a ``client``) or
starts a local cluster. Workers need seatrack installed and, for partitioned output, the
output folder on a file system they share with the client.
"""

from __future__ import annotations

import contextlib
import functools
import os
import shutil
from collections.abc import Callable
from collections.abc import Iterator
from collections.abc import Sequence
from operator import itemgetter
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.compiled import compile_all
from seatrack.filters.ais import AisTrackerConfig
from seatrack.filters.ais.offsets import prior_counts
from seatrack.filters.ais.refine import Refinement
from seatrack.filters.ais.refine import drive
from seatrack.filters.ais.refine import n_ident
from seatrack.filters.ais.tracker import track_vessel_groups
from seatrack.filters.ais.tracks import prepare_reports
from seatrack.filters.ais.tracks import tracks_from_states
from seatrack.io.ais.output import TracksWriter
from seatrack.io.ais.output import track_columns
from seatrack.io.ais.output import tracks_table
from seatrack.io.ais.pipeline import GroupState
from seatrack.io.ais.pipeline import RunSummary
from seatrack.io.ais.pipeline import finish_group
from seatrack.io.ais.pipeline import start_group
from seatrack.io.ais.read import file_blocks
from seatrack.io.ais.reports import AisReports
from seatrack.io.ais.reports import concat_reports
from seatrack.io.atomic import OutputError
from seatrack.io.atomic import check_output_path

__all__ = ["track_files_dask", "dask_client"]


def _read_split(path: str, source: int, parts: int) -> tuple[list[AisReports], dict[str, int]]:
    """Rows of one file split by MMSI (``parts`` pieces + one for rows without MMSI)."""
    blocks: list[AisReports] = []
    for attempt in file_blocks(path):
        blocks = attempt
    r = concat_reports(blocks) if blocks else AisReports.empty((path,))
    r.sources = (path,)
    r.source = np.full(len(r), source, dtype=np.int64)
    skipped = dict(blocks[0].skipped) if len(blocks) == 1 else dict(r.skipped)
    key = np.where(r.mmsi >= 0, r.mmsi % parts, parts)
    order = np.argsort(key, kind="stable")
    bounds = np.searchsorted(key[order], np.arange(parts + 2))
    return [r.take(order[bounds[j] : bounds[j + 1]]) for j in range(parts + 1)], skipped


def _partition(pieces: Sequence[AisReports], sources: tuple[str, ...]) -> AisReports:
    r = concat_reports(list(pieces)) if pieces else AisReports.empty(sources)
    r.sources = sources
    r.source = np.concatenate([p.source for p in pieces]) if pieces else r.source
    r.skipped = {}
    return r


def _start(pieces: Sequence[AisReports], sources: tuple[str, ...], cfg: AisTrackerConfig) -> Any:
    return start_group(_partition(pieces, sources), cfg)


def _step(grp: Any, f: Callable[[Refinement], Any]) -> tuple[GroupState, Any]:
    return grp, (f(grp.ref) if grp.ref is not None else None)


def _counts(grp: Any, prior: NDArray[np.float64]) -> NDArray[np.int64]:
    if grp.ref is None:
        return np.zeros(prior.size, dtype=np.int64)
    return prior_counts(grp.ref.scores(), prior)


def _n_ident(grp: Any) -> int:
    return 0 if grp.ref is None else n_ident(grp.ref)


def _first_keys(r: AisReports) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Per row: the input key (source, line) of its vessel's first row, and its own."""
    key = r.source * (1 << 40) + r.line
    vkey = key.copy()
    ok = r.mmsi >= 0
    if ok.any():
        u, inv = np.unique(r.mmsi[ok], return_inverse=True)
        first = np.full(u.size, np.iinfo(np.int64).max)
        np.minimum.at(first, inv, key[ok])
        vkey[ok] = first[inv]
    vkey[~ok] = np.iinfo(np.int64).max
    return vkey, key


def _result(grp: Any) -> tuple[Any, RunSummary]:
    """TRACKS table of a partition (with its order keys) and its summary."""
    import pyarrow as pa

    tr = finish_group(grp)
    summary = RunSummary()
    summary.add(grp.reports, tr)
    table = tracks_table(grp.reports, track_columns(tr))
    vkey, key = _first_keys(grp.reports.take(_order(grp.reports)))
    table = table.append_column("_vkey", pa.array(vkey)).append_column("_key", pa.array(key))
    return table, summary


def _order(r: AisReports) -> NDArray[np.int64]:
    from seatrack.io.ais.reports import output_order

    return output_order(r)


def _no_mmsi(pieces: Sequence[AisReports], sources: tuple[str, ...]) -> tuple[Any, RunSummary]:
    import pyarrow as pa

    r = _partition(pieces, sources)
    prep = prepare_reports(r)
    tr = tracks_from_states(prep.planes, track_vessel_groups([prep.inputs])[0])
    summary = RunSummary()
    summary.add(r, tr)
    table = tracks_table(r, track_columns(tr))
    vkey, key = _first_keys(r.take(_order(r)))
    table = table.append_column("_vkey", pa.array(vkey)).append_column("_key", pa.array(key))
    return table, summary


def _write_part(result: tuple[Any, RunSummary], path: str) -> RunSummary:
    import pyarrow.parquet as pq

    table, summary = result
    pq.write_table(table.drop_columns(["_vkey", "_key"]), path, compression="zstd")
    return summary


class _DaskGroups:
    """:class:`~seatrack.filters.ais.refine.GroupRunner` of partitions held by workers."""

    def __init__(self, client: Any, states: list[Any]) -> None:
        self.client, self.states = client, states

    def each(self, f: Callable[[Refinement], Any]) -> list[Any]:
        done = self.client.map(_step, self.states, f=f, pure=False)
        self.states = self.client.map(itemgetter(0), done)
        return list(self.client.gather(self.client.map(itemgetter(1), done)))

    def counts(self, prior: NDArray[np.float64]) -> NDArray[np.int64]:
        parts = self.client.gather(self.client.map(_counts, self.states, prior=prior, pure=False))
        return np.sum(np.asarray(parts, dtype=np.int64).reshape(len(parts), -1), axis=0)

    def n_ident(self) -> int:
        return sum(self.client.gather(self.client.map(_n_ident, self.states, pure=False)))


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, processes: bool = True) -> Iterator[Any]:
    """A ``distributed.Client`` of ``scheduler`` (an address) or of a new local cluster."""
    try:
        from distributed import Client
        from distributed import LocalCluster
    except ImportError:
        raise ValueError(
            "--dask needs dask and distributed: pip install 'seatrack[dask]'"
        ) from None
    if scheduler is not None:
        with Client(scheduler) as client:
            yield client
        return
    n = os.cpu_count() or 1
    if processes:
        compile_all()  # the worker processes must not compile the same kernels at once
    with (
        LocalCluster(
            n_workers=n if processes else 1,
            threads_per_worker=1 if processes else n,
            processes=processes,
            dashboard_address=None,
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client


def track_files_dask(
    paths: Sequence[str | Path],
    out: str | Path,
    config: AisTrackerConfig | None = None,
    scheduler: str | None = None,
    partitions: int | None = None,
    client: Any = None,
) -> RunSummary:
    """Track AIS files on a Dask cluster (see the module docstring).

    Parameters
    ----------
    paths : input files (any kind :func:`~seatrack.io.ais.read.file_blocks` reads).
    out : a ``.csv`` file (one file, order of one process), or a ``.parquet`` path: a folder
        of one Parquet file per partition when more than one partition, else one file.
    scheduler : address of a running scheduler; default a local cluster.
    partitions : MMSI partitions (default: 4 per worker thread).
    client : an existing ``distributed.Client`` (overrides ``scheduler``).
    """
    if client is None:
        with dask_client(scheduler) as c:
            return track_files_dask(paths, out, config, partitions=partitions, client=c)
    cfg = config or AisTrackerConfig()
    names = [str(p) for p in paths]
    sources = tuple(names)
    threads = sum(client.nthreads().values()) or 1
    parts = partitions or 4 * threads
    split = [client.submit(_read_split, p, s, parts, pure=False) for s, p in enumerate(names)]
    files = [client.submit(itemgetter(0), f) for f in split]
    skipped_parts = client.gather([client.submit(itemgetter(1), f) for f in split])
    piece = functools.partial(client.submit, pure=False)
    states = [
        piece(lambda fs, j=j: _start([f[j] for f in fs], sources, cfg), files) for j in range(parts)
    ]
    runner = _DaskGroups(client, states)
    if cfg.refine:
        drive(runner, cfg)
    results = client.map(_result, runner.states, pure=False)
    results.append(piece(lambda fs: _no_mmsi([f[parts] for f in fs], sources), files))
    summary = _write_output(client, results, Path(out))
    for sk in skipped_parts:
        for k, v in sk.items():
            summary.skipped[k] = summary.skipped.get(k, 0) + v
    return summary


def _merge(summaries: Sequence[RunSummary]) -> RunSummary:
    total = RunSummary()
    for s in summaries:
        total.rows += s.rows
        total.used += s.used
        total.outliers += s.outliers
        total.codes = total.codes + s.codes
        total.vessels += s.vessels
        total.segments += s.segments
        total.offsets += s.offsets
        total.groups += s.groups
    return total


def _write_output(client: Any, results: list[Any], out: Path) -> RunSummary:
    """Partitioned Parquet from the workers, or one file written on the client."""
    if out.suffix.lower() in (".parquet", ".pq") and len(results) > 2:
        if out.exists() and not out.is_dir():
            raise OutputError(f"{out}: exists and is not a folder (partitioned Parquet output)")
        check_output_path(out / "part-00000.parquet")
        tmp = out.with_name(f".{out.name}.tmp-{os.getpid()}")
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
        try:
            files = [str(tmp / f"part-{j:05d}.parquet") for j in range(len(results))]
            summaries = client.gather(client.map(_write_part, results, files, pure=False))
            old = out.with_name(f".{out.name}.old-{os.getpid()}")
            if out.exists():
                os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return _merge(summaries)
    import pyarrow as pa
    import pyarrow.compute as pc

    gathered = client.gather(results)
    tables = [t for t, _ in gathered]
    table = pa.concat_tables(tables)
    order = pc.sort_indices(table, sort_keys=[("_vkey", "ascending"), ("_key", "ascending")])
    table = table.take(order).drop_columns(["_vkey", "_key"])
    _write_table(table, out)
    return _merge([s for _, s in gathered])


def _write_table(table: Any, out: Path) -> None:
    """One TRACKS file from a TRACKS table in output order (as one process writes it)."""
    from seatrack.io.ais.output import write_table

    with TracksWriter(out) as writer:
        write_table(writer, table)
