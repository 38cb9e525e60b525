import csv
import subprocess
import sys

import numpy as np

from seatrack.simulate import Leg, NoiseModel, observe, trajectory


def _seatrack(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "seatrack.cli", *args], capture_output=True, text=True, cwd=cwd
    )


def _write_plots(path):
    tr = trajectory(
        [5000, 8000, 1000],
        np.radians(100),
        150,
        [Leg.straight(60), Leg.turn(np.pi / 2, np.radians(3))],
        dt=2.0,
    )
    m = observe(
        tr,
        None,
        ["range", "azimuth", "elevation", "range_rate"],
        NoiseModel([20, np.radians(0.3), np.radians(0.3), 1.0]),
        np.random.default_rng(0),
    )
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["track", "time_s", "range_m", "azimuth_deg", "elevation_deg", "range_rate_mps"])
        for tid in ("a", "b"):
            for i in range(len(m.t)):
                w.writerow(
                    [
                        tid,
                        m.t[i],
                        m.z[i, 0],
                        np.degrees(m.z[i, 1]),
                        np.degrees(m.z[i, 2]),
                        m.z[i, 3],
                    ]
                )
    return 2 * len(m.t)


def test_track_ekf_writes_one_row_per_plot(tmp_path):
    n = _write_plots(tmp_path / "plots.csv")
    cfg = tmp_path / "cfg.toml"
    cfg.write_text("q = 5.0\nsigma_range_m = 20.0\nsigma_azimuth_deg = 0.3\n")
    r = _seatrack(
        "track",
        "plots.csv",
        "--method",
        "ekf",
        "--config",
        "cfg.toml",
        "--out",
        "track.csv",
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    rows = list(csv.DictReader(open(tmp_path / "track.csv")))
    assert len(rows) == n
    assert {"track", "time_s", "x_m", "std_z_m", "nis"} <= set(rows[0])
    assert {row["track"] for row in rows} == {"a", "b"}


def test_track_errors_are_one_line_without_traceback(tmp_path):
    (tmp_path / "bad.csv").write_text("time_s,range_m,azimuth_deg\n0,100,10\n1,nan,10\n")
    r = _seatrack("track", "bad.csv", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 2
    assert "bad.csv, line 3" in r.stderr and "Traceback" not in r.stderr
    _write_plots(tmp_path / "plots.csv")
    r = _seatrack("track", "plots.csv", "--method", "nope", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 2 and "unknown method 'nope'" in r.stderr and "Traceback" not in r.stderr
    (tmp_path / "c.toml").write_text("q = = 1\n")
    r = _seatrack("track", "plots.csv", "--config", "c.toml", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 2 and "c.toml: not valid TOML" in r.stderr
