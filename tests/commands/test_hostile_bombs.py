"""Size bombs of issue 26: small inputs or option values that ask for unbounded memory or
time are refused before the work starts, with one line naming the cause.

All cases run in one child process whose address space is capped (RLIMIT_AS, 3 GB: the
interpreter with numba and pyarrow maps about 1 GB), so a regression fails with "out of
memory" instead of exhausting the machine; each case must end within 10 s.
"""

from __future__ import annotations

import json
import subprocess
import sys
import zlib
from pathlib import Path

import pyarrow as pa
from test_hostile_navigate import nav_inputs
from test_hostile_track import PLOTS

from seatrack.simulate.scenarios import bundled_scenario

CHILD = r"""
import contextlib, io, json, resource, sys, time
cap = 3 << 30
resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
from seatrack.cli import main
results = {}
for name, argv in json.loads(sys.argv[1]).items():
    err = io.StringIO()
    t0 = time.monotonic()
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            main(argv)
    except SystemExit as exc:
        code = exc.code
    results[name] = {"code": code, "err": err.getvalue(), "s": time.monotonic() - t0}
print(json.dumps(results))
"""

ZEROS = bytes(1 << 24)


def _gzip_bomb(path: Path, head: bytes, mb: int) -> None:
    """``head`` then ``mb`` MiB of NUL bytes, gzip-compressed (about 1000:1)."""
    co = zlib.compressobj(6, zlib.DEFLATED, 31)
    with path.open("wb") as fh:
        fh.write(co.compress(head))
        for _ in range(mb // 16):
            fh.write(co.compress(ZEROS))
        fh.write(co.flush())


def _zstd_bomb(path: Path, head: bytes, mb: int) -> None:
    with pa.output_stream(str(path), compression="zstd") as fh:
        fh.write(head)
        for _ in range(mb // 16):
            fh.write(ZEROS)


def _cases(d: Path) -> dict[str, tuple[list[str], str]]:
    """name -> (argv, words the error line must hold)."""
    ais_head = b"mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg\n"
    _gzip_bomb(d / "ais.csv.gz", ais_head, 64)
    _zstd_bomb(d / "ais.csv.zst", ais_head, 64)
    _gzip_bomb(d / "plots.csv", PLOTS.encode(), 64)  # named .csv, really gzip
    head, *body = PLOTS.splitlines()
    for name, width, n in (("long_id.csv", 300_000, 5000), ("wide_id.csv", 100_000, 20_000)):
        rows = [head]
        for k in range(n):  # one track id this long: ids were as wide as the longest
            cells = body[k % len(body)].split(",")
            cells[0] = "x" * width if k == 7 else f"t{k // len(body)}"
            rows.append(",".join(cells))
        (d / name).write_text("\n".join(rows) + "\n")
    (d / "labelled.csv").write_text(PLOTS)
    (d / "queue.toml").write_text("queue_length = 1000000000\n")
    coastal = bundled_scenario("coastal_multitarget").read_text()
    (d / "crowd.toml").write_text(coastal.replace("targets = 20 ", "targets = 100000 "))
    (d / "births.toml").write_text(
        coastal.replace("births_per_scan = 0.03", "births_per_scan = 1e6")
    )
    (d / "crossings.toml").write_text(coastal.replace("crossings = 2 ", "crossings = 50000 "))
    start = nav_inputs(d)
    echoes = (d / "echoes.csv").read_text().splitlines()
    first = echoes[1].split(",")
    last = list(first)
    last[0] = str(float(first[0]) + 1.5e6)
    (d / "gap.csv").write_text("\n".join([echoes[0], ",".join(first), ",".join(last)]) + "\n")
    out = str(d / "out.csv")
    return {
        "ais gzip bomb": (["ais", str(d / "ais.csv.gz"), "--out", out], "ais.csv.gz"),
        "ais zstd bomb": (["ais", str(d / "ais.csv.zst"), "--out", out], "ais.csv.zst"),
        "gzip named .csv": (["track", str(d / "plots.csv"), "--out", out], "plots.csv"),
        "300 kB track id": (["track", str(d / "long_id.csv"), "--out", out], "line 9"),
        "100 kB track id": (["track", str(d / "wide_id.csv"), "--out", out],
                            "line 9: column track = 'xxx"),
        "queue_length 1e9": (["track", str(d / "labelled.csv"), "--method", "turning",
                              "--config", str(d / "queue.toml"), "--out", out],
                             "queue_length: must be <= 1000"),
        "simulate 1e5 targets": (["simulate", str(d / "crowd.toml"), "--out", str(d / "sim")],
                                 "multitarget"),
        "evaluate 1e5 targets": (["evaluate", str(d / "crowd.toml")], "multitarget"),
        "births 1e6 per scan": (["evaluate", str(d / "births.toml")], "multitarget"),
        "50000 crossings": (["simulate", str(d / "crossings.toml"), "--out", str(d / "sim")],
                            "multitarget"),
        "evaluate 1e5 runs": (["evaluate", "linear_cv", "--runs", "100000", "--no-progress"],
                              "100000 runs"),
        "multi-target 1e5 runs": (["evaluate", "coastal_multitarget", "--runs", "100000"],
                                  "100000 runs"),
        "navigate 1.5e6 s gap": (["navigate", "--map", str(d / "map.csv"), "--echoes",
                                  str(d / "gap.csv"), "--start", start, "--out", out], "gap.csv"),
    }  # fmt: skip


def test_size_bombs_are_refused_within_10_s_and_bounded_memory(tmp_path):
    cases = _cases(tmp_path)
    (tmp_path / "out.csv").write_bytes(b"previous\n")
    argv = {name: argv for name, (argv, _) in cases.items()}
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(argv)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    results = json.loads(proc.stdout.splitlines()[-1])
    for name, (_, words) in cases.items():
        r = results[name]
        lines = r["err"].splitlines()
        where = f"{name}: {r}"
        assert r["code"] == 2 and len(lines) == 1 and lines[0].startswith("error: "), where
        assert words in lines[0] and "out of memory" not in lines[0], where
        assert r["s"] < 10.0, where
    assert (tmp_path / "out.csv").read_bytes() == b"previous\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
