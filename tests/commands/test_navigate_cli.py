"""`seatrack navigate` and `seatrack survey` on simulated files; clean errors naming the row."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from seatrack.cli import main
from seatrack.geometry import wrap_pi
from seatrack.io.landmarks import read_map_csv
from seatrack.io.landmarks import write_map_csv
from seatrack.io.navigation import NAV_COLUMNS
from seatrack.io.navigation import write_echoes
from seatrack.io.navigation import write_gyro
from seatrack.io.table import read_csv_table
from seatrack.simulate.radar_echoes import channel_landmarks
from seatrack.simulate.radar_echoes import river_route
from seatrack.simulate.radar_echoes import simulate_radar

ROUTE = river_route(2000.0, 4.0)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("nav")
    lms = channel_landmarks(ROUTE, 8, np.random.default_rng(1))
    sim = simulate_radar(ROUTE, lms, np.random.default_rng(2))
    e = sim.echoes
    write_echoes(d / "echoes.csv", e.t, e.antenna, e.range, e.amplitude)
    write_gyro(d / "gyro.csv", sim.gyro_t, sim.gyro_rate)
    write_map_csv(sim.nav_map, d / "map.csv")
    x0 = sim.truth[0]
    start = f"{x0[0]:.1f},{x0[1]:.1f},{np.degrees(x0[2]):.2f},{np.hypot(x0[3], x0[4]):.2f}"
    return d, sim, start


def _main(monkeypatch, capsys, *args):
    monkeypatch.setattr(sys, "argv", ["seatrack", *map(str, args)])
    code = 0
    try:
        main()
    except SystemExit as exc:
        code = int(exc.code or 0)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def test_navigate_writes_nav_csv(files, monkeypatch, capsys):
    d, sim, start = files
    out = d / "nav.csv"
    code, text, err = _main(monkeypatch, capsys, "navigate", "--map", d / "map.csv", "--echoes",
                            d / "echoes.csv", "--gyro", d / "gyro.csv", "--start", start,
                            "--out", out)  # fmt: skip
    assert code == 0, err
    assert "landmark updates" in text
    t = read_csv_table(out, required=list(NAV_COLUMNS))
    tt = t["time_s"]
    assert np.allclose(np.diff(tt), 2.5 / 16, atol=2e-3)
    x = np.interp(tt, sim.truth_t, sim.truth[:, 0])
    y = np.interp(tt, sim.truth_t, sim.truth[:, 1])
    h = np.interp(tt, sim.truth_t, sim.truth[:, 2])
    late = tt > 60
    pe = np.hypot(t["x_m"] - x, t["y_m"] - y)[late]
    assert np.sqrt(np.mean(pe**2)) < 6.0
    he = np.degrees(wrap_pi(np.radians(t["heading_deg"]) - h))[late]
    assert np.sqrt(np.mean(he**2)) < 0.5
    assert np.all((t["heading_deg"] >= 0) & (t["heading_deg"] < 360))


def test_survey_writes_a_corrected_map(files, monkeypatch, capsys):
    d, sim, start = files
    out = d / "map2.csv"
    code, text, err = _main(monkeypatch, capsys, "survey", "--map", d / "map.csv", "--echoes",
                            d / "echoes.csv", "--gyro", d / "gyro.csv", "--start", start,
                            "--out", out)  # fmt: skip
    assert code == 0, err
    m = read_map_csv(out)
    assert len(m) == 8 and "corrected map" in text
    assert m.ids.tolist() == sim.nav_map.ids.tolist()


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (
            "time_s,antenna_deg,range_m\n0.0,10.0,500\n0.1,11.0,x\n",
            "echoes.csv, line 3: column range_m",
        ),
        (
            "time_s,antenna_deg,range_m\n0.0,10.0,500\n0.1,11.0,-5\n",
            "echoes.csv, line 3: range_m = -5",
        ),
        (
            "time_s,antenna_deg,range_m\n1.0,10.0,500\n0.5,11.0,600\n",
            "echoes.csv, line 3: time_s = 0.5",
        ),
        ("time_s,range_m\n0.0,500\n", "missing required column(s) antenna_deg"),
        (
            "time_s,antenna_deg,range_m\n0.0,0.0,500\n0.5,72.0,500\n1.0,300.0,500\n",
            "echoes.csv, line 4: antenna angle deviates",
        ),
    ],
)
def test_bad_echo_file_names_the_row(files, monkeypatch, capsys, content, message):
    d, _, start = files
    bad = d / "bad" / "echoes.csv"
    bad.parent.mkdir(exist_ok=True)
    bad.write_text(content)
    code, _, err = _main(monkeypatch, capsys, "navigate", "--map", d / "map.csv", "--echoes", bad,
                         "--start", start, "--out", d / "x.csv")  # fmt: skip
    assert code == 2
    assert message in err and "Traceback" not in err


def test_bad_gyro_map_and_start(files, monkeypatch, capsys):
    d, _, start = files
    g = d / "gyro_bad.csv"
    g.write_text("time_s,turn_rate_dps\n0,0.1\n0,0.2\n")
    args = ["--echoes", d / "echoes.csv", "--gyro", g, "--start", start, "--out", d / "x.csv"]
    code, _, err = _main(monkeypatch, capsys, "navigate", "--map", d / "map.csv", *args)
    assert code == 2 and "gyro_bad.csv, line 3: duplicate time_s" in err
    m = d / "map_bad.csv"
    m.write_text("id,kind,x_m,y_m,orientation_deg\nA,point,0,0,\nB,contour,5,5,\n")
    code, _, err = _main(monkeypatch, capsys, "navigate", "--map", m, "--echoes",
                         d / "echoes.csv", "--start", start, "--out", d / "x.csv")  # fmt: skip
    assert code == 2 and "map_bad.csv, line 3: contour element needs orientation_deg" in err
    code, _, err = _main(monkeypatch, capsys, "navigate", "--map", d / "map.csv", "--echoes",
                         d / "echoes.csv", "--start", "1,2,3", "--out", d / "x.csv")  # fmt: skip
    assert code == 2 and "--start must be" in err
