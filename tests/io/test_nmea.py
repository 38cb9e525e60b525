"""NMEA !AIVDM logs: real reports encoded with pyais, decoded back through read_nmea."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pyais.encode import encode_dict
from pyais.util import compute_checksum

from ais_samples import data_file
from seatrack.io.ais import format_times
from seatrack.io.ais import read_ais
from seatrack.io.ais import read_ais_csv
from seatrack.io.ais.nmea import nmea_checksum
from seatrack.io.ais.read import looks_like_nmea
from seatrack.io.ais.read import read_ais_csv as read_nmea


def _tag(t: float) -> str:
    body = f"c:{int(t)}"
    return f"\\{body}*{nmea_checksum(body.encode()):02X}\\"


def _split(sentence: str, seq: int) -> list[str]:
    """Split a one-sentence message into two fragments (valid NMEA 0183 multi-sentence)."""
    fields = sentence.split("*")[0][1:].split(",")
    payload, fill = fields[5], fields[6]
    out = []
    for k, (chunk, f) in enumerate(((payload[:15], "0"), (payload[15:], fill)), start=1):
        body = f"{fields[0]},2,{k},{seq},{fields[4]},{chunk},{f}"
        out.append(f"!{body}*{compute_checksum('!' + body):02X}")
    return out


def _encode_real(n: int = 400) -> tuple[list[str], np.ndarray]:
    """The first n rows of the Vestland file as NMEA lines; returns lines and row indices."""
    r = read_ais_csv(data_file("no_vestland_20220901.csv"))
    idx = np.arange(0, len(r), max(1, len(r) // n))[:n]
    iso = format_times(r.t[idx])
    lines: list[str] = []
    for j, (i, ts) in enumerate(zip(idx, iso, strict=True)):
        msg_type = 18 if j % 4 == 3 else 1
        data = {
            "type": msg_type,
            "mmsi": int(r.mmsi[i]),
            "lat": float(r.lat[i]),
            "lon": float(r.lon[i]),
            "speed": float(r.sog_kn[i]),
            "course": float(r.cog_deg[i]),
            "heading": int(r.heading_deg[i]),
        }
        (s,) = encode_dict(data, talker_id="AI", sentence_type="VDM", radio_channel="A")
        parts = _split(s, j % 10) if j % 5 == 2 else [s]
        for k, part in enumerate(parts):
            if j % 2:
                lines.append((_tag(r.t[i]) if k == 0 else "") + part)
            else:
                lines.append(f"{ts} {part}")
    return lines, idx


def test_real_reports_round_trip(tmp_path: Path) -> None:
    lines, idx = _encode_real()
    p = tmp_path / "log.nmea"
    p.write_text("\n".join(lines) + "\n")
    assert looks_like_nmea(p)
    src = read_ais_csv(data_file("no_vestland_20220901.csv"))
    r = read_nmea(p)
    assert len(r) == idx.size and r.valid.all()
    # every line accounted for: reports + continuation fragments
    assert len(r) + sum(r.skipped.values()) == len(lines)
    assert r.skipped == {"continuation fragment": int(np.sum(np.arange(idx.size) % 5 == 2))}
    assert np.array_equal(r.mmsi, src.mmsi[idx])
    assert np.array_equal(r.t, src.t[idx])
    # AIS resolution 1/10000 minute of arc: at most half a step of rounding
    assert np.abs(r.lat - src.lat[idx]).max() <= 0.5 / 600000 + 1e-12
    assert np.abs(r.lon - src.lon[idx]).max() <= 0.5 / 600000 + 1e-12
    assert np.abs(r.sog_kn - src.sog_kn[idx]).max() <= 0.05 + 1e-9
    assert np.abs(r.cog_deg - src.cog_deg[idx]).max() <= 0.05 + 1e-9
    # read_ais detects the NMEA log by content
    assert np.array_equal(read_ais([p]).t, r.t)


def test_bad_lines_are_rejected_or_counted(tmp_path: Path) -> None:
    good = encode_dict(
        {"type": 1, "mmsi": 257725000, "lat": 60.4, "lon": 5.3, "speed": 10.0, "course": 90.0},
        sentence_type="VDM",
    )[0]
    na = encode_dict({"type": 1, "mmsi": 257725001, "lat": 91, "lon": 181}, sentence_type="VDM")[0]
    static = encode_dict(
        {"type": 5, "mmsi": 257725000, "shipname": "TEST VESSEL", "destination": "BERGEN"},
        sentence_type="VDM",
    )
    assert len(static) == 2
    bad = good[:-2] + ("00" if good[-2:] != "00" else "11")
    frag = _split(good, 3)
    lines = [
        f"1661990400 {good}",  # 1 ok (epoch prefix)
        f"1661990401 {bad}",  # 2 bad checksum
        "",  # 3 blank
        f"1661990402 {frag[0]}",  # 4 fragment without its second part
        f"1661990403 {static[0]}",  # 5 type 5, two fragments
        f"1661990403 {static[1]}",  # 6
        "$GPRMC,092750.000,A,5321.6802,N,00630.3372,W,0.02,31.66,280511,,,A*43",  # 7
        good,  # 8 no timestamp
        f"2022-09-01T00:00:09Z {na}",  # 9 position not available
        "\\c:1661990405*00\\" + good,  # 10 bad tag-block checksum
        f"1661990406 {good}",  # 11 ok
        f"1661990406 {good}",  # 12 duplicate of 11
    ]
    p = tmp_path / "bad.nmea"
    p.write_text("\n".join(lines))
    r = read_nmea(p)
    got = dict(zip(r.line.tolist(), r.reject.tolist(), strict=True))
    assert got == {
        1: "",
        2: "bad checksum",
        3: "blank line",
        4: "incomplete multi-sentence message",
        8: "unparsable time",
        9: "lat not available (91)",
        10: "bad checksum",
        11: "",
        12: "duplicate report",
    }
    assert r.skipped == {
        "continuation fragment": 1,
        "not a position report (type 5)": 1,
        "not an AIS sentence": 1,
    }
    assert len(r) + sum(r.skipped.values()) == len(lines)
    assert r.t[0] == 1661990400.0 and r.mmsi[0] == 257725000
