"""``seatrack.api.fuse.fuse`` and ``seatrack fuse``: tables, files, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cli_inprocess import seatrack
from seatrack.api.fuse import TABLES
from seatrack.api.fuse import fuse
from seatrack.fusion import scenario as sc
from seatrack.fusion.coverage import Coverage
from seatrack.io.ais.output import format_times
from seatrack.io.multitarget import write_unlabelled_plots
from seatrack.io.radar import parse_radar_config

T0 = 1.7e9
TOML = 'lat_deg = 56.0\nlon_deg = 7.0\nmax_range_m = 15000.0\nsigma_range_m = 20.0\n' \
       'sigma_azimuth_deg = 0.3\n[fusion]\ndark_delay_s = 10.0\n'  # fmt: skip


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    d = tmp_path_factory.mktemp("fuse")
    setup = parse_radar_config({"lat_deg": 56.0, "lon_deg": 7.0, "max_range_m": 15000.0})
    cov = Coverage.of(setup.site, land=False)
    start = np.array([[-6000, 0], [6000, 2000], [0, -6000.0]])
    course, speed = np.array([90, 270, 0.0]), np.array([10, 10, 12.0])
    truth = sc.straight_truth(start, course, speed, T0, 300)
    rng = np.random.default_rng(2)
    plots, _ = sc.simulate_plots(truth, np.arange(T0, T0 + 300, 3.0), cov, setup.sensor, 2.0, rng)
    rep, _ = sc.ais_reports(truth, np.full(3, 6.0), (56.0, 7.0), sc.Corruption(dark=(2,)),
                            10.0, rng)  # fmt: skip
    write_unlabelled_plots(d / "plots.csv", plots)
    with (d / "ais.csv").open("w") as fh:
        fh.write("mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg\n")
        for m, t, la, lo, s, c in zip(rep.mmsi, format_times(rep.t), rep.lat, rep.lon,
                                      rep.sog_kn, rep.cog_deg, strict=True):  # fmt: skip
            fh.write(f"{m},{t},{la:.6f},{lo:.6f},{s:.1f},{c:.1f},\n")
    (d / "radar.toml").write_text(TOML)
    return d / "ais.csv", d / "plots.csv", d / "radar.toml"


def test_fuse_returns_the_three_tables(files) -> None:
    ais, plots, toml = files
    out = fuse(ais, plots, toml)
    assert list(out) == list(TABLES)
    r = out["radar_tracks"]
    for col in ("track", "time_s", "lat_deg", "lon_deg", "mmsi", "identity_prob", "class"):
        assert col in r.columns
    assert set(r["class"]) <= {"ais", "dark", "unknown"}
    named = r[r["class"] == "ais"]
    assert set(named["mmsi"]) == {"219000001", "219000002"}
    assert (r[r["class"] == "dark"]["mmsi"] == "").all() and (r["class"] == "dark").sum() > 50
    v = out["ais_vessels"]
    assert {"vessel", "time_s", "covered", "track", "not_seen"} <= set(v.columns)
    assert not v["not_seen"].any()
    a = out["ais_reports"]
    assert {"line", "gap", "jump", "identity_conflict"} <= set(a.columns)
    assert a["line"].min() == 2


def test_command_writes_the_folder(files, tmp_path: Path) -> None:
    ais, plots, toml = files
    res = seatrack("fuse", "--ais", ais, "--plots", plots, "--config", toml, "--out",
                   tmp_path / "pic")  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in (tmp_path / "pic").iterdir()) == sorted(
        f"{t}.csv" for t in TABLES
    )
    assert "dark" in res.stdout


def test_bad_plot_line_is_named(files, tmp_path: Path) -> None:
    ais, plots, toml = files
    bad = tmp_path / "bad.csv"
    lines = plots.read_text().splitlines()
    lines[3] = lines[3].split(",")[0] + ",-5,10"
    bad.write_text("\n".join(lines) + "\n")
    res = seatrack("fuse", "--ais", ais, "--plots", bad, "--config", toml, "--out", tmp_path / "o")
    assert res.returncode == 2
    assert res.stderr.strip() == f"error: {bad}, line 4: range_m must be > 0"
    assert not (tmp_path / "o" / "radar_tracks.csv").exists()


def test_bad_config_key_is_named(files, tmp_path: Path) -> None:
    ais, plots, _ = files
    toml = tmp_path / "radar.toml"
    toml.write_text(TOML + "gate = -3.0\n")
    res = seatrack(
        "fuse", "--ais", ais, "--plots", plots, "--config", toml, "--out", tmp_path / "o"
    )
    assert res.returncode == 2
    assert res.stderr.startswith(f"error: {toml}: fusion: gate") and res.stderr.count("\n") == 1
