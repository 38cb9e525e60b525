"""Warnings for suspicious units (seatrack.io.suspect): they fire on the mistakes a user
makes on day one and stay silent on the bundled scenarios and examples."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from seatrack.io.plots import read_plots
from seatrack.io.suspect import km_warning
from seatrack.io.suspect import ms_warning
from seatrack.io.suspect import radians_warning
from seatrack.io.tma import read_bearings
from seatrack.simulate.scenarios import bundled_scenario
from seatrack.simulate.scenarios import bundled_scenarios
from seatrack.simulate.scenarios import load_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_radians():
    rng = np.random.default_rng(0)
    rad = rng.uniform(0, 2 * math.pi, 50)
    assert "azimuth_deg is between" in radians_warning("p.csv", "azimuth_deg", rad)
    assert radians_warning("p.csv", "azimuth_deg", np.degrees(rad)) is None
    assert radians_warning("p.csv", "azimuth_deg", rad[:5]) is None  # too few to tell
    assert radians_warning("p.csv", "azimuth_deg", np.full(50, 3.0)) is None  # constant


def test_kilometres():
    km = np.linspace(2.0, 40.0, 30)
    assert "looks like kilometres" in km_warning("p.csv", "range_m", km)
    assert km_warning("p.csv", "range_m", 1000 * km) is None


def test_milliseconds():
    t = np.arange(30) * 2000.0  # a 2 s radar scan in ms
    assert "median 2000 s apart" in ms_warning("p.csv", "time_s", t)
    assert ms_warning("p.csv", "time_s", t / 1000) is None
    groups = np.repeat(["a", "b"], 15)
    t2 = np.concatenate([np.arange(15) * 60.0, 1e6 + np.arange(15) * 60.0])  # sonar, minutes
    assert ms_warning("p.csv", "time_s", t2, groups) is None
    assert ms_warning("p.csv", "time_s", t2 * 1000, groups) is not None


@pytest.mark.parametrize("name", bundled_scenarios())
def test_silent_on_the_bundled_scenarios(tmp_path, name, capsys):
    from seatrack.api.simulate import simulation_files
    from seatrack.api.simulate import write_simulation

    sc = load_scenario(bundled_scenario(name))
    if sc.multitarget is not None:
        return  # its plots are the unlabelled case, tracked by test_hostile_bounds
    write_simulation(sc.simulate(np.random.default_rng(sc.seed)), tmp_path)
    for p in simulation_files(sc, tmp_path):
        if p.name.startswith("plots_"):
            read_plots(p)
        elif p.name.startswith("bearings_"):
            read_bearings(p, default_sigma=math.radians(1.0))
    assert capsys.readouterr().err == ""


def test_silent_on_the_examples(capsys):
    read_bearings(EXAMPLES / "tma_bearings.csv", default_sigma=math.radians(1.0))
    assert capsys.readouterr().err == ""


def test_gyro_in_rad_per_s(tmp_path, capsys):
    from seatrack.io.navigation import read_gyro
    from seatrack.io.navigation import write_gyro
    from seatrack.simulate.radar_echoes import channel_landmarks
    from seatrack.simulate.radar_echoes import river_route
    from seatrack.simulate.radar_echoes import simulate_radar

    route = river_route(2000.0, 4.0)
    lm = channel_landmarks(route, 8, np.random.default_rng(1))
    sim = simulate_radar(route, lm, np.random.default_rng(2))
    deg = tmp_path / "gyro.csv"
    write_gyro(deg, sim.gyro_t, sim.gyro_rate)  # written in deg/s
    read_gyro(deg)
    assert capsys.readouterr().err == ""
    rad = tmp_path / "gyro_rad.csv"
    write_gyro(rad, sim.gyro_t, np.radians(sim.gyro_rate))  # the mistake: rad/s in the file
    read_gyro(rad)
    err = capsys.readouterr().err
    assert err.startswith(f"warning: {rad}: every turn_rate_dps is below 0.05") and "rad/s" in err


AIS_FILES = sorted((Path(__file__).resolve().parents[2] / "src/seatrack/data/ais").glob("*.csv"))


def _ais_variant(src: Path, dst: Path, how: str) -> Path:
    lines = src.read_text().splitlines()
    head = lines[0].split(",")
    names = {"lat": ("lat", "Latitude", "LAT"), "lon": ("lon", "Longitude", "LON"),
             "sog": ("sog_kn", "SOG")}  # fmt: skip
    col = {k: next(head.index(n) for n in v if n in head) for k, v in names.items()}
    out = [lines[0]]
    for ln in lines[1:]:
        c = ln.split(",")
        if how == "swap":
            c[col["lat"]], c[col["lon"]] = c[col["lon"]], c[col["lat"]]
        elif how == "mps" and c[col["sog"]].strip():
            c[col["sog"]] = f"{float(c[col['sog']]) * 0.514444:.2f}"
        out.append(",".join(c))
    dst.write_text("\n".join(out) + "\n")
    return dst


@pytest.mark.parametrize("path", AIS_FILES, ids=lambda p: p.name)
def test_ais_units_silent_on_the_bundled_logs_and_firing_on_the_mistakes(tmp_path, path):
    from seatrack.io.ais import read_ais
    from seatrack.io.suspect import AisUnitCheck

    def check(p: Path) -> list[str]:
        c = AisUnitCheck()
        c.add(read_ais([p]))
        return c.warnings(p.name)

    assert check(path) == []
    swapped = check(_ais_variant(path, tmp_path / "swap.csv", "swap"))
    has_cog = np.isfinite(read_ais([path]).cog_deg).any()  # the North Sea logs have none
    if has_cog:
        assert len(swapped) == 1 and "lat and lon look swapped" in swapped[0]
    else:
        assert swapped == []  # undetectable without courses (the speeds do not tell)
    mps = check(_ais_variant(path, tmp_path / "mps.csv", "mps"))
    assert len(mps) == 1 and "sog_kn is a median 0.5" in mps[0] and "m/s" in mps[0]
