"""Files of a small simulated radar + AIS scene for the ``fuse`` API and command tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from seatrack.fusion import scenario as sc
from seatrack.fusion.coverage import Coverage
from seatrack.io.ais.output import format_times
from seatrack.io.multitarget import write_unlabelled_plots
from seatrack.io.radar import parse_radar_config

T0 = 1.7e9
TOML = (
    "lat_deg = 56.0\nlon_deg = 7.0\nmax_range_m = 15000.0\nsigma_range_m = 20.0\n"
    "sigma_azimuth_deg = 0.3\n[fusion]\ndark_delay_s = 10.0\n"
)


def write_scene(d: Path) -> tuple[Path, Path, Path]:
    """Three vessels for 300 s (the third dark): ``ais.csv``, ``plots.csv`` (Unix time),
    ``radar.toml`` in ``d``."""
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
