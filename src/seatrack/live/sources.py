"""Stream sources of the live process: ``udp://HOST:PORT`` (datagrams), ``tcp://HOST:PORT``
(a client that reconnects with backoff) and a FILE (read once).

AIS sources are split into lines; plot sources (``kind="plots"``) are UDP datagrams or a
FILE, each passed whole (binary CAT048 or CSV text). Each source puts :class:`Chunk` items
(the source's name, its lines, the receipt time as Unix seconds and as
``time.perf_counter()``) on a bounded asyncio queue. A TCP or FILE source waits when the
queue is full (back-pressure); a UDP source reads every datagram ready at once into one
chunk, and cannot wait, so a chunk that finds the queue full is handed to ``on_overflow``
(the process counts its lines as rejected, ``"queue full"``). Lines split across TCP
reads are joined.
"""

from __future__ import annotations

import asyncio
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from seatrack.io.table import InputError

__all__ = [
    "UDP_BATCH", "UDP_PAUSE_S", "UDP_PENDING", "UDP_RCVBUF", "Chunk", "Source", "UdpReader",
    "open_udp", "parse_hostport", "parse_source", "run_file", "run_source", "run_tcp",
]  # fmt: skip

#: the receive buffer asked for a UDP source, bytes: 32 MiB hold about 1.5 s of 20,000
#: messages/s (a datagram of 18 sentences takes ~2.3 kB of kernel buffer) while the
#: process is busy
UDP_RCVBUF = 32 << 20


@dataclass(frozen=True)
class Source:
    """``kind`` = ``udp`` | ``tcp`` | ``file``; ``host``, ``port`` or ``path``."""

    kind: str
    host: str = ""
    port: int = 0
    path: Path | None = None

    @property
    def name(self) -> str:
        return str(self.path) if self.kind == "file" else f"{self.kind}://{self.host}:{self.port}"


@dataclass
class Chunk:
    """Lines from one source with their receipt time (Unix s and perf counter s)."""

    source: str
    lines: list[bytes]
    received_s: float
    perf_s: float
    kind: str = "ais"


def parse_hostport(text: str, option: str) -> tuple[str, int]:
    """``HOST:PORT`` -> (host, port), checked."""
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise InputError(f"{option}: expected HOST:PORT, got {text!r}")
    return host.strip("[]"), int(port)


def parse_source(text: str, option: str) -> Source:
    """``udp://HOST:PORT``, ``tcp://HOST:PORT`` or a file path -> :class:`Source`."""
    if "://" in text:
        u = urlsplit(text)
        if u.scheme not in ("udp", "tcp"):
            raise InputError(f"{option}: expected udp://HOST:PORT, tcp://HOST:PORT or a file, "
                             f"got {text!r}")  # fmt: skip
        host, port = parse_hostport(u.netloc, option)
        return Source(u.scheme, host, port)
    p = Path(text)
    if not p.is_file():
        raise InputError(f"{option}: {text}: no such file")
    return Source("file", path=p)


#: Linux's ``SO_RCVBUFFORCE`` (not in Python's socket module): a receive buffer beyond
#: ``net.core.rmem_max`` for a process with ``CAP_NET_ADMIN``
_SO_RCVBUFFORCE = 33 if sys.platform.startswith("linux") else None

#: the most datagrams read from one UDP socket per wake-up of the event loop
UDP_BATCH = 8


#: a UDP source stops reading while this many chunks wait on the queue (and looks again
#: every :data:`UDP_PAUSE_S`): a backlog stays in the socket's receive buffer, not in the
#: process's memory
UDP_PENDING = 4
UDP_PAUSE_S = 0.005


class UdpReader:
    """A UDP source read by the event loop: each time the socket is readable, every
    datagram ready (up to :data:`UDP_BATCH`) is read and queued as one :class:`Chunk`
    (receipt time: when the reading started), so that a burst costs one wake-up and one
    queue item instead of one per datagram; paused while :data:`UDP_PENDING` chunks wait.
    Closed with :meth:`close`."""

    def __init__(self, sock: Any, name: str, kind: str, queue: asyncio.Queue,
                 overflow: Callable[[Chunk], None]) -> None:  # fmt: skip
        self.sock, self.name, self.kind = sock, name, kind
        self.queue, self.overflow = queue, overflow
        self.loop = asyncio.get_running_loop()
        self.loop.add_reader(sock.fileno(), self.ready)
        self.paused = False

    def resume(self) -> None:
        """Read again once the queue has room (else look again later)."""
        if self.sock.fileno() < 0:
            return
        if self.queue.qsize() >= UDP_PENDING:
            self.loop.call_later(UDP_PAUSE_S, self.resume)
            return
        self.paused = False
        self.loop.add_reader(self.sock.fileno(), self.ready)

    def ready(self) -> None:
        """Read what is ready (called by the event loop)."""
        if self.queue.qsize() >= UDP_PENDING:
            self.paused = True
            self.loop.remove_reader(self.sock.fileno())
            self.loop.call_later(UDP_PAUSE_S, self.resume)
            return
        now, perf = time.time(), time.perf_counter()
        lines: list[bytes] = []
        recv, ais = self.sock.recv, self.kind == "ais"
        for _ in range(UDP_BATCH):
            try:
                data = recv(1 << 16)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:  # pragma: no cover - e.g. an ICMP error reported on the socket
                break
            if ais:
                lines.extend(data.splitlines())
            else:
                lines.append(data)  # plots: binary, whole
        if lines:
            chunk = Chunk(self.name, lines, now, perf, self.kind)
            try:
                self.queue.put_nowait(chunk)
            except asyncio.QueueFull:
                self.overflow(chunk)

    def get_extra_info(self, name: str) -> Any:
        """``"sockname"``: the bound address (as an asyncio transport's)."""
        return self.sock.getsockname() if name == "sockname" else None

    def close(self) -> None:
        """Stop reading and close the socket."""
        if self.sock.fileno() >= 0:
            if not self.paused:
                self.loop.remove_reader(self.sock.fileno())
            self.sock.close()


