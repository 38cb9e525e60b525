"""Input files that may be compressed, read in bounded chunks.

A file is decompressed by what it holds, not by its name: gzip, zstd and bzip2 are
recognised by their magic bytes (a ``.csv`` that is really gzip is read as gzip; a ``.gz``
that is not gzip is read as it is, and fails as the text it is). Decompression runs in
chunks, and is stopped with an :class:`~seatrack.io.table.InputError` naming the file

* when the data decompress to more than :data:`MAX_RATIO` times the compressed bytes
  read so far (a compression bomb: the bundled AIS logs gzip 4.4 to 6.4 times), once past
  :data:`RATIO_FREE_BYTES` -- a bomb is refused after its first MiB, whatever its size;
* when a whole-file read would hold more than the memory budget
  (:mod:`seatrack.io.budget`);
* when the compressed data are corrupt or truncated (the message names the input, never
  an output being written at the time).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

from seatrack.errors import InputError
from seatrack.io.budget import current
from seatrack.io.budget import format_bytes

__all__ = [
    "MAX_RATIO",
    "PROBE_BYTES",
    "RATIO_FREE_BYTES",
    "check_ratio",
    "compression_of",
    "open_input",
    "read_input",
]

#: largest decompressed / compressed size ratio accepted
MAX_RATIO = 100
#: decompressed bytes read before the ratio is checked (the first lines of a file may
#: compress very well)
RATIO_FREE_BYTES = 1 << 20
#: magic bytes -> pyarrow compression name
_MAGIC = ((b"\x1f\x8b", "gzip"), (b"\x28\xb5\x2f\xfd", "zstd"), (b"BZh", "bz2"))


def compression_of(path: Path) -> str | None:
    """``"gzip"``, ``"zstd"``, ``"bz2"`` by the file's first bytes, or None."""
    with path.open("rb") as fh:
        head = fh.read(4)
    return next((name for magic, name in _MAGIC if head.startswith(magic)), None)


class _Bounded(io.RawIOBase):
    """A decompressing stream that stops a bomb and names its file on a corrupt one."""

    def __init__(self, path: Path, comp: str, raw: Any, whole: bool) -> None:
        import pyarrow as pa

        self.path = path
        self.comp = comp
        self.raw = raw  # the compressed file: its position is the compressed bytes read
        self.stream = pa.CompressedInputStream(raw, comp)
        self.size = max(path.stat().st_size, 1)
        self.nbytes = 0
        self.limit = current().memory_bytes // 8 if whole else None

    def readable(self) -> bool:
        return True

    def read(self, size: int = -1) -> bytes:
        if size is None or size < 0:
            chunks = []
            while chunk := self.read(1 << 20):
                chunks.append(chunk)
            return b"".join(chunks)
        try:
            data = bytes(self.stream.read(size))
        except (OSError, ValueError) as exc:
            raise InputError(f"{self.path}: not valid {self.comp} data ({exc})") from None
        self.nbytes += len(data)
        if self.nbytes > RATIO_FREE_BYTES and self.nbytes > MAX_RATIO * max(self.raw.tell(), 1):
            raise InputError(
                f"{self.path}: decompresses to more than {MAX_RATIO} times its size "
                f"({format_bytes(self.nbytes)} so far from {format_bytes(self.raw.tell())} of "
                f"{format_bytes(self.size)}): a compression bomb, or not a measurement file"
            )
        if self.limit is not None and self.nbytes > self.limit:
            raise InputError(
                f"{self.path}: more than {format_bytes(self.limit)} of decompressed text to "
                f"hold in memory, over an eighth of the memory budget (raise it: seatrack "
                "--memory-limit SIZE ...)"
            )
        return data

    def readinto(self, b: Any) -> int:
        data = self.read(len(b))
        b[: len(data)] = data
        return len(data)

    def close(self) -> None:
        self.stream.close()
        self.raw.close()
        super().close()


def open_input(path: Path, whole: bool = False) -> Any:
    """A binary stream of ``path``, decompressed when it is gzip, zstd or bzip2 data.

    ``whole``: the caller reads the whole file into memory (the decompressed size is then
    also bounded by the memory budget). A plain file is returned as it is.

    Raises
    ------
    InputError
        The file cannot be opened (naming it).
    """
    import pyarrow as pa

    try:
        comp = compression_of(path)
        if comp is None:
            return path.open("rb")
        return _Bounded(path, comp, pa.OSFile(str(path)), whole)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None


#: decompressed bytes :func:`check_ratio` reads (pyarrow reads the compressed data 64 kB at
#: a time: a bomb shows its ratio within the first 7 MB)
PROBE_BYTES = 16 << 20


def check_ratio(path: Path) -> None:
    """Refuse a compression bomb before any work: the first :data:`PROBE_BYTES` of a
    compressed file are decompressed (a few milliseconds) and stopped as :func:`open_input`
    stops them. A plain file is not read.

    Raises
    ------
    InputError
        A compression bomb, corrupt compressed data, or an unreadable file (naming it).
    """
    try:
        if compression_of(path) is None:
            return
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None
    with open_input(path) as fh:
        done = 0
        while done < PROBE_BYTES and (chunk := fh.read(1 << 20)):
            done += len(chunk)


def read_input(path: Path) -> bytes:
    """The whole content of ``path``, decompressed (see :func:`open_input`)."""
    with open_input(path, whole=True) as fh:
        data: bytes = fh.read()
    return data
