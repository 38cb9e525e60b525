import numpy as np
import pytest

from seatrack.io.plots import read_plot_tracks
from seatrack.io.plots import read_plots
from seatrack.io.table import InputError


def test_reads_tracks_converts_units_and_sensor_velocity(tmp_path):
    p = tmp_path / "plots.csv"
    p.write_text(
        "track,time_s,range_m,azimuth_deg,sensor_x_m,sensor_y_m\n"
        "A,0,1000,90,0,0\nA,2,1010,91,10,0\nB,0,500,359.5,0,0\nA,4,1020,92,20,0\n"
    )
    tr = read_plot_tracks(p)
    assert [t.label for t in tr] == ["A", "B"]
    a = tr[0]
    assert len(a) == 3 and not a.is_3d and a.range_rate is None
    np.testing.assert_allclose(a.azimuth, np.radians([90, 91, 92]))
    np.testing.assert_allclose(a.sensor_vel[:, 0], 5.0)
    np.testing.assert_allclose(tr[1].sensor_vel, 0.0)  # one plot: no velocity
    assert a.line.tolist() == [2, 3, 5]
    allp = read_plots(p)  # all plots in file order, each with its label
    assert allp.track.tolist() == ["A", "A", "B", "A"]


@pytest.mark.parametrize(
    "body,msg",
    [
        ("time_s,range_m,azimuth_deg\n0,100,360\n", "line 2: azimuth_deg must be in \\[0, 360\\)"),
        ("time_s,range_m,azimuth_deg\n0,-1,10\n", "line 2: range_m must be > 0"),
        ("time_s,range_m,azimuth_deg\n1,100,10\n0,100,10\n", "line 3: time_s = 0 is earlier"),
        ("time_s,range_m,azimuth_deg\n1,100,10\n1,100,10\n", "line 3: duplicate time_s"),
        ("time_s,range_m\n1,100\n", "missing required column.*azimuth_deg"),
        ("time_s,range_m,azimuth_deg,elevation_deg\n0,100,10,95\n", "elevation_deg must be in"),
        (
            "time_s,range_m,azimuth_deg,range_rate_mps\n0,100,10,1\n1,100,10,\n",
            "line 3: column range_rate_mps is empty here",
        ),
        ("track,time_s,range_m,azimuth_deg\nA,0,100,10\n,1,100,10\n", "line 3: empty track id"),
        ("time_s,range_m,azimuth_deg\n0,100,10\n1,1e308,10\n", "line 3: range_m = 1e.308 is impl"),
        ("time_s,range_m,azimuth_deg\n0,100,10\n1e15,100,10\n", "line 3: time_s = 1e.15 is impl"),
        ("time_s,range_m,azimuth_deg\n0,100,10\n2e6,100,10\n", "line 3: time gap of 2e.06 s"),
        # the shared limit of every reader: the Unix time of 2100-01-01 (4.1024e9 s)
        ("time_s,range_m,azimuth_deg\n4.15e9,100,10\n", "line 2: time_s = 4.15e.09 is impl"),
        (
            "time_s,range_m,azimuth_deg,range_rate_mps\n0,100,10,1\n1,100,10,1e9\n",
            "line 3: range_rate_mps = 1e.09 is implausible",
        ),
    ],
)
def test_bad_plot_files(tmp_path, body, msg):
    p = tmp_path / "bad.csv"
    p.write_text(body)
    with pytest.raises(InputError, match=msg):
        read_plots(p)


def test_track_ids_are_stored_once_each_not_as_wide_as_the_longest(tmp_path):
    from seatrack.io.plots import read_plots

    long_id = "L" * 100
    rows = ["track,time_s,range_m,azimuth_deg"]
    for k in range(50):
        rows += [f"a,{k},{1000 + k},10", f"{long_id},{k},{2000 + k},20"]
    p = tmp_path / "p.csv"
    p.write_text("\n".join(rows) + "\n")
    labels = read_plots(p).track
    assert labels.dtype == object  # 8 bytes per row, not 400 (a <U100 array)
    assert labels.tolist() == ["a", long_id] * 50
    assert len({id(s) for s in labels}) == 2  # one str object per distinct id
