"""``seatrack live``: bad command lines are one ``error:`` line and exit 2; FILE sources
without ``--http`` end by themselves with the counters."""

from __future__ import annotations

import json

import pytest

from cli_inprocess import seatrack
from seatrack.live.nmea import encode_report


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "give at least one --ais or --plots source"),
        (["--ais", "ftp://x:1"], "--ais: expected udp://HOST:PORT, tcp://HOST:PORT or a file"),
        (["--ais", "udp://127.0.0.1"], "--ais: expected HOST:PORT"),
        (["--ais", "nothere.nmea"], "--ais: nothere.nmea: no such file"),
        (["--plots", "udp://127.0.0.1:0"], "--plots needs --config radar.toml"),
        (["--plots", "tcp://127.0.0.1:5"], "--plots: udp://HOST:PORT or a file"),
        (["--ais", "udp://127.0.0.1:0", "--window", "-1"], "--window"),
        (["--ais", "udp://127.0.0.1:0", "--nmea-out", "tcp://1.2.3.4:5"], "--nmea-out: expected"),
    ],
)
def test_bad_command_lines(args, message):
    run = seatrack("live", *args)
    assert run.returncode == 2 and run.stderr.startswith("error: ") and message in run.stderr


def test_file_source_ends_with_the_counters(tmp_path):
    p = tmp_path / "ais.nmea"
    lines = [encode_report(219000001, 1.7e9 + k, 57.0, 11.0 + k * 1e-4, 7.0, 90.0)[0]
             for k in range(5)]  # fmt: skip
    p.write_bytes(b"\n".join([*lines, b"!AIVDM,garbage"]) + b"\n")
    run = seatrack("live", "--ais", p)
    assert run.returncode == 0, run.stderr
    h = json.loads(run.stdout.splitlines()[-1])
    assert (h["received"], h["decoded"], h["vessels"]) == (6, 5, 1)
    assert h["rejected"] == {"truncated sentence": 1}
