"""Tests of seatrack.simulate.scenarios: TOML loading, validation messages, simulation."""

import math

import numpy as np
import pytest

from seatrack.geometry import G0
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import geodetic_to_enu
from seatrack.io.table import InputError
from seatrack.simulate.scenarios import bundled_scenario
from seatrack.simulate.scenarios import bundled_scenarios
from seatrack.simulate.scenarios import load_scenario
from seatrack.simulate.scenarios import resolve_scenario

BASE = """
name = "t"
duration_s = 100.0
seed = 3
runs = 7

[[targets]]
position_m = [1000.0, 2000.0]
course_deg = 90.0
speed_kn = 10.0

[[sensors]]
type = "radar2d"
sigma = { azimuth_deg = 0.5, range_m = 10.0 }
scan_period_s = 2.0
"""


def _load(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return load_scenario(p), p


def test_bundled_scenarios_load_and_simulate():
    names = bundled_scenarios()
    assert {"demo", "linear_cv", "tma_classic"} <= set(names)
    for n in names:
        sc = load_scenario(bundled_scenario(n))
        sim = sc.simulate(np.random.default_rng(0))
        assert sim.t[-1] == pytest.approx(sc.duration)
        assert len(sim.targets) == len(sc.targets) and len(sim.sensors) == len(sc.sensors)
        for sd in sim.sensors:
            assert len(sd.measurements) == len(sc.targets)
            assert sd.measurements[0].z.shape == (sd.t.size, len(sd.sensor.components))


def test_tma_classic_geometry():
    sc = load_scenario(bundled_scenario("tma_classic"))
    sim = sc.simulate(np.random.default_rng(1))
    sd = sim.sensors[0]
    assert sd.sensor.type == "passive_sonar" and sd.t.size == 32
    np.testing.assert_allclose(np.diff(sd.t), 60.0)
    assert sd.sensor.sigma[0] == pytest.approx(math.radians(1.5))
    own = sd.observer
    # course 140 deg, then 110, 80, 50, 20 at samples 13..16 (1-based), 20 afterwards
    np.testing.assert_allclose(
        np.degrees(own.course[[0, 11, 12, 13, 14, 15, 31]]),
        [140, 140, 110, 80, 50, 20, 20],
        atol=1e-9,
    )
    np.testing.assert_allclose(own.speed, 5 * KNOT_MPS)
    tgt = sd.truth[0]
    np.testing.assert_allclose(tgt.pos[0, :2], [4920.0, 850.0])
    assert np.degrees(tgt.course[0]) == pytest.approx(220.0)
    np.testing.assert_allclose(tgt.speed, 4 * KNOT_MPS)


def test_units_and_legs(tmp_path):
    text = BASE.replace(
        "speed_kn = 10.0",
        """speed_kn = 10.0
legs = [
  { type = "straight", duration_s = 10.0 },
  { type = "turn", turn_rate_dps = 2.0, duration_s = 5.0 },
  { type = "turn", angle_deg = -30.0, turn_rate_dps = 3.0 },
  { type = "turn", angle_deg = 45.0, g = 1.5 },
  { type = "turn", angle_deg = 20.0, duration_s = 4.0 },
  { type = "accelerate", duration_s = 4.0, accel_mps2 = 0.5 },
  { type = "speed_change", to_speed_mps = 3.0, accel_mps2 = 0.25 },
  { type = "climb", duration_s = 6.0, climb_rate_mps = 2.0 },
]""",
    )
    sc, _ = _load(tmp_path, text)
    t = sc.targets[0]
    v0 = 10 * KNOT_MPS
    assert t.speed == pytest.approx(v0) and t.course == pytest.approx(math.pi / 2)
    legs = t.legs
    assert legs[0].duration == 10.0 and legs[0].turn_rate == 0.0
    assert legs[1].turn_rate == pytest.approx(math.radians(2.0)) and legs[1].duration == 5.0
    assert legs[2].turn_rate == pytest.approx(-math.radians(3.0)) and legs[
        2
    ].duration == pytest.approx(10.0)
    assert legs[3].turn_rate == pytest.approx(1.5 * G0 / v0)
    assert legs[4].turn_rate == pytest.approx(math.radians(5.0))
    assert legs[5].accel == 0.5
    v1 = v0 + 2.0  # after the accelerate leg
    assert legs[6].accel == -0.25 and legs[6].duration == pytest.approx((v1 - 3.0) / 0.25)
    assert legs[7].climb_rate == 2.0
    assert sc.seed == 3 and sc.runs == 7 and sc.dt == 2.0
    tr = t.trajectory(np.array([0.0, 10.0]))
    np.testing.assert_allclose(tr.pos[1, :2], [1000.0 + 10 * v0, 2000.0], atol=1e-9)


def test_lat_lon_positions(tmp_path):
    text = BASE.replace(
        "[[targets]]\nposition_m = [1000.0, 2000.0]",
        "origin = { lat_deg = 54.0, lon_deg = 10.0 }\n"
        "[[targets]]\nlat_deg = 54.01\nlon_deg = 10.02",
    )
    sc, _ = _load(tmp_path, text)
    np.testing.assert_allclose(
        sc.targets[0].start, geodetic_to_enu(54.01, 10.02, 0.0, 54.0, 10.0), atol=1e-9
    )
    assert 1000 < sc.targets[0].start[0] < 1400 and 1000 < sc.targets[0].start[1] < 1200


def test_fixed_sensor_3d_clutter_and_reproducibility(tmp_path):
    text = BASE.replace(
        'type = "radar2d"\nsigma = { azimuth_deg = 0.5, range_m = 10.0 }',
        """type = "radar3d"
components = ["range", "azimuth", "elevation", "range_rate"]
sigma = { azimuth_deg = 0.5, range_m = 10.0, elevation_deg = 0.5, range_rate_mps = 1.0 }
epsilon = 0.1
outlier_scale = { range_m = 10.0, azimuth_deg = 25.0 }
p_detect = 0.8
clutter_density = 3.0
clutter_range_m = [100.0, 5000.0]
position_m = [10.0, 20.0, 30.0]""",
    ).replace("[1000.0, 2000.0]", "[1000.0, 2000.0, 500.0]")
    sc, _ = _load(tmp_path, text)
    s = sc.sensors[0]
    assert s.components == ("azimuth", "range", "elevation", "range_rate")
    assert s.outlier_scale == (25.0, 10.0, 1.0, 1.0)
    np.testing.assert_allclose(s.position, [10.0, 20.0, 30.0])
    a = sc.simulate(np.random.default_rng(5))
    b = sc.simulate(np.random.default_rng(5))
    c = sc.simulate(np.random.default_rng(6))
    ma, mb = a.sensors[0].measurements[0], b.sensors[0].measurements[0]
    np.testing.assert_array_equal(ma.z, mb.z)
    np.testing.assert_array_equal(a.sensors[0].clutter_range, b.sensors[0].clutter_range)
    assert not np.array_equal(
        ma.detected, c.sensors[0].measurements[0].detected
    ) or not np.allclose(ma.z[ma.detected], c.sensors[0].measurements[0].z[ma.detected])
    np.testing.assert_allclose(ma.sensor_pos, np.tile([10.0, 20.0, 30.0], (ma.t.size, 1)))
    assert a.sensors[0].observer is None
    sd = a.sensors[0]
    assert sd.clutter_t.size > 0
    assert np.all((sd.clutter_range >= 100) & (sd.clutter_range <= 5000))
    # missed detections happen at about 1 - p_detect
    assert 0.6 < ma.detected.mean() < 0.95


def test_resolve_scenario(tmp_path):
    assert resolve_scenario("demo") == bundled_scenario("demo")
    with pytest.raises(InputError, match="bundled"):
        resolve_scenario("nonexistent_name")
    with pytest.raises(InputError, match="not found"):
        resolve_scenario(tmp_path / "missing.toml")


BAD = [
    # (replacement of BASE text or full text, expected substrings)
    (("duration_s = 100.0\n", ""), ["duration_s", "missing required key"]),
    (("duration_s = 100.0", 'duration_s = "long"'), ["duration_s", "expected a number", "'long'"]),
    (("duration_s = 100.0", "duration_s = -5.0"), ["duration_s", "must be > 0"]),
    (
        (
            "speed_kn = 10.0",
            'speed_kn = 10.0\nlegs = [{ type = "straight", duration_s = 5.0 }, '
            '{ type = "straight", duration_s = -1.0 }]',
        ),
        ["targets[0].legs[1].duration_s", "must be > 0"],
    ),
    (
        (
            "speed_kn = 10.0",
            'speed_kn = 10.0\nlegs = [{ type = "straight", duration_s = 5.0 }, '
            '{ type = "straight", duration_s = 5.0 }, '
            '{ type = "turn", turn_rate_dps = "fast", duration_s = 3.0 }]',
        ),
        ["targets[0].legs[2].turn_rate_dps", "expected a number"],
    ),
    (
        (
            "speed_kn = 10.0",
            'speed_kn = 10.0\nlegs = [{ type = "turn", turn_rate_dps = 1.0, angle_deg = 9.0, '
            "duration_s = 3.0 }]",
        ),
        ["targets[0].legs[0]", "exactly two"],
    ),
    (
        ("speed_kn = 10.0", 'speed_kn = 10.0\nlegs = [{ type = "zigzag", duration_s = 3.0 }]'),
        ["targets[0].legs[0].type", "unknown leg type", "zigzag"],
    ),
    (
        (
            "speed_kn = 10.0",
            "speed_kn = 10.0\n"
            'legs = [{ type = "accelerate", duration_s = 100.0, accel_mps2 = -1.0 }]',
        ),
        ["targets[0].legs[0]", "speed negative"],
    ),
    (
        ('type = "radar2d"', 'type = "lidar"'),
        ["sensors[0].type", "unknown sensor type", "lidar", "passive_sonar"],
    ),
    (
        ("sigma = { azimuth_deg = 0.5, range_m = 10.0 }", "sigma = { azimuth_deg = 0.5 }"),
        ["sensors[0].sigma.range_m", "missing required key"],
    ),
    (
        (
            "sigma = { azimuth_deg = 0.5, range_m = 10.0 }",
            "sigma = { azimuth_deg = 0.5, range_m = -1.0 }",
        ),
        ["sensors[0].sigma.range_m", "must be > 0"],
    ),
    (  # a zero sigma once passed here and divided by zero in `seatrack evaluate`
        (
            "sigma = { azimuth_deg = 0.5, range_m = 10.0 }",
            "sigma = { azimuth_deg = 0.0, range_m = 10.0 }",
        ),
        ["sensors[0].sigma.azimuth_deg", "must be > 0, got 0"],
    ),
    (  # 1e7 s at a 1 s scan period: refused before anything is allocated
        ("duration_s = 100.0", "duration_s = 1e7"),
        ["sensors[0].scan_period_s", "5e+06 scans; at most 1000000"],
    ),
    (
        ("scan_period_s = 2.0", "scan_period_s = 1e-6"),
        ["scan_period_s", "at most 1000000"],
    ),
    (
        ("course_deg = 90.0", "course_deg = 1e30"),
        ["targets[0].course_deg", "implausibly large"],
    ),
    (
        ("position_m = [1000.0, 2000.0]", "position_m = [1e300, 2000.0]"),
        ["targets[0].position_m[0]", "expected a finite number of magnitude"],
    ),
    (
        ("runs = 7", "runs = 7\n[evaluate.ekf]\nq = nan"),
        ["evaluate.ekf.q", "must be finite"],
    ),
    (
        ("runs = 7", "runs = 7\n[evaluate.ekf]\nq = [[1]]"),
        ["evaluate.ekf.q", "expected a number, string or boolean"],
    ),
    (
        ("scan_period_s = 2.0", "scan_period_s = 2.0\np_detect = 1.5"),
        ["sensors[0].p_detect", "<= 1"],
    ),
    (
        ("scan_period_s = 2.0", "scan_period_s = 2.0\nclutter_density = 1.0"),
        ["sensors[0].clutter_range_m", "required"],
    ),
    (
        ("scan_period_s = 2.0", 'scan_period_s = 2.0\ncomponents = ["azimuth", "elevation"]'),
        ["sensors[0].components", "elevation", "radar2d"],
    ),
    (("course_deg = 90.0", "course_deg = 90.0\ncourse = 3"), ["targets[0].course", "unknown key"]),
    (("speed_kn = 10.0", "speed_kn = 10.0\nspeed_mps = 3.0"), ["targets[0].speed_kn", "not both"]),
    (("course_deg = 90.0\n", ""), ["targets[0].course_deg", "missing required key"]),
    (
        ("position_m = [1000.0, 2000.0]", "position_m = [1000.0]"),
        ["targets[0].position_m", "2 or 3"],
    ),
    (
        ("position_m = [1000.0, 2000.0]", "lat_deg = 54.0\nlon_deg = 10.0"),
        ["targets[0].lat_deg", "origin"],
    ),
    (("seed = 3", "seed = 3.5"), ["seed", "expected an integer"]),
    (("runs = 7", "runs = 0"), ["runs", ">= 1"]),
    (("runs = 7", "runs = 7\nevaluate = { ekf = 3 }"), ["evaluate.ekf", "expected a table"]),
    (("[[sensors]]", "[[sensorz]]"), ["sensorz", "unknown key"]),
    (
        (
            "[[targets]]\nposition_m = [1000.0, 2000.0]\ncourse_deg = 90.0\nspeed_kn = 10.0\n",
            "targets = 5\n",
        ),
        ["targets", "expected a non-empty array", "number 5"],
    ),
    (
        ("[[targets]]\nposition_m = [1000.0, 2000.0]\ncourse_deg = 90.0\nspeed_kn = 10.0\n", ""),
        ["targets", "missing required key"],
    ),
]


@pytest.mark.parametrize(("edit", "expected"), BAD)
def test_malformed_scenarios_name_file_key_and_problem(tmp_path, edit, expected):
    old, new = edit
    assert old in BASE
    p = tmp_path / "bad.toml"
    p.write_text(BASE.replace(old, new, 1))
    with pytest.raises(InputError) as exc:
        load_scenario(p)
    msg = str(exc.value)
    assert str(p) in msg
    for s in expected:
        assert s in msg, (s, msg)


def test_toml_syntax_error_has_line_number(tmp_path):
    p = tmp_path / "syntax.toml"
    p.write_text(BASE.replace("seed = 3", "seed = = 3"))
    with pytest.raises(InputError) as exc:
        load_scenario(p)
    msg = str(exc.value)
    line = BASE.splitlines().index("seed = 3") + 1
    assert str(p) in msg and "TOML syntax error" in msg and f"line {line}" in msg


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_scenario(tmp_path / "nope.toml")
    p = tmp_path / "bin.toml"
    p.write_bytes(b"\xff\xfe\x00bad")
    with pytest.raises(InputError, match="UTF-8"):
        load_scenario(p)


def test_example_scenarios_in_repo_load_and_simulate():
    from pathlib import Path

    examples = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.toml"))
    assert examples, "examples/*.toml missing"
    for p in examples:
        sc = load_scenario(p)
        sim = sc.simulate(np.random.default_rng(0))
        assert all(len(sd.measurements) == len(sc.targets) for sd in sim.sensors)
