"""Compressed inputs (seatrack.io.compressed): recognised by their bytes, decompressed in
bounded chunks; bombs and corrupt data refused naming the file."""

from __future__ import annotations

import bz2
import gzip

import pyarrow as pa
import pytest

from seatrack.io.budget import budget
from seatrack.io.compressed import MAX_RATIO
from seatrack.io.compressed import RATIO_FREE_BYTES
from seatrack.io.compressed import compression_of
from seatrack.io.compressed import read_input
from seatrack.io.table import InputError

TEXT = b"time_s,range_m\n" + b"".join(b"%d,%d\n" % (k, 1000 + 7 * k) for k in range(5000))


def _zstd(data: bytes) -> bytes:
    sink = pa.BufferOutputStream()
    with pa.CompressedOutputStream(sink, "zstd") as fh:
        fh.write(data)
    return sink.getvalue().to_pybytes()


@pytest.mark.parametrize(
    ("name", "pack", "kind"),
    [("a.csv", gzip.compress, "gzip"), ("a.gz", bz2.compress, "bz2"), ("a.txt", _zstd, "zstd"),
     ("a.csv.gz", lambda d: d, None)],
)  # fmt: skip
def test_decompressed_by_content_whatever_the_name(tmp_path, name, pack, kind):
    p = tmp_path / name
    p.write_bytes(pack(TEXT))
    assert compression_of(p) == kind
    assert read_input(p) == TEXT


def test_a_bomb_is_stopped_early(tmp_path):
    p = tmp_path / "bomb.gz"
    n = RATIO_FREE_BYTES + (8 << 20)
    p.write_bytes(gzip.compress(bytes(n)))
    assert n > MAX_RATIO * p.stat().st_size
    with pytest.raises(InputError, match=rf"^{p}: decompresses to more than {MAX_RATIO} times"):
        read_input(p)


def test_a_whole_read_is_bounded_by_the_memory_budget(tmp_path):
    p = tmp_path / "big.gz"
    p.write_bytes(gzip.compress(TEXT * 40, compresslevel=1))  # 2.8 MB, compresses < 100:1
    with budget(memory_bytes=8 << 20), pytest.raises(InputError, match="memory budget"):
        read_input(p)


@pytest.mark.parametrize("cut", [0.5, 0.9])
def test_truncated_or_corrupt_data_name_the_file(tmp_path, cut):
    data = gzip.compress(TEXT)
    p = tmp_path / "t.csv.gz"
    p.write_bytes(data[: int(len(data) * cut)])
    with pytest.raises(InputError, match=rf"^{p}: not valid gzip data"):
        read_input(p)
    p.write_bytes(data[:30] + bytes(100) + data[130:])
    with pytest.raises(InputError, match=rf"^{p}: not valid gzip data"):
        read_input(p)


def test_a_bomb_is_refused_from_its_first_megabytes_whatever_its_size(tmp_path):
    """The ratio is that of the compressed bytes read so far, not of the whole file: a
    3 GB bomb stops as early as a 60 MB one (the check every input gets before work)."""
    from seatrack.io.compressed import PROBE_BYTES
    from seatrack.io.compressed import check_ratio
    from seatrack.io.table import check_input_file

    p = tmp_path / "bomb.csv.gz"
    p.write_bytes(gzip.compress(b"mmsi,time_utc\n" + bytes(60 << 20)))  # a header, then NULs
    with pytest.raises(InputError, match="compression bomb") as exc:
        check_ratio(p)
    so_far = float(str(exc.value).split("(")[1].split(" MB so far")[0]) * 1e6
    assert so_far <= PROBE_BYTES  # refused within the probe, long before the 60 MB
    with pytest.raises(InputError, match=rf"^{p}: decompresses to more than"):
        check_input_file(p)
    ok = tmp_path / "ok.csv.gz"
    ok.write_bytes(gzip.compress(b"".join(b"%d,2017-07-05T19:00:01Z\n" % k for k in range(200000))))
    check_ratio(ok)  # a real file's ratio (about 10) passes