async def open_udp(
    src: Source, queue: asyncio.Queue, overflow: Callable[[Chunk], None], kind: str = "ais"
) -> UdpReader:
    """Bind a UDP source (receive buffer enlarged: beyond ``net.core.rmem_max`` where the
    process may, with ``SO_RCVBUFFORCE``, else up to it)."""
    import socket

    sock = socket.socket(socket.AF_INET6 if ":" in src.host else socket.AF_INET,
                         socket.SOCK_DGRAM)  # fmt: skip
    for opt in (getattr(socket, "SO_RCVBUFFORCE", _SO_RCVBUFFORCE), socket.SO_RCVBUF):
        if opt is None:
            continue
        try:  # Linux caps SO_RCVBUF at net.core.rmem_max (and reports twice the grant)
            sock.setsockopt(socket.SOL_SOCKET, opt, UDP_RCVBUF)
            break
        except OSError:  # not privileged (SO_RCVBUFFORCE), or a system limit
            pass
    sock.bind((src.host, src.port))
    sock.setblocking(False)
    return UdpReader(sock, src.name, kind, queue, overflow)


async def run_tcp(
    src: Source,
    queue: asyncio.Queue,
    on_reconnect: Callable[[], None],
    kind: str = "ais",
    backoff_s: tuple[float, float] = (0.2, 10.0),
) -> None:
    """Read lines from a TCP server for ever, reconnecting after a failure or the end of
    the stream with exponential backoff (``backoff_s`` = first and largest wait, s; reset
    after a connection that delivered data)."""
    wait = backoff_s[0]
    while True:
        try:
            reader, writer = await asyncio.open_connection(src.host, src.port)
        except OSError:
            await asyncio.sleep(wait)
            wait = min(2 * wait, backoff_s[1])
            on_reconnect()
            continue
        rest = b""
        try:
            while True:
                data = await reader.read(1 << 16)
                if not data:
                    break
                wait = backoff_s[0]
                *lines, rest = (rest + data).split(b"\n")
                if len(rest) > 1 << 16:  # no line end in 64 KiB: not NMEA, pass it on
                    lines.append(rest)
                    rest = b""
                if lines:
                    chunk = Chunk(src.name, lines, time.time(), time.perf_counter(), kind)
                    await queue.put(chunk)
        except OSError:
            pass
        finally:
            writer.close()
        if rest:  # a line cut by the disconnection: counted (rejected) downstream
            await queue.put(Chunk(src.name, [rest], time.time(), time.perf_counter(), kind))
        await asyncio.sleep(wait)
        wait = min(2 * wait, backoff_s[1])
        on_reconnect()


async def run_file(src: Source, queue: asyncio.Queue, kind: str = "ais", block: int = 512) -> None:
    """Put a file's lines on the queue (blocks of ``block`` lines) and return; a plot
    file (CSV or CAT048) goes whole, as one datagram."""
    assert src.path is not None
    if kind == "plots":
        data = src.path.read_bytes()
        await queue.put(Chunk(src.name, [data], time.time(), time.perf_counter(), kind))
        return
    with open(src.path, "rb") as f:
        lines: list[bytes] = []
        for line in f:
            lines.append(line)
            if len(lines) >= block:
                await queue.put(Chunk(src.name, lines, time.time(), time.perf_counter(), kind))
                lines = []
        if lines:
            await queue.put(Chunk(src.name, lines, time.time(), time.perf_counter(), kind))


async def run_source(
    src: Source,
    queue: asyncio.Queue,
    overflow: Callable[[Chunk], None],
    on_reconnect: Callable[[], None],
    kind: str = "ais",
) -> UdpReader | None:
    """Start a source: UDP returns its reader (closed by the caller); TCP runs until
    cancelled; FILE returns once its lines are queued."""
    if src.kind == "udp":
        return await open_udp(src, queue, overflow, kind)
    if src.kind == "tcp":
        await run_tcp(src, queue, on_reconnect, kind)
        return None
    await run_file(src, queue, kind)
    return None
