"""``seatrack replay``: send recorded files to a live process over UDP with their own
timing (for tests, demos and training).

Inputs, detected by content:

* an NMEA log (``!AIVDM`` lines, with a tag block or a leading timestamp): each line sent
  at its time, a leading timestamp turned into a tag block ``\\c:...*hh\\`` (so the live
  process gets the message time); lines without a time go with the one before;
* an AIS CSV export (the columns ``seatrack ais`` reads): each usable report encoded as a
  type 1 position report with pyais's encoder and a tag block
  (:func:`seatrack.live.nmea.encode_report`);
* a plot file: CSV with the PLOTS.csv columns ``time_s``, ``range_m``, ``azimuth_deg``
  (one datagram per scan: the header and the scan's rows), or ASTERIX CAT048 (``.ast``:
  one datagram per scan, re-encoded by :func:`seatrack.io.asterix.encode_cat048` at the
  same resolution).

All files are merged in time order; the first item goes at once and each later one
``(t - t0) / speed`` seconds after it. AIS and plot files may be replayed to different
addresses (``--to`` for AIS, ``--plots-to`` for plots).
"""

from __future__ import annotations

import re
import socket
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.io.table import InputError
from seatrack.live.nmea import encode_report
from seatrack.live.nmea import parse_tag_time
from seatrack.live.nmea import tag_block

__all__ = ["Item", "file_items", "merge_files", "send_items"]

MAX_DATAGRAM = 1400
_TAG = re.compile(rb"^\\([^\\]*)\\")


@dataclass(frozen=True)
class Item:
    """One datagram to send: its time (s), the payload and its kind (``ais``|``plots``)."""

    t: float
    data: bytes
    kind: str


def _nmea_items(path: Path) -> list[Item]:
    from seatrack.io.ais.reports import parse_times

    items: list[Item] = []
    t_prev = 0.0
    for raw in path.read_bytes().splitlines():
        line = raw.strip()
        if not line:
            continue
        m = _TAG.match(line)
        t: float | None = None
        if m:
            t = parse_tag_time(m.group(1))
        else:
            k = line.find(b"!")
            if k > 0:
                txt = line[:k].decode("ascii", "replace").strip().rstrip(",;").strip()
                tt = float(parse_times(np.array([txt]))[0])
                if np.isfinite(tt):
                    t = tt
                    line = tag_block(tt) + line[k:]
        t_prev = t_prev if t is None else t
        items.append(Item(t_prev, line, "ais"))
    return items


def _ais_csv_items(path: Path) -> list[Item]:
    from seatrack.io.ais import read_ais

    r = read_ais([path])
    ok = np.flatnonzero(r.valid)
    return [
        Item(float(r.t[k]), line, "ais")
        for k in ok[np.argsort(r.t[ok], kind="stable")]
        for line in encode_report(int(r.mmsi[k]), float(r.t[k]), float(r.lat[k]),
                                  float(r.lon[k]), float(r.sog_kn[k]), float(r.cog_deg[k]))
    ]  # fmt: skip


def _plot_csv_items(path: Path) -> list[Item]:
    from seatrack.io.multitarget import read_unlabelled_plots

    p = read_unlabelled_plots(path)
    head = "time_s,range_m,azimuth_deg"
    az = np.degrees(p.azimuth) % 360.0
    items = []
    for t in np.unique(p.t):
        rows = [f"{t:.6f},{r:.6f},{a:.6f}" for r, a in zip(p.range[p.t == t], az[p.t == t],
                                                           strict=True)]  # fmt: skip
        for k in range(0, len(rows), 30):  # 30 rows: a datagram well under 1400 bytes
            items.append(Item(float(t), "\n".join([head, *rows[k : k + 30]]).encode(), "plots"))
    return items


