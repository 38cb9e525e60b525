"""Byte-identity of ``seatrack ais`` output against a reference source tree.

Runs ``seatrack ais`` twice per case, once with this checkout's ``src`` and once with a
reference tree (``--ref REV``: ``git archive REV src`` into a temporary folder; or
``--ref-src DIR``: an extracted ``src`` folder, whose numba cache then survives between
runs), each in a child process, and compares the TRACKS files byte for byte (CSV and
Parquet). Cases: every bundled real file alone and all of them together; the three hourly
files of ``benchmarks/ais.py`` (``--memory-limit 1G``, and with small vessel groups); a
synthetic single file; a DMA-shaped file (26 columns). Prints one line per output with
its size, wall time of both runs and whether the bytes are identical (first differing line
for CSV otherwise; for Parquet whose bytes differ, whether the tables are equal: the row
groups follow the vessel groups, whose size depends on the memory free at the time); exit
status 1 if any differs.

    python benchmarks/ais_compare.py --ref main                 # full sizes (minutes)
    python benchmarks/ais_compare.py --ref main --quick         # small synthetic files
    python benchmarks/ais_compare.py --ref-src REFDIR/src --keep DATA_DIR

``--keep DIR`` keeps the generated inputs and the reference outputs in ``DIR`` and reuses
them on the next run (the reference is run only when its output is missing).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from ais_data import hourly_files
from ais_data import vessels
from ais_data import write_csv
from seatrack.data import AIS_SAMPLES
from seatrack.data import ais_sample

ROOT = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class Case:
    """One ``seatrack ais`` run: its name, inputs and extra options."""

    name: str
    inputs: tuple[Path, ...]
    options: tuple[str, ...] = ()


def run(src: Path, case: Case, out: Path) -> float:
    """``seatrack ais`` of ``case`` with ``src`` on the path, writing ``out``; wall s."""
    env = dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, "-m", "seatrack.cli", "ais", *map(str, case.inputs)]
    cmd += ["--out", str(out), *case.options]
    t = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode:
        raise RuntimeError(f"{case.name} ({src}) failed: {proc.stderr.strip()}")
    return time.perf_counter() - t


def first_difference(a: Path, b: Path) -> str:
    """Where two files first differ (line of a CSV, else byte offset)."""
    with a.open("rb") as fa, b.open("rb") as fb:
        for k, (la, lb) in enumerate(zip(fa, fb, strict=False), start=1):
            if la != lb:
                return f"line {k}: {la[:120]!r} != {lb[:120]!r}"
    return f"sizes {a.stat().st_size} != {b.stat().st_size}"


def same_bytes(a: Path, b: Path) -> bool:
    if a.stat().st_size != b.stat().st_size:
        return False
    with a.open("rb") as fa, b.open("rb") as fb:
        while True:
            ca, cb = fa.read(1 << 24), fb.read(1 << 24)
            if ca != cb:
                return False
            if not ca:
                return True


def same_table(a: Path, b: Path) -> bool:
    """Parquet files holding equal tables (schema, metadata and values)."""
    import pyarrow.parquet as pq

    ta, tb = pq.read_table(a), pq.read_table(b)
    return ta.schema.equals(tb.schema, check_metadata=True) and ta.equals(tb)


def cases(data: Path, quick: bool) -> list[Case]:
    """The compared runs (synthetic inputs generated into ``data`` when missing)."""
    real = tuple(ais_sample(n) for n in AIS_SAMPLES)
    out = [Case(f"real {p.stem}", (p,)) for p in real]
    out.append(Case("real, all five files", real))
    n_hourly = 150_000 if quick else 3_000_000
    hourly = tuple(data / f"ais_hour{h}.csv" for h in range(3))
    if not all(p.exists() for p in hourly):
        hourly_files(data, n_hourly, max(n_hourly // 3000, 10))
    out.append(Case("three hourly files, 1G", hourly, ("--memory-limit", "1G")))
    out.append(Case("three hourly files, 64M", hourly, ("--memory-limit", "64M")))
    syn = data / "synthetic.csv"
    if not syn.exists():
        n = 100_000 if quick else 1_000_000
        write_csv(syn, vessels(n, 1000 if not quick else 100, seed=0), "common")
    out.append(Case("synthetic single file", (syn,)))
    dma = data / "aisdk.csv"
    if not dma.exists():
        n = 100_000 if quick else 3_000_000
        write_csv(dma, vessels(n, max(n // 3750, 10), seed=2, span=86400.0), "dma")
    out.append(Case("DMA-shaped file", (dma,), ("--memory-limit", "4G")))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    group = ap.add_mutually_exclusive_group(required=True)
    group.add_argument("--ref", help="git revision of the reference (git archive REV src)")
    group.add_argument("--ref-src", type=Path, help="an extracted reference src folder")
    ap.add_argument("--keep", type=Path, help="folder for inputs and reference outputs")
    ap.add_argument("--quick", action="store_true", help="small synthetic files")
    ap.add_argument("--only", help="run only cases whose name contains this text")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="ais-compare-") as tmp:
        work = Path(tmp)
        data = args.keep or work
        data.mkdir(parents=True, exist_ok=True)
        ref_src = args.ref_src
        if ref_src is None:
            archive = subprocess.run(
                ["git", "-C", str(ROOT), "archive", args.ref, "src"],
                capture_output=True,
                check=True,
            ).stdout
            subprocess.run(["tar", "-x", "-C", str(work)], input=archive, check=True)
            ref_src = work / "src"
        all_same = True
        print(f"{'case':36s} {'output':8s} {'bytes':>12s} {'ref s':>7s} {'new s':>7s} identical")
        for case in cases(data, args.quick):
            if args.only and args.only not in case.name:
                continue
            tag = case.name.replace(" ", "_").replace(",", "")
            for fmt in ("csv", "parquet"):
                ref_out = data / f"ref_{tag}.{fmt}"
                t_ref = float("nan")
                if not ref_out.exists():
                    t_ref = run(ref_src, case, ref_out)
                new_out = work / f"new_{tag}.{fmt}"
                t_new = run(ROOT / "src", case, new_out)
                same = same_bytes(ref_out, new_out)
                if same:
                    note = "yes"
                elif fmt == "parquet" and same_table(ref_out, new_out):
                    note = "same table (bytes differ: row groups)"
                else:
                    note = "NO: " + first_difference(ref_out, new_out)
                all_same &= not note.startswith("NO")
                size = ref_out.stat().st_size
                print(
                    f"{case.name:36s} {fmt:8s} {size:12,d} {t_ref:7.1f} {t_new:7.1f} {note}",
                    flush=True,
                )
                new_out.unlink()
    return 0 if all_same else 1


if __name__ == "__main__":
    sys.exit(main())
