"""Tests of seatrack.simulate.files: simulated plots/bearings/truth to CSV and back."""

import numpy as np
import pytest

from seatrack.io.plots import read_plot_tracks
from seatrack.io.table import InputError
from seatrack.io.table import read_csv_table
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory
from seatrack.simulate.files import BEARING_COLUMNS
from seatrack.simulate.files import plots_from_measurements
from seatrack.simulate.files import read_truth
from seatrack.simulate.files import write_bearings
from seatrack.simulate.files import write_clutter
from seatrack.simulate.files import write_plots
from seatrack.simulate.files import write_truth


def _meas(components, sigma, seed=0, p_detect=0.8, start=(3000.0, 4000.0, 200.0), observer=None):
    tr = trajectory(
        list(start), np.radians(300.0), 12.0, [Leg.straight(20), Leg.turn(np.pi / 2, 0.1)], dt=1.0
    )
    m = observe(tr, observer, components, NoiseModel(sigma), np.random.default_rng(seed), p_detect)
    return tr, m


def test_plots_round_trip_2d_with_range_rate(tmp_path):
    own = trajectory([0.0, 0.0], 0.0, 5.0, [Leg.straight(40)], dt=1.0)
    _, m1 = _meas(("azimuth", "range", "range_rate"), (0.01, 10.0, 1.0), seed=1, observer=own)
    _, m2 = _meas(
        ("azimuth", "range", "range_rate"),
        (0.01, 10.0, 1.0),
        seed=2,
        start=(-500.0, 100.0, 0.0),
        observer=own,
    )
    p = tmp_path / "PLOTS.csv"
    n = write_plots(p, [("A", m1), ("B", m2)])
    assert n == m1.detected.sum() + m2.detected.sum()
    tracks = read_plot_tracks(p)
    assert [t.label for t in tracks] == ["A", "B"]
    for t, m in zip(tracks, (m1, m2), strict=True):
        ref = plots_from_measurements(m, t.label)
        assert len(t) == m.detected.sum() < m.t.size  # missed scans left out
        np.testing.assert_array_equal(t.t, ref.t)
        np.testing.assert_array_equal(t.range, ref.range)
        np.testing.assert_allclose(t.azimuth, ref.azimuth, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(t.range_rate, ref.range_rate)
        np.testing.assert_array_equal(t.sensor, ref.sensor)
        assert t.elevation is None


def test_plots_round_trip_3d(tmp_path):
    _, m = _meas(("range", "azimuth", "elevation"), (10.0, 0.01, 0.01), p_detect=1.0)
    p = tmp_path / "PLOTS.csv"
    write_plots(p, [("7", m)])
    (t,) = read_plot_tracks(p)
    ref = plots_from_measurements(m, "7")
    assert t.label == "7" and t.is_3d and t.range_rate is None
    np.testing.assert_allclose(t.elevation, ref.elevation, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(t.range, ref.range)


def test_plots_from_measurements_keeps_scan_indices():
    _, m = _meas(("azimuth", "range"), (0.01, 10.0), p_detect=0.7)
    pt = plots_from_measurements(m, "x")
    np.testing.assert_array_equal(pt.line, np.flatnonzero(m.detected))
    np.testing.assert_array_equal(pt.range, m.z[m.detected, 1])
    np.testing.assert_array_equal(pt.sensor_vel, m.sensor_vel[m.detected])
    _, mb = _meas(("azimuth",), (0.01,))
    with pytest.raises(ValueError, match="range and azimuth"):
        plots_from_measurements(mb)


def test_bearings_file(tmp_path):
    own = trajectory([0.0, 0.0], np.radians(140), 2.5, [Leg.straight(30)], dt=1.0)
    _, m = _meas(("azimuth",), (np.radians(1.5),), observer=own, p_detect=0.9)
    p = tmp_path / "BEARINGS.csv"
    n = write_bearings(p, [("C1", m)], 1.5)
    tab = read_csv_table(p, BEARING_COLUMNS[1:], ("contact",), text=("contact",))
    assert n == len(tab) == m.detected.sum()
    assert list(tab["contact"]) == ["C1"] * n
    np.testing.assert_allclose(np.radians(tab["bearing_deg"]), m.z[m.detected, 0], atol=1e-14)
    np.testing.assert_array_equal(tab["observer_x_m"], m.sensor_pos[m.detected, 0])
    np.testing.assert_array_equal(tab["observer_y_m"], m.sensor_pos[m.detected, 1])
    assert np.all(tab["sigma_deg"] == 1.5)
    assert np.all((tab["bearing_deg"] >= 0) & (tab["bearing_deg"] < 360))


def test_truth_round_trip(tmp_path):
    tr, _ = _meas(("azimuth",), (0.01,))
    p = tmp_path / "truth.csv"
    write_truth(p, [("T1", tr), ("T2", tr)])
    back = read_truth(p)
    assert list(back) == ["T1", "T2"]
    b = back["T1"]
    np.testing.assert_array_equal(b.pos, tr.pos)
    np.testing.assert_array_equal(b.vel, tr.vel)
    np.testing.assert_allclose(b.course, tr.course, atol=1e-15)
    np.testing.assert_allclose(b.turn_rate, tr.turn_rate, atol=1e-15)
    q = tmp_path / "own.csv"
    write_truth(q, tr)
    header = q.read_text().splitlines()[0]
    assert header.startswith(
        "time_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,course_deg,speed_mps,turn_rate_dps"
    )
    assert list(read_truth(q)) == [""]


def test_truth_reader_names_file_and_line(tmp_path):
    tr, _ = _meas(("azimuth",), (0.01,))
    p = tmp_path / "truth.csv"
    write_truth(p, [("T1", tr)])
    lines = p.read_text().splitlines()
    lines[4] = lines[4].replace(lines[4].split(",")[2], "abc", 1)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as exc:
        read_truth(p)
    assert str(p) in str(exc.value) and "line 5" in str(exc.value)


def test_clutter_file(tmp_path):
    p = tmp_path / "clutter.csv"
    t = np.array([0.0, 0.0, 2.0])
    n = write_clutter(
        p, t, np.array([100.0, 200.0, 300.0]), np.array([0.1, 6.2, 3.0]), np.zeros((3, 3))
    )
    tab = read_csv_table(p, ("time_s", "range_m", "azimuth_deg", "sensor_x_m"))
    assert n == 3 and len(tab) == 3
    np.testing.assert_allclose(np.radians(tab["azimuth_deg"]), [0.1, 6.2, 3.0])


def test_bearings_file_is_read_by_the_tma_reader(tmp_path):
    from seatrack.io.tma import read_bearings

    own = trajectory([0.0, 0.0], np.radians(140), 2.5, [Leg.straight(30)], dt=1.0)
    _, m = _meas(("azimuth",), (np.radians(1.5),), observer=own, p_detect=0.9)
    p = tmp_path / "BEARINGS.csv"
    write_bearings(p, [("C1", m)], 1.5)
    b = read_bearings(p)["C1"]
    np.testing.assert_array_equal(b.t, m.t[m.detected])
    np.testing.assert_allclose(b.bearing, m.z[m.detected, 0], atol=1e-14)
    np.testing.assert_array_equal(b.observer, m.sensor_pos[m.detected, :2])
    np.testing.assert_allclose(b.sigma, np.radians(1.5))


@pytest.mark.parametrize(
    ("column", "value", "message"),
    [
        ("x_m", "1e300", "x_m = 1e300 must be in [-1e+08, 1e+08]"),
        ("course_deg", "360", "course_deg = 360 must be in [0, 360)"),
        ("speed_mps", "-1", "speed_mps = -1 must be in [0, 10000]"),
        ("time_s", "1e308", "time_s = 1e308 must be in"),
    ],
)
def test_truth_values_are_checked(tmp_path, column, value, message):
    tr, _ = _meas(("azimuth",), (0.01,))
    p = tmp_path / "truth.csv"
    write_truth(p, tr)
    lines = [ln.split(",") for ln in p.read_text().splitlines()]
    lines[3][lines[0].index(column)] = value
    p.write_text("\n".join(",".join(c) for c in lines) + "\n")
    with pytest.raises(InputError) as exc:
        read_truth(p)
    assert str(exc.value) == f"{p}, line 4: {message}" or message in str(exc.value)
    assert f"{p}, line 4: " in str(exc.value)


def test_writers_are_atomic(tmp_path):
    """A failure part-way through a file keeps the previous file and leaves no temporary."""
    _, good = _meas(("azimuth", "range"), (0.01, 10.0))
    _, no_bearing = _meas(("range",), (10.0,))
    p = tmp_path / "bearings.csv"
    p.write_text("previous\n")
    with pytest.raises(ValueError, match="contact b: measurements have no bearing"):
        write_bearings(p, [("a", good), ("b", no_bearing)], 1.0)  # rows of "a" were written
    assert p.read_text() == "previous\n"
    assert [x.name for x in tmp_path.iterdir()] == ["bearings.csv"]
