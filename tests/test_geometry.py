import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from seatrack import geometry as g

finite = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False)
angles = st.floats(-50.0, 50.0, allow_nan=False)


@given(angles)
def test_wrap_pi_range_and_equivalence(a):
    w = g.wrap_pi(a)
    assert -math.pi < w <= math.pi
    assert math.isclose(math.cos(w), math.cos(a), abs_tol=1e-9)
    assert math.isclose(math.sin(w), math.sin(a), abs_tol=1e-9)


@given(angles)
def test_wrap_2pi_range_and_equivalence(a):
    w = g.wrap_2pi(a)
    assert 0.0 <= w < 2 * math.pi
    assert math.isclose(math.cos(w), math.cos(a), abs_tol=1e-9)


def test_wrap_edges():
    assert g.wrap_pi(math.pi) == math.pi
    assert g.wrap_pi(-math.pi) == math.pi
    assert g.wrap_2pi(2 * math.pi) == 0.0
    assert g.wrap_2pi(-1e-18) == 0.0 or g.wrap_2pi(-1e-18) < 2 * math.pi
    np.testing.assert_allclose(g.wrap_pi(np.array([3 * math.pi, -3 * math.pi])), [math.pi, math.pi])


@given(st.floats(0, 359.999), st.floats(0, 359.999))
def test_angle_diff_across_north(a_deg, b_deg):
    d = g.angle_diff(math.radians(a_deg), math.radians(b_deg))
    expected = (a_deg - b_deg + 180.0) % 360.0 - 180.0
    if expected == -180.0:
        expected = 180.0
    assert math.isclose(math.degrees(d), expected, abs_tol=1e-7)


def test_angle_diff_wraps_at_0_360():
    assert math.isclose(math.degrees(g.angle_diff(math.radians(1), math.radians(359))), 2.0)
    assert math.isclose(math.degrees(g.angle_diff(math.radians(359), math.radians(1))), -2.0)


def test_bearing_convention_clockwise_from_north():
    assert g.bearing(0.0, 1.0) == 0.0
    assert math.isclose(g.bearing(1.0, 0.0), math.pi / 2)
    assert math.isclose(g.bearing(0.0, -1.0), math.pi)
    assert math.isclose(g.bearing(-1.0, 0.0), 3 * math.pi / 2)


@given(finite, finite)
def test_polar_round_trip_2d(x, y):
    if math.hypot(x, y) < 1e-6:
        return
    r, a = g.cart_to_polar(np.array([x, y]))
    assert 0 <= a < 2 * math.pi
    np.testing.assert_allclose(g.polar_to_cart(r, a), [x, y], atol=1e-8 * max(1.0, abs(r)))


@given(finite, finite, finite)
def test_spherical_round_trip_3d(x, y, z):
    if math.hypot(x, y) < 1e-6:
        return
    r, a, e = g.cart_to_spherical(np.array([x, y, z]))
    assert -math.pi / 2 <= e <= math.pi / 2
    np.testing.assert_allclose(g.spherical_to_cart(r, a, e), [x, y, z], atol=1e-8 * max(1.0, r))


@given(st.floats(0, 2 * math.pi), st.floats(0, 30))
def test_course_speed_round_trip(c, s):
    v = g.velocity_from_course(c, s)
    c2, s2 = g.course_speed(v[0], v[1])
    assert math.isclose(s2, s, abs_tol=1e-9)
    if s > 1e-6:
        assert abs(g.angle_diff(c2, c)) < 1e-9


@given(st.floats(0, 2 * math.pi))
def test_beam_rotation_orthogonal_and_points_along_beam(psi):
    R = g.rotation_to_beam(psi)
    np.testing.assert_allclose(R @ R.T, np.eye(2), atol=1e-12)
    target = 1000.0 * np.array([math.sin(psi), math.cos(psi)])
    np.testing.assert_allclose(R @ target, [1000.0, 0.0], atol=1e-9)
    right = np.array([math.sin(psi + math.pi / 2), math.cos(psi + math.pi / 2)])
    np.testing.assert_allclose(R @ right, [0.0, 1.0], atol=1e-12)


@given(st.floats(-80, 80), st.floats(-179, 179), st.floats(-0.05, 0.05), st.floats(-0.05, 0.05))
def test_enu_geodetic_round_trip(lat0, lon0, dlat, dlon):
    lat, lon = lat0 + dlat, lon0 + dlon
    enu = g.geodetic_to_enu(lat, lon, 10.0, lat0, lon0, 0.0)
    la, lo, h = g.enu_to_geodetic(enu, lat0, lon0, 0.0)
    assert abs(la - lat) < 1e-9 and abs(lo - lon) < 1e-9 and abs(h - 10.0) < 1e-4


def test_enu_against_known_distances():
    # one minute of latitude at 57 N is ~1855.5 m on WGS84 (meridian arc), east-west zero
    enu = g.geodetic_to_enu(57.0 + 1 / 60, 11.0, 0.0, 57.0, 11.0)
    assert abs(enu[0]) < 1e-6
    assert 1853.0 < enu[1] < 1858.0
    assert enu[2] < 0  # the tangent plane rises above the ellipsoid


def test_units():
    assert math.isclose(g.knots_to_mps(1.0), 1852 / 3600)
    assert math.isclose(g.mps_to_knots(g.knots_to_mps(7.5)), 7.5)
    assert g.bearing_rad_to_deg(-math.radians(10)) == pytest.approx(350.0)
    assert g.bearing_rad_to_deg(2 * math.pi) == 0.0
    assert math.isclose(g.bearing_deg_to_rad(370.0), math.radians(10))


def test_enu_per_point_origins_equal_one_call_per_origin():
    """Arrays of origins (one per point) give exactly the per-origin results, both ways."""
    rng = np.random.default_rng(3)
    lat0 = rng.uniform(-70, 70, 50)
    lon0 = rng.uniform(-180, 180, 50)
    lat = lat0 + rng.uniform(-0.5, 0.5, 50)
    lon = lon0 + rng.uniform(-0.5, 0.5, 50)
    h = rng.uniform(-50, 50, 50)
    enu = g.geodetic_to_enu(lat, lon, h, lat0, lon0)
    one = np.array(
        [g.geodetic_to_enu(a, b, c, d, e) for a, b, c, d, e in zip(lat, lon, h, lat0, lon0)]
    )
    assert enu.shape == (50, 3)
    assert np.allclose(enu, one, atol=1e-6)
    la, lo, hh = g.enu_to_geodetic(enu, lat0, lon0)
    assert np.allclose(la, lat, atol=1e-10) and np.allclose(lo, lon, atol=1e-10)
    assert np.allclose(hh, h, atol=1e-6)
