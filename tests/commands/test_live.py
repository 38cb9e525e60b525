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


def test_radar_toml_fusion_table_is_read_and_checked(tmp_path):
    """``--config`` takes radar.toml's ``[fusion]`` table (bad keys: exit 2); with AIS and
    radar inputs the health has the fusion's counts."""
    from fusion_samples import write_scene

    _, plots, toml = write_scene(tmp_path)
    p = tmp_path / "ais.nmea"
    p.write_bytes(encode_report(219000001, 1.7e9, 56.0, 7.0, 7.0, 90.0)[0] + b"\n")
    run = seatrack("live", "--ais", p, "--plots", plots, "--config", toml)
    assert run.returncode == 0, run.stderr
    h = json.loads(run.stdout.splitlines()[-1])
    assert h["plots"]["scans"] == 100 and h["radar_tracks"] == 3
    assert 0 <= h["dark"] <= 3 and h["not_seen"] in (0, 1)  # present: the fusion ran
    bad = tmp_path / "bad.toml"
    bad.write_text(toml.read_text() + "bogus_s = 1.0\n")  # inside [fusion]
    run = seatrack("live", "--ais", p, "--plots", plots, "--config", bad)
    assert run.returncode == 2 and run.stderr.startswith("error: ") and "bogus_s" in run.stderr
