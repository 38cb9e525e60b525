"""``seatrack live`` ingest without sockets: CPU time per AIS message and memory in one
process, less sensitive to a shared machine's load than the rates of ``live.py``.

The datagrams of ``benchmarks/live.py`` (type 1 reports with a ``c:`` tag block, 18
sentences per datagram, ``--vessels`` vessels reporting in turn at ``--rate`` messages
per second of message time) are built beforehand and handed to the process's consumer
(:meth:`~seatrack.live.process.LiveProcess.handle`) in bursts of 14 datagrams (about 256
lines, the consumer's burst): NMEA checks, decoding, duplicates, the AIS tracker and the
counters, as on the socket path. ``--fusion`` adds a radar (no scans), so that every
report also goes to the radar-AIS fusion's store of AIS states, as in ``live.py``.

Printed: the CPU time per message (``time.process_time``) and the rate it allows, for
``--repeats`` passes (each on a new process object); the resident memory after the
imports and its growth over the last pass (10,000 vessels: the out-of-order windows and
the duplicate filter fill in 10 s of messages).

    python benchmarks/live_ingest.py                      # 100,000 messages, 3 passes
    python benchmarks/live_ingest.py --messages 400000 --repeats 1   # memory at 20 s

Anchor (issue 27): 20,000 msg/s sustained; aim for at least 30,000 msg/s of CPU here.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from live import RADAR
from live import encode_type1
from seatrack.live.process import LiveOptions
from seatrack.live.process import LiveProcess
from seatrack.live.sources import Chunk
from seatrack.live.sources import Source


def rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def datagrams(n: int, vessels: int, rate: float) -> list[bytes]:
    rng = np.random.default_rng(0)
    mmsi = 200_000_000 + np.arange(vessels)
    lat0, lon0 = 57.0 + rng.uniform(-0.5, 0.5, vessels), 11.0 + rng.uniform(-0.8, 0.8, vessels)
    sog, cog = rng.uniform(0, 20, vessels), rng.uniform(0, 360, vessels)
    vn = sog * 0.514444 * np.cos(np.radians(cog)) / 111_320
    ve = sog * 0.514444 * np.sin(np.radians(cog)) / (111_320 * np.cos(np.radians(lat0)))
    t0 = time.time() - n / rate
    idx = np.arange(n) % vessels
    dt = np.arange(n) / rate
    lines = encode_type1(mmsi[idx], lat0[idx] + vn[idx] * dt, lon0[idx] + ve[idx] * dt,
                         sog[idx], cog[idx], (t0 + dt).astype(int) % 60,
                         (t0 + dt) * 1000)  # fmt: skip
    return [b"\n".join(lines[j : j + 18]) for j in range(0, n, 18)]


def options(fusion: bool, tmp: Path) -> LiveOptions:
    if not fusion:
        return LiveOptions()
    from seatrack.fusion.picture import load_fusion_config

    (tmp / "radar.toml").write_text(RADAR)
    radar, fcfg = load_fusion_config(tmp / "radar.toml")
    dummy = Source("udp", "127.0.0.1", 0)  # not opened: handle() is fed directly
    return LiveOptions(ais=[dummy], plots=[dummy], radar=radar, fusion=fcfg)


def one_pass(opts: LiveOptions, dgs: list[bytes], burst: int = 14) -> tuple[float, float, int]:
    """(CPU s, memory growth MB, messages received) of one pass."""
    proc = LiveProcess(opts)
    proc.handle([Chunk("warm-up", dgs[0].splitlines(), time.time(), time.perf_counter())])
    r0, c0 = rss_mb(), time.process_time()
    for j in range(1, len(dgs), burst):
        now, perf = time.time(), time.perf_counter()
        proc.handle([Chunk("udp://rx:1", d.splitlines(), now, perf) for d in dgs[j : j + burst]])
    cpu, grown = time.process_time() - c0, rss_mb() - r0
    cnt = proc.counters
    assert cnt.check() and cnt.late == 0 and not cnt.rejected, cnt.health()
    return cpu, grown, cnt.received


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--messages", type=int, default=100_000)
    ap.add_argument("--vessels", type=int, default=10_000)
    ap.add_argument("--rate", type=float, default=20_000.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--fusion", action="store_true")
    args = ap.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    dgs = datagrams(args.messages, args.vessels, args.rate)
    with tempfile.TemporaryDirectory() as d:
        opts = options(args.fusion, Path(d))
        print(f"resident memory after the imports and the datagrams: {rss_mb():.0f} MB")
        for _ in range(args.repeats):
            cpu, grown, n = one_pass(opts, dgs)
            print(f"{n} messages, {args.vessels} vessels{' + fusion' if args.fusion else ''}: "
                  f"{1e6 * cpu / n:.1f} us CPU per message ({n / cpu:,.0f} msg/s of CPU; "
                  f"anchor 20,000, aim 30,000); memory grew {grown:.0f} MB")  # fmt: skip
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