def _ast_items(path: Path) -> list[Item]:
    from seatrack.io.asterix import DAY_S
    from seatrack.io.asterix import encode_cat048
    from seatrack.io.asterix import read_cat048

    c = read_cat048(path)
    items = []
    for tod in np.unique(c.time_of_day_s[np.isfinite(c.time_of_day_s)]):
        k = c.time_of_day_s == tod
        sac, sic = int(max(c.sac[k][0], 0)), int(max(c.sic[k][0], 0))
        for block in encode_cat048(np.full(k.sum(), tod), c.range_m[k], c.azimuth[k], sac, sic,
                                   c.mode3a[k], c.flight_level[k]):  # fmt: skip
            items.append(Item(float(tod % DAY_S), block, "plots"))
    return items


def file_items(path: str | Path) -> list[Item]:
    """The datagrams of one file (see the module docstring), in time order."""
    from seatrack.io.ais import looks_like_nmea
    from seatrack.io.table import check_input_file

    p = check_input_file(path, "a file to replay")
    head = p.read_bytes()[:4096]
    if p.suffix.lower() == ".ast" or head[:1] == b"\x30" and b"\n" not in head[:3]:
        items = _ast_items(p)
    elif looks_like_nmea(p):
        items = _nmea_items(p)
    else:
        first = head.split(b"\n", 1)[0].decode("utf-8-sig", "replace")
        cols = {c.strip() for c in first.split(",")}
        if {"time_s", "range_m", "azimuth_deg"} <= cols:
            items = _plot_csv_items(p)
        else:
            items = _ais_csv_items(p)
    if not items:
        raise InputError(f"{p}: nothing to replay")
    return sorted(items, key=lambda it: it.t)


def _pack(items: list[Item]) -> list[Item]:
    """AIS lines of one time in datagrams of at most ``MAX_DATAGRAM`` bytes."""
    out: list[Item] = []
    for it in items:
        last = out[-1] if out else None
        if (it.kind == "ais" and last is not None and last.kind == "ais" and last.t == it.t
                and len(last.data) + len(it.data) + 1 <= MAX_DATAGRAM):  # fmt: skip
            out[-1] = Item(it.t, last.data + b"\n" + it.data, "ais")
        else:
            out.append(it)
    return out


def send_items(
    items: list[Item], targets: dict[str, tuple[str, int]], speed: float = 1.0,
    stop: Any = None,
) -> int:  # fmt: skip
    """Send the items (merged, time order) to ``targets[kind]`` at ``speed`` times their
    own pace; returns the datagrams sent. ``stop``: a ``threading.Event`` that ends it."""
    items = _pack(sorted(items, key=lambda it: it.t))
    if not items:
        return 0
    socks = {k: socket.socket(socket.AF_INET6 if ":" in h else socket.AF_INET,
                              socket.SOCK_DGRAM) for k, (h, _) in targets.items()}  # fmt: skip
    t0, w0 = items[0].t, time.monotonic()
    sent = 0
    try:
        for it in items:
            if it.kind not in targets:
                continue
            wait = w0 + (it.t - t0) / speed - time.monotonic()
            if wait > 0:
                if stop is not None and stop.wait(wait):
                    break
                if stop is None:
                    time.sleep(wait)
            socks[it.kind].sendto(it.data, targets[it.kind])
            sent += 1
    finally:
        for s in socks.values():
            s.close()
    return sent


def merge_files(paths: list[Path]) -> list[Item]:
    """The items of several files in one time order; CAT048 times of day are put on the
    UTC day of the earliest Unix-timed item when there is one."""
    from seatrack.io.asterix import DAY_S

    per_file = [(Path(p), file_items(p)) for p in paths]
    unix = [it.t for p, items in per_file if p.suffix.lower() != ".ast" for it in items[:1]]
    midnight = (min(unix) // DAY_S) * DAY_S if unix else 0.0
    out: list[Item] = []
    for p, items in per_file:
        if p.suffix.lower() == ".ast" and midnight:
            items = [Item(it.t + midnight, it.data, it.kind) for it in items]
        out += items
    return sorted(out, key=lambda it: it.t)
