"""Tests of seatrack.io.asterix: CAT048 decode, the project's encoder, cross-checked
against the asterix-decoder package."""

from __future__ import annotations

import math

import asterix
import numpy as np
import pytest

from seatrack.io.asterix import NM_M
from seatrack.io.asterix import AsterixError
from seatrack.io.asterix import decode_cat048
from seatrack.io.asterix import encode_cat048
from seatrack.io.asterix import read_cat048
from seatrack.io.table import InputError


def plots(n: int = 300, seed: int = 0):
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 86399, n))
    r = rng.uniform(0, 255 * NM_M, n)
    az = rng.uniform(0, 2 * np.pi, n)
    m3 = np.where(rng.uniform(size=n) < 0.5, rng.integers(0, 4096, n), -1)
    fl = np.where(rng.uniform(size=n) < 0.5, rng.integers(-100, 2000, n) / 4, np.nan)
    return t, r, az, m3, fl


def test_round_trip_within_the_resolutions():
    t, r, az, m3, fl = plots()
    blocks = encode_cat048(t, r, az, sac=7, sic=9, mode3a=m3, flight_level=fl, max_block=500)
    assert len(blocks) > 1 and all(len(b) <= 500 for b in blocks)
    d = decode_cat048(b"".join(blocks))
    assert len(d) == t.size
    assert (d.sac == 7).all() and (d.sic == 9).all()
    assert np.abs(d.time_of_day_s - t).max() <= 0.5 / 128 + 1e-9
    assert np.abs(d.range_m - r).max() <= 0.5 * NM_M / 256 + 1e-9
    daz = (d.azimuth - az + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(daz).max() <= 0.5 * math.radians(360 / 65536) + 1e-12
    np.testing.assert_array_equal(d.mode3a, m3)
    np.testing.assert_array_equal(d.flight_level, fl)  # quarter FLs are exact


def test_encoder_agrees_with_asterix_decoder():
    t, r, az, m3, fl = plots(50, seed=1)
    blocks = encode_cat048(t, r, az, sac=3, sic=4, mode3a=m3, flight_level=fl)
    ours = decode_cat048(b"".join(blocks))
    theirs = [rec for b in blocks for rec in asterix.parse(b, verbose=False)]
    assert len(theirs) == len(ours)
    for k, rec in enumerate(theirs):
        assert rec["category"] == 48
        assert (rec["I010"]["SAC"]["val"], rec["I010"]["SIC"]["val"]) == (3, 4)
        assert rec["I140"]["ToD"]["val"] == pytest.approx(ours.time_of_day_s[k], abs=1e-9)
        assert rec["I040"]["RHO"]["val"] * NM_M == pytest.approx(ours.range_m[k], abs=1e-6)
        theta = rec["I040"]["THETA"]["val"]
        assert math.radians(theta) == pytest.approx(ours.azimuth[k], abs=1e-12)
        assert rec["I020"]["TYP"]["val"] == 1
        if ours.mode3a[k] >= 0:
            assert int(rec["I070"]["Mode3A"]["val"], 8) == ours.mode3a[k]
        else:
            assert "I070" not in rec
        if np.isfinite(ours.flight_level[k]):
            assert rec["I090"]["FL"]["val"] == pytest.approx(ours.flight_level[k])
        else:
            assert "I090" not in rec


def test_items_not_used_are_skipped_by_their_length():
    # FSPEC: 010 140 020 040 . . 130 | FX; 220 . 250 . . . . | FX; ... SP (FRN 27)
    fspec = bytes([0b11110011, 0b10100001, 0b00000001, 0b00000100])
    items = (
        bytes([1, 2]) + (128 * 100).to_bytes(3, "big")  # 010, 140 = 100 s
        + bytes([0x21, 0x00])  # 020 with one extension
        + (256 * 10).to_bytes(2, "big") + (16384).to_bytes(2, "big")  # 040: 10 NM, 90 deg
        + bytes([0b10100000, 5, 6])  # 130: two subfields
        + bytes([1, 2, 3])  # 220
        + bytes([2]) + bytes(16)  # 250: two 8-byte repetitions
        + bytes([3, 0xAA, 0xBB])  # SP: explicit length 3
    )  # fmt: skip
    rec = fspec + items
    block = bytes([48]) + (3 + len(rec)).to_bytes(2, "big") + rec
    d = decode_cat048(block)
    assert len(d) == 1 and d.time_of_day_s[0] == 100.0
    assert d.range_m[0] == pytest.approx(10 * NM_M) and d.azimuth[0] == pytest.approx(np.pi / 2)
    assert asterix.parse(block, verbose=False)[0]["I040"]["RHO"]["val"] == 10.0


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (bytes([34, 0, 4, 0]), "category 34"),
        (bytes([48, 0, 40, 0xF0]), "length 40 does not fit"),
        (bytes([48, 0, 5, 0xF0, 1]), "cut"),
        (bytes([48, 0]), "header cut short"),
    ],
)
def test_malformed_blocks_are_errors(data, message):
    with pytest.raises(AsterixError, match=message):
        decode_cat048(data)


def test_file_errors_name_the_file(tmp_path):
    p = tmp_path / "plots.ast"
    p.write_bytes(b"".join(encode_cat048([1.0], [1000.0], [0.5])) + bytes([48, 0, 9]))
    with pytest.raises(InputError, match=r"plots\.ast: byte 14"):
        read_cat048(p)
