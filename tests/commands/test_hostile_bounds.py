"""Issue 26 (bounded work, all-or-nothing commands): the internal errors, size bombs, output
paths and suspicious inputs it lists, each run through the CLI (see hostile_inputs.py).

Every case must end in exit status 0 or 2 with one ``error:`` line naming the file or the
option, and without touching an earlier output.
"""

from __future__ import annotations

import csv

import pytest
from hostile_inputs import assert_clean
from hostile_inputs import run_cli
from test_hostile_ais import NMEA_TEXT
from test_hostile_simulate import SCENARIO

from seatrack.io.ais.nmea import nmea_checksum

FAST = ["--methods", "ekf", "--runs", "1", "--no-progress"]


def _sentence(payload: str, fill: int = 0) -> str:
    body = f"AIVDM,1,1,,A,{payload},{fill}"
    return f"!{body}*{nmea_checksum(body.encode()):02X}"


# ---------------------------------------------------------------------------
# section 3: internal errors
# ---------------------------------------------------------------------------
#: payloads too short for their message type (1, 1, 18, 3, 27, 19): decoded with None fields
SHORT_PAYLOADS = ["1", "13mi84", "B", "3", "K", "C0000"]


def test_short_ais_payloads_are_rejected_lines_and_the_log_kept(tmp_path):
    good = NMEA_TEXT.splitlines()
    bad = [f"2017-07-05T10:00:00Z {_sentence(p)}" for p in SHORT_PAYLOADS]
    log = tmp_path / "log.nmea"
    log.write_text("\n".join([good[0], *bad, *good[1:]]) + "\n")
    out = tmp_path / "tracks.csv"
    args = ["ais", log, "--out", out]
    r = run_cli(*args)
    assert_clean(r, {}, args)
    assert r.code == 0, r.err
    rows = list(csv.DictReader(out.open(newline="")))
    reasons = {int(row["line"]): row["reject_reason"] for row in rows}
    for k in range(len(bad)):  # lines 2..7, each rejected with its own line number
        assert reasons[2 + k] == "undecodable message"
    assert sum(1 for row in rows if not row["reject_reason"]) == len(good)


@pytest.mark.parametrize("key", ["range_m = 20.0", "azimuth_deg = 0.3"])
def test_a_tiny_sensor_sigma_is_refused_by_name(tmp_path, key):
    sc = tmp_path / "s.toml"
    sc.write_text(SCENARIO.replace(key, key.split("=")[0] + "= 1e-300"))
    assert SCENARIO != sc.read_text()
    for cmd in (["evaluate", sc, *FAST], ["simulate", sc, "--out", tmp_path / "sim"]):
        r = run_cli(*cmd)
        assert r.code == 2, r.err
        assert r.err.startswith(f"error: {sc}: sensors[0].sigma.{key.split()[0]}: must be >= 1e-06")


@pytest.mark.parametrize("runs", ["0", "-5"])
def test_evaluate_runs_is_checked_for_multitarget_scenarios(runs):
    r = run_cli("evaluate", "coastal_multitarget", "--runs", runs)
    assert r.code == 2 and r.err == f"error: --runs = {runs} must be in [1, 100000]\n"


def test_evaluate_processes_zero_is_refused():
    r = run_cli("evaluate", "coastal_multitarget", "--processes", "0", "--runs", "1")
    assert r.code == 2 and r.err.startswith("error: --processes = 0 must be in [1, ")
