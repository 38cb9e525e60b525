"""Tests of seatrack.io.radar: the radar site file."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from seatrack.config import ConfigError
from seatrack.io.radar import in_sector
from seatrack.io.radar import load_radar_config
from seatrack.io.radar import parse_radar_config

TEXT = """
lat_deg = 57.70
lon_deg = 11.85
antenna_height_m = 20.0
sigma_range_m = 20.0
max_range_m = 30000.0
blind_sectors_deg = [[350.0, 10.0]]
method = "imm"

[sensor]
sigma_azimuth_deg = 0.3

[tracker]
max_speed_kn = 30.0
"""


def test_file_is_parsed_to_si(tmp_path: Path) -> None:
    p = tmp_path / "radar.toml"
    p.write_text(TEXT)
    setup = load_radar_config(p)
    assert setup.site.lat == pytest.approx(math.radians(57.70))
    assert setup.site.lon == pytest.approx(math.radians(11.85))
    assert setup.site.antenna_height == 20.0
    assert setup.site.max_range == 30000.0
    assert setup.site.method == "imm"
    assert setup.sensor.sigma_range == 20.0
    assert setup.sensor.sigma_azimuth == pytest.approx(math.radians(0.3))
    assert setup.tracker.max_speed == pytest.approx(30.0 * 1852.0 / 3600.0)
    assert setup.method_table["sensor"] == {"sigma_range_m": 20.0, "sigma_azimuth_deg": 0.3}


def test_defaults_apart_from_the_position() -> None:
    setup = parse_radar_config({"lat_deg": 1.0, "lon_deg": 2.0})
    assert setup.site.max_range == 40000.0
    assert setup.site.blind_sectors == ()
    assert setup.site.method == "ekf"
    assert setup.site.scan_period == 2.5


def test_scan_period_key() -> None:
    setup = parse_radar_config({"lat_deg": 1.0, "lon_deg": 2.0, "scan_period_s": 1.0})
    assert setup.site.scan_period == 1.0
    with pytest.raises(ConfigError, match="scan_period_s"):
        parse_radar_config({"lat_deg": 1.0, "lon_deg": 2.0, "scan_period_s": 0.0})


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({"lon_deg": 2.0}, "lat_deg: required"),
        ({"lat_deg": 91.0, "lon_deg": 2.0}, "lat_deg: must be <= 90"),
        ({"lat_deg": 1.0, "lon_deg": 2.0, "colour": "red"}, "unknown key 'colour'"),
        ({"lat_deg": 1.0, "lon_deg": 2.0, "min_range_m": 5e4}, "must be below max_range_m"),
        ({"lat_deg": 1.0, "lon_deg": 2.0, "blind_sectors_deg": [[1.0]]}, "blind_sectors_deg"),
        ({"lat_deg": 1.0, "lon_deg": 2.0, "method": "nope"}, "unknown method"),
        ({"lat_deg": 1.0, "lon_deg": 2.0, "tracker": 3}, "[tracker] must be a table"),
        ({"lat_deg": 1.0, "lon_deg": 2.0, "sigma_range_m": -1.0}, "sigma_range_m"),
    ],
)
def test_bad_tables_name_the_key(table: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        parse_radar_config(table, source="r.toml")


def test_sector_crossing_north() -> None:
    sector = (math.radians(350.0), math.radians(10.0))
    assert in_sector(math.radians(355.0), sector)
    assert in_sector(math.radians(5.0), sector)
    assert not in_sector(math.radians(20.0), sector)
    assert not in_sector(math.radians(180.0), sector)
