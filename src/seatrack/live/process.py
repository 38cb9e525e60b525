"""The live process: sources -> bounded queue -> NMEA / plots -> trackers -> fusion ->
picture, web server, NMEA output and store, in one asyncio loop.

One consumer task takes chunks of lines off the queue (several at a time, so that a
burst is converted to vessel planes in one vectorised call), runs them through the
:class:`~seatrack.live.nmea.Assembler`, the duplicate filter and the decoder, and folds
the position reports into :class:`~seatrack.live.ais.LiveAis`; the counters change
together with the picture (:mod:`seatrack.live.counters`). Radar chunks go to
:class:`~seatrack.live.radar.LiveRadar` when a radar is configured. A ticker closes timed
out scans and fragments, refreshes the picture and feeds the web clients, the NMEA output
and the store once a second or faster.
With AIS and radar inputs, every closed scan is handed to the radar-AIS fusion
(:class:`~seatrack.live.fusion.LiveFusion`) with the AIS states emitted so far; it runs in
a worker thread fed by a bounded queue of scans (the newest wins, drops counted), and the
picture takes its result at the next refresh.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass
from dataclasses import field
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.geometry import KNOT_MPS
from seatrack.live.ais import LiveAis
from seatrack.live.counters import Counters
from seatrack.live.ingest import Positions
from seatrack.live.ingest import read_lines
from seatrack.live.ingest import read_messages
from seatrack.live.nmea import Assembler
from seatrack.live.nmea import Duplicates
from seatrack.live.nmea import Message
from seatrack.live.picture import Picture
from seatrack.live.sources import Chunk
from seatrack.live.sources import Source
from seatrack.live.sources import open_udp
from seatrack.live.sources import run_source

__all__ = ["GC_THRESHOLDS", "LiveOptions", "LiveProcess", "tune_garbage_collector"]


@dataclass
class LiveOptions:
    """Options of ``seatrack live`` (see :mod:`seatrack.commands.live`)."""

    ais: list[Source] = field(default_factory=list)
    plots: list[Source] = field(default_factory=list)
    radar: Any = None
    http: tuple[str, int] | None = None
    nmea_out: tuple[str, int] | None = None
    store: Path | None = None
    window_s: float = 10.0
    queue_size: int = 4096
    tick_s: float = 0.25
    commit_s: float = 0.5
    ais_config: Any = None
    fusion: Any = None  # FusionConfig of radar.toml's [fusion] table (default: defaults)
    fusion_queue: int = 1  # scans waiting for the fusion worker at most


class LiveProcess:
    """The live process (see the module docstring); :meth:`run` until ``stop`` is set."""

    def __init__(self, opts: LiveOptions) -> None:
        self.opts = opts
        self.counters = Counters()
        self.assembler = Assembler()
        self.duplicates = Duplicates(opts.window_s)
        self.ais = LiveAis(opts.ais_config, opts.window_s)
        self.identities = _identities(opts)  # shared MMSIs split, AIS anomalies flagged
        self.names: dict[int, str] = {}
        self.picture = Picture()
        self.queue: asyncio.Queue[Chunk] = asyncio.Queue(opts.queue_size)
        self.radar: Any = None
        if opts.plots:
            from seatrack.live.radar import LiveRadar

            self.radar = LiveRadar(opts.radar, self.counters)
        self.listeners: list[Any] = []  # callables fed the picture changes
        self.viewers: list[Any] = []  # callables: True while someone watches the picture
        self.store: Any = None
        self.writer: Any = None
        self.restored = 0
        self.restore_s = 0.0
        self._closing = asyncio.Event()
        if opts.store is not None:
            self._open_store(opts.store)
        self.fusion: Any = None
        self._fusion_emitted = False  # the fusion, not the store, empties ais.emitted
        self._fusion_seen = 0  # the fusion's result version shown in the picture
        if opts.ais and self.radar is not None:
            from seatrack.live.fusion import LiveFusion

            self.fusion = LiveFusion(opts.radar, opts.fusion, opts.fusion_queue)
            self.radar.listeners.append(self.fusion.scan)
            self.picture.fused = True
            if self.ais.emitted is None:
                self.ais.emitted, self._fusion_emitted = [], True
        self.nmea_out: Any = None
        if opts.nmea_out is not None and self.radar is not None:
            from seatrack.live.nmea_out import NmeaOut

            self.nmea_out = NmeaOut(*opts.nmea_out, self.counters)
            self.radar.on_scan.append(self.nmea_out.scan)
        self.http_port: int | None = None
        self._transports: list[Any] = []
        self.udp_ports: list[int] = []  # bound ports of the UDP sources, in order
        self._store_task: asyncio.Task | None = None
        self._tasks: list[asyncio.Task] = []

    def _open_store(self, path: Path) -> None:
        from seatrack.live.store import Store
        from seatrack.live.store import StoreWriter

        t0 = time.perf_counter()
        self.store = Store(path)
        self.writer = StoreWriter(self.store)
        self.ais.emitted = []
        with _collector_paused():  # tens of thousands of objects made, none garbage
            self.restored = self.writer.restore(self.ais, self.radar, self.counters)
            if self.ais.vessels:  # each MMSI's split goes on from its restored vessels
                keys, tr, t = self.ais.tracks()
                self.identities.resume(keys, t, tr.lat, tr.lon, tr.speed / KNOT_MPS,
                                       np.degrees(tr.course))  # fmt: skip
        self.restore_s = time.perf_counter() - t0
        self.names.update({m: v.name for m, v in self.ais.vessels.items() if v.name})
        if self.radar is not None:
            self.radar.on_scan.append(self.writer.radar_scan)

    async def commit(self) -> None:
        """Write what was gathered since the last commit (in a worker thread)."""
        for m in self.ais.dirty:
            self.ais.vessels[m].name = self.names.get(m, "")
        batch = self.writer.take(self.ais, self.radar, self.counters)
        await asyncio.to_thread(self.store.commit, batch)

    async def store_loop(self) -> None:
        """Commit every ``commit_s`` seconds, and once more when the process stops."""
        while True:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._closing.wait(), self.opts.commit_s)
            closing = self._closing.is_set()  # set during the commit: one more
            await self.commit()
            if closing:
                return

    # ---- AIS ------------------------------------------------------------------------------
    def overflow(self, chunk: Chunk) -> None:
        """A datagram that found the queue full: its lines are rejected."""
        if chunk.kind == "ais":
            self.counters.reject("queue full", len(chunk.lines))
        else:
            self.counters.plots_rejected["queue full"] += 1

    def handle(self, chunks: list[Chunk]) -> None:
        """Process chunks of lines (AIS messages, radar datagrams)."""
        pos = Positions()
        for c in chunks:
            if c.kind == "plots":
                if self.radar is not None:
                    for data in c.lines:
                        self.radar.datagram(data, c.received_s, c.perf_s)
                continue
            read_lines(c.lines, c.source, c.received_s, c.perf_s, self.assembler,
                       self.duplicates, self.counters, pos, self._name)  # fmt: skip
        expired = self.assembler.expire(time.time())
        if expired:
            read_messages(expired, self.duplicates, self.counters, pos, self._name)
        if len(pos):
            self.track(pos)

    def handle_messages(self, messages: list[Message]) -> None:
        """Count, de-duplicate, decode and track complete messages."""
        pos = Positions()
        read_messages(messages, self.duplicates, self.counters, pos, self._name)
        if len(pos):
            self.track(pos)

    def _name(self, mmsi: int, name: str) -> None:
        if self.names.get(mmsi) != name:
            self.names[mmsi] = name
            if mmsi in self.ais.vessels:
                self.ais.dirty.add(mmsi)
                self.ais.changed.add(mmsi)

    def track(self, pos: Positions) -> None:
        """Fold position reports into the AIS picture and count them."""
        cnt = self.counters
        emitted = self.ais.emitted if self.fusion is not None else None
        n0 = 0 if emitted is None else len(emitted)
        c = pos.columns()
        rows = np.column_stack((c["t"], c["lat"], c["lon"], c["sog_kn"], c["cog_deg"]))
        keys = self.identities.route(c["mmsi"], rows)
        used = self.ais.add(keys, c["t"], c["lat"], c["lon"], c["sog_kn"], c["cog_deg"])
        if self.fusion is not None and emitted is not None:  # every used report's state
            self.fusion.add_estimates(emitted[n0:])
            if self._fusion_emitted:
                emitted.clear()
        n_used = int(used.sum())
        cnt.received += len(pos)
        cnt.decoded += n_used
        cnt.positions += n_used
        cnt.late += len(pos) - n_used
        cnt.latency.add(time.perf_counter() - c["perf_s"][used])
        if self.writer is not None:
            k = np.flatnonzero(used)
            self.writer.ais_reports(list(zip(
                c["mmsi"][k].tolist(), c["t"][k].tolist(), c["lat"][k].tolist(),
                c["lon"][k].tolist(), c["sog_kn"][k].tolist(), c["cog_deg"][k].tolist(),
                [pos.sources[j] for j in k.tolist()], c["received_s"][k].tolist(), strict=True,
            )))  # fmt: skip

    async def consume(self) -> None:
        """The consumer task: chunks off the queue, in bursts (up to 64 chunks or about
        256 lines: the latency of a burst's first message grows with its size)."""
        while True:
            chunks = [await self.queue.get()]
            lines = len(chunks[0].lines)
            while len(chunks) < 64 and lines < 256:
                try:
                    chunks.append(self.queue.get_nowait())
                except asyncio.QueueEmpty:
                    break
                lines += len(chunks[-1].lines)
            self.handle(chunks)
            for _ in chunks:
                self.queue.task_done()

    async def tick(self) -> None:
        """Close timed-out scans (once the queue is read) and fragments; refresh the
        picture while someone watches it (the trackers are always current: the GeoJSON
        view is computed for the viewers)."""
        while True:
            await asyncio.sleep(self.opts.tick_s)
            expired = self.assembler.expire(time.time())
            if expired:
                self.handle_messages(expired)
            if self.radar is not None and self.queue.empty():  # caught up: nothing to read
                self.radar.timeout(time.time())
            if any(wants() for wants in self.viewers):
                self.refresh()

    def refresh(self) -> None:
        """Update the picture from the trackers and hand the changes to the listeners."""
        self.picture.refresh_ais(self.ais, self.names, self.identities)
        if self.radar is not None and self.radar.changed:
            self.picture.set_radar(self.radar.current)
            self.radar.changed = False
        if self.fusion is not None and self.fusion.version != self._fusion_seen:
            self._fusion_seen = self.fusion.version
            self.picture.set_fusion(self.fusion.tracks, self.fusion.not_seen)
        changes = self.picture.take_changes()
        if changes is not None:
            for fn in self.listeners:
                fn("picture", changes)

    def health(self) -> dict[str, Any]:
        """``/api/health``: counters, vessels and radar tracks."""
        h = self.counters.health()
        h["vessels"] = sum(1 for v in self.ais.vessels.values() if v.estimate is not None)
        h["radar_tracks"] = 0 if self.radar is None else self.radar.n_tracks
        if self.fusion is not None:
            h["dark"] = self.fusion.n_dark
            h["not_seen"] = len(self.fusion.not_seen)
            h["fusion_ms"] = self.fusion.latency.percentiles_ms()
            h["fusion_scans"] = self.fusion.version
            h["fusion_scans_dropped"] = self.fusion.dropped
            h["fusion_waiting"] = self.fusion.waiting
            if self.fusion.errors:
                h["fusion_errors"] = dict(self.fusion.errors)
        if self.radar is not None and self.radar.listener_errors:
            h["scan_consumer_errors"] = dict(self.radar.listener_errors)
        h["ais_flags"] = dict(self.identities.counts)
        h["pending_fragments"] = self.assembler.pending
        h["queue"] = self.queue.qsize()
        if self.store is not None:
            h["store"] = {"path": str(self.store.path), "commits": self.store.commits,
                          "committed_rows": self.store.committed_rows}  # fmt: skip
        return h

    # ---- running --------------------------------------------------------------------------
    async def start(self) -> list[asyncio.Task]:
        """Bind the sources and start the tasks; returns the tasks of the FILE sources."""
        cnt = self.counters

        def reconnected() -> None:
            cnt.reconnects += 1

        if self.fusion is not None:
            self.fusion.start()
        self._tasks.append(asyncio.create_task(self.consume()))
        self._tasks.append(asyncio.create_task(self.tick()))
        if self.store is not None:
            self._store_task = asyncio.create_task(self.store_loop())
        files = []
        for kind, sources in (("ais", self.opts.ais), ("plots", self.opts.plots)):
            for src in sources:
                if src.kind == "udp":
                    tr = await open_udp(src, self.queue, self.overflow, kind)
                    self._transports.append(tr)
                    self.udp_ports.append(tr.get_extra_info("sockname")[1])
                else:
                    task = asyncio.create_task(
                        run_source(src, self.queue, self.overflow, reconnected, kind)
                    )
                    self._tasks.append(task)
                    if src.kind == "file":
                        files.append(task)
        return files

    async def drain(self) -> None:
        """Wait until every queued chunk is processed, then refresh."""
        await self.queue.join()
        if self.radar is not None:
            self.radar.flush()
        if self.fusion is not None:
            await asyncio.to_thread(self.fusion.wait_idle)
        self.refresh()

    async def stop(self) -> None:
        """Close the sources and cancel the tasks."""
        for tr in self._transports:
            tr.close()
        for t in self._tasks:
            t.cancel()
        for t in self._tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await t
        self._tasks.clear()
        if self.fusion is not None:
            await asyncio.to_thread(self.fusion.close)
        if self.nmea_out is not None:
            self.nmea_out.close()
        if self.store is not None:
            self._closing.set()
            if self._store_task is not None:
                await self._store_task  # the last commit
            else:
                await self.commit()
            self.store.close()
            self.store = None


@contextlib.contextmanager
def _collector_paused() -> Iterator[None]:
    """No automatic garbage collection inside (a bulk load: the collector would scan the
    growing heap again and again, for no garbage); as it was after."""
    import gc

    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


#: the collector's thresholds for a live process (:func:`tune_garbage_collector`): a young
#: collection every 10,000 allocations net, a middle one every 50 young ones
GC_THRESHOLDS = (10_000, 50, 10)


def tune_garbage_collector() -> int:
    """Set the garbage collector for a long-running live process; returns how many
    objects are frozen.

    Every object alive now (modules, configuration, a picture restored from the store) is
    moved out of the collector's sight (:func:`gc.freeze`), so that no later collection
    walks it again; and the thresholds become :data:`GC_THRESHOLDS`, so that the objects
    of a report (its estimate, its store row), which live until the vessel's next report
    or the next scan, die in the young generations instead of piling up in the old one,
    whose full collections stall the event loop. Measured with ``benchmarks/live.py``
    (10,000 vessels at 20,000 msg/s, 30 s, ``gc.callbacks``): 28 full collections of
    135 ms each without either; with the freeze alone 9-46 full collections of 18-49 ms
    median (latency max 93-131 ms); with both, none and one middle collection of 62-74 ms
    (latency max 38-42 ms). Called once the process is up; no collection before (it would
    delay a restarted process's first answer by 0.1-0.2 s with 10,000 vessels restored).
    """
    import gc

    gc.freeze()
    gc.set_threshold(*GC_THRESHOLDS)
    return gc.get_freeze_count()


def _identities(opts: LiveOptions) -> Any:
    """The causal MMSI split of the process: in the radar's plane when there is one, the
    gap keys of its ``[fusion]`` table (the defaults without one)."""
    from seatrack.live.identity import LiveIdentities

    origin = None
    if opts.radar is not None:
        origin = (math.degrees(opts.radar.site.lat), math.degrees(opts.radar.site.lon))
    if opts.fusion is None:
        return LiveIdentities(origin)
    return LiveIdentities(origin, opts.fusion.gap_factor, opts.fusion.min_gap)
