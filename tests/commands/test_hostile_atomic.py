"""Every command's outputs are atomic: a write that fails part-way (the file-size limit
RLIMIT_FSIZE, as a full disk would) keeps the previous output and leaves no temporary.

All commands run in one child process (the limit is per process), each with a limit below
the size of its output, after a warm-up run without the limit (compiled kernels and caches
are written then, not under the limit).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_hostile_ais import CSV_TEXT
from test_hostile_navigate import nav_inputs
from test_hostile_simulate import SCENARIO
from test_hostile_tma import BEARINGS
from test_hostile_track import PLOTS

PREVIOUS = b"previous good output\n"

CHILD = r"""
import contextlib, io, json, resource, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
from seatrack.cli import main
cases = json.loads(sys.argv[1])
results = {}
for name, case in cases.items():
    for argv, limit in ((case["warmup"], None), (case["argv"], case["limit"])):
        if argv is None:
            continue
        soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
        if limit is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, hard))
        err = io.StringIO()
        try:
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                main(argv)
        except SystemExit as exc:
            code = exc.code
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
    results[name] = {"code": code, "err": err.getvalue()}
print(json.dumps(results))
"""


def _cases(d: Path) -> tuple[dict[str, dict[str, object]], dict[str, list[Path]]]:
    """Command lines (with a warm-up run writing elsewhere) and the outputs each must keep."""
    start = nav_inputs(d)
    (d / "plots.csv").write_text(PLOTS)
    (d / "b.csv").write_text(BEARINGS)
    (d / "ais.csv").write_text(CSV_TEXT)
    (d / "sc.toml").write_text(SCENARIO)
    nav = ["--map", d / "map.csv", "--echoes", d / "echoes.csv", "--start", start]
    ev = ["evaluate", d / "sc.toml", "--methods", "ekf", "--runs", "1", "--no-progress"]
    spec = {  # name: (argv with OUT, output paths, limit in bytes, warm up)
        "navigate": (["navigate", *nav, "--out", "OUT"], ["nav.csv"], 300, True),
        "survey": (["survey", *nav, "--out", "OUT"], ["map2.csv"], 100, True),
        "simulate": (["simulate", d / "sc.toml", "--out", "OUT"], ["sim/truth.csv"], 1000, True),
        "evaluate": ([*ev, "--csv", "OUT"], ["table.csv"], 100, True),
        "track": (["track", d / "plots.csv", "--out", "OUT"], ["track.csv"], 1000, True),
        "tma": (["tma", d / "b.csv", "--no-detect", "--out", "OUT"], ["result.json"], 500, True),
        "ais": (["ais", d / "ais.csv", "--out", "OUT"], ["tracks.csv"], 1000, True),
        "demo": (["demo", "--runs", "1", "--processes", "1", "--out", "OUT"],
                 ["demo/data/truth.csv", "demo/results.txt"], 1000, False),
    }  # fmt: skip
    cases, outputs = {}, {}
    for name, (argv, outs, limit, warm) in spec.items():
        target = d / outs[0].split("/")[0]
        paths = [d / o for o in outs]
        for p in paths:
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(PREVIOUS)
        warm_target = d / "warm" / target.name
        cases[name] = {
            "argv": [str(target if a == "OUT" else a) for a in argv],
            "warmup": [str(warm_target if a == "OUT" else a) for a in argv] if warm else None,
            "limit": limit,
        }
        outputs[name] = paths
    return cases, outputs


@pytest.fixture(scope="module")
def child_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, dict]:
    d = tmp_path_factory.mktemp("atomic")
    cases, outputs = _cases(d)
    r = subprocess.run([sys.executable, "-c", CHILD, json.dumps(cases)], capture_output=True,
                       text=True, timeout=600)  # fmt: skip
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.splitlines()[-1]), outputs


@pytest.mark.parametrize(
    "name", ["navigate", "survey", "simulate", "evaluate", "track", "tma", "ais", "demo"]
)
def test_a_write_cut_part_way_keeps_the_previous_output(child_run, name):
    results, outputs = child_run
    res = results[name]
    assert res["code"] == 2, res
    assert res["err"].startswith("error: ") and "File too large" in res["err"], res
    assert len(res["err"].strip().splitlines()) == 1, res
    assert str(outputs[name][0].parent) in res["err"] and "/." not in res["err"], res
    for p in outputs[name]:
        assert p.read_bytes() == PREVIOUS, p
        left = [f for f in os.listdir(p.parent) if f.startswith(".")]
        assert not left, f"temporaries left in {p.parent}: {left}"
