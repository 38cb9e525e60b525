import numpy as np
import pytest

from seatrack.io.plots import read_plots
from seatrack.io.table import InputError


def test_reads_tracks_converts_units_and_sensor_velocity(tmp_path):
    p = tmp_path / "plots.csv"
    p.write_text(
        "track,time_s,range_m,azimuth_deg,sensor_x_m,sensor_y_m\n"
        "A,0,1000,90,0,0\nA,2,1010,91,10,0\nB,0,500,359.5,0,0\nA,4,1020,92,20,0\n"
    )
    tr = read_plots(p)
    assert [t.track for t in tr] == ["A", "B"]
    a = tr[0]
    assert len(a) == 3 and not a.is_3d and a.range_rate is None
    np.testing.assert_allclose(a.azimuth, np.radians([90, 91, 92]))
    np.testing.assert_allclose(a.sensor_vel[:, 0], 5.0)
    assert a.lines.tolist() == [2, 3, 5]


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
    ],
)
def test_bad_plot_files(tmp_path, body, msg):
    p = tmp_path / "bad.csv"
    p.write_text(body)
    with pytest.raises(InputError, match=msg):
        read_plots(p)
