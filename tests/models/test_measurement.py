import numpy as np
import pytest

from seatrack.models import Bearing
from seatrack.models import Position
from seatrack.models import RangeBearing
from seatrack.models import RangeBearingElevation
from seatrack.models import RangeRate
from seatrack.models import Stacked
from seatrack.models import numerical_jacobian

rng = np.random.default_rng(7)


def _check(model, x, sensor, eps=1e-6):
    J = model.jacobian(x, sensor)
    Jn = numerical_jacobian(lambda s: model.h(s, sensor), x, angular=model.angular, eps=eps)
    np.testing.assert_allclose(J, Jn, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_bearing_jacobian(seed):
    r = np.random.default_rng(seed)
    x = np.concatenate([r.uniform(-5000, 5000, 2), r.uniform(-10, 10, 2)])
    _check(Bearing(n=4), x, r.uniform(-100, 100, 2))


@pytest.mark.parametrize("seed", range(5))
def test_range_bearing_jacobian(seed):
    r = np.random.default_rng(seed)
    x = np.concatenate([r.uniform(-5000, 5000, 2), r.uniform(-10, 10, 2), [0.01]])
    _check(RangeBearing(n=5), x, r.uniform(-100, 100, 2))


@pytest.mark.parametrize("seed", range(5))
def test_range_bearing_elevation_jacobian(seed):
    r = np.random.default_rng(seed)
    x = np.concatenate([r.uniform(-5000, 5000, 3), r.uniform(-100, 100, 3)])
    _check(RangeBearingElevation(), x, r.uniform(-100, 100, 3))


@pytest.mark.parametrize("seed", range(5))
def test_range_rate_jacobian_moving_sensor(seed):
    r = np.random.default_rng(seed)
    x = np.concatenate([r.uniform(-5000, 5000, 3), r.uniform(-100, 100, 3)])
    sensor = np.concatenate([r.uniform(-100, 100, 3), r.uniform(-10, 10, 3)])
    _check(RangeRate(), x, sensor)


def test_stacked_and_bearing_near_north_wraps():
    m = Stacked([RangeBearingElevation(), RangeRate()])
    x = np.array([-1e-3, 3000.0, 100.0, 5.0, -3.0, 0.0])  # just west of North: bearing ~ 2 pi
    z = m.h(x)
    assert z.shape == (4,) and z[1] > 6.28
    # absolute step 1e-3 m on the tiny x coordinate keeps round-off of the 3 km range below 1e-9
    _check(m, x, None, eps=1e-3)
    assert m.angular.tolist() == [False, True, True, False]


def test_values_and_conventions():
    x = np.array([1000.0, 0.0, 0.0, 10.0])
    z = RangeBearing().h(x)
    np.testing.assert_allclose(z, [1000.0, np.pi / 2])
    # target moving north while due east: range rate zero; moving east: +10 (opening)
    assert abs(RangeRate(n=4, pos=(0, 1), vel=(2, 3)).h(x)[0]) < 1e-12
    assert RangeRate(n=4, pos=(0, 1), vel=(2, 3)).h(np.array([1000.0, 0, 10, 0]))[
        0
    ] == pytest.approx(10)
    e = RangeBearingElevation().h(np.array([0.0, 1000.0, 1000.0, 0, 0, 0]))
    np.testing.assert_allclose(e, [np.sqrt(2) * 1000, 0.0, np.pi / 4])


def test_batch_shapes():
    X = rng.normal(size=(7, 3, 6)) * 1000
    m = RangeBearingElevation()
    assert m.h(X).shape == (7, 3, 3)
    assert m.jacobian(X).shape == (7, 3, 3, 6)
    J = m.jacobian(X)
    np.testing.assert_allclose(J[2, 1], m.jacobian(X[2, 1]))
    assert Position(n=4).jacobian(X[..., :4]).shape == (7, 3, 2, 4)


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("rr", [False, True])
def test_compiled_polar_measurement_equals_the_model_objects(d, rr):
    from seatrack.models.measurement import polar_measurement

    rng = np.random.default_rng(d + 2 * rr)
    x = np.concatenate([rng.normal(0, 3000, (9, d)), rng.normal(0, 20, (9, d))], -1)
    s = np.concatenate([rng.normal(0, 100, (9, d)), rng.normal(0, 5, (9, d))], -1)
    base = RangeBearing(n=2 * d) if d == 2 else RangeBearingElevation(n=2 * d)
    pos, vel = tuple(range(d)), tuple(range(d, 2 * d))
    m = Stacked([base, RangeRate(n=2 * d, pos=pos, vel=vel)]) if rr else base
    hx, H = polar_measurement(x, s, d, rr)
    np.testing.assert_allclose(hx, m.h(x, s), rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(H, m.jacobian(x, s), rtol=1e-12, atol=1e-15)


def test_in_layout_reads_the_same_components_of_a_padded_state():
    """A CV model's measurement on the CV + CT layout ``[x, y, vx, vy, w]``: same ``h``,
    Jacobian zero on the padding, equal for every model of a prefix layout."""
    from seatrack.models.measurement import in_layout

    m4 = Stacked([RangeBearing(n=4), RangeRate(n=4, pos=(0, 1), vel=(2, 3))])
    m5 = Stacked([RangeBearing(n=5), RangeRate(n=5, pos=(0, 1), vel=(2, 3))])
    u4, u5 = in_layout(m4, 5), in_layout(m5, 5)
    assert u4 == u5
    x5 = np.array([3000.0, -2000.0, 12.0, -7.0, 0.03])
    sensor = np.array([100.0, 50.0, 1.0, 2.0])
    np.testing.assert_array_equal(u4.h(x5, sensor), m4.h(x5[:4], sensor))
    H = u4.jacobian(x5, sensor)
    np.testing.assert_array_equal(H[:, :4], m4.jacobian(x5[:4], sensor))
    np.testing.assert_array_equal(H[:, 4], 0.0)
    assert in_layout(object(), 5) is None
    with pytest.raises(ValueError, match="cannot read"):
        in_layout(Position(n=6, pos=(0, 1, 2)), 4)


@pytest.mark.parametrize("d", [2, 3])
def test_sensor_frame_is_the_position_along_and_across_the_measured_direction(d):
    """The near-sensor frame of a plot (azimuth ``az``, elevation ``el``): the range,
    azimuth [and elevation] rows become the position along ``u``, across ``v`` (horizontal)
    [and ``w``] -- an orthonormal frame, linear (Jacobian checked numerically); the plot's
    own point is ``[range, 0, (0)]``; the range-rate row stays the polar one."""
    from seatrack.models.measurement import polar_measurement
    from seatrack.models.measurement import sensor_frame_core

    rng = np.random.default_rng(5 + d)
    x = np.concatenate([rng.normal(0, 40, (6, d)), rng.normal(0, 10, (6, d))], -1)
    s = np.concatenate([rng.normal(0, 5, (6, d)), rng.normal(0, 2, (6, d))], -1)
    for az, el in ((0.0, 0.0), (0.3, 0.2), (2.0, -0.4), (4.5, 1.3)):
        el = el if d == 3 else 0.0

        def h(state, k, az=az, el=el):
            hx, H = polar_measurement(state[None], s[k : k + 1], d, True)
            sensor_frame_core(state[None], s[k : k + 1], d, az, el, hx, H)
            return hx[0]

        hx, H = polar_measurement(x, s, d, True)
        polar = hx.copy()
        sensor_frame_core(x, s, d, az, el, hx, H)
        u = np.array([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])
        v = np.array([np.cos(az), -np.sin(az), 0.0])
        w = np.array([-np.sin(el) * np.sin(az), -np.sin(el) * np.cos(az), np.cos(el)])
        frame = np.array([u, v, w])[:d, :d]
        np.testing.assert_allclose(frame @ frame.T, np.eye(d), atol=1e-15)
        rel = x[:, :d] - s[:, :d]
        np.testing.assert_allclose(hx[:, :d], rel @ frame.T, rtol=1e-13, atol=1e-12)
        assert np.array_equal(hx[:, d], polar[:, d])
        for k in range(6):
            J = numerical_jacobian(lambda state, k=k: h(state, k), x[k])
            np.testing.assert_allclose(H[k], J, rtol=1e-6, atol=1e-8)
            assert np.array_equal(H[k, :d, :d], frame) and not H[k, :d, d:].any()
        on_plot = np.concatenate([s[0, :d] + 37.0 * u[:d], np.ones(d)])[None]
        hp, Hp = polar_measurement(on_plot, s[:1], d, True)
        sensor_frame_core(on_plot, s[:1], d, az, el, hp, Hp)
        np.testing.assert_allclose(hp[0, :d], [37.0] + [0.0] * (d - 1), atol=1e-12)


def test_near_sensor_compares_ranges_with_the_position_spread():
    from seatrack.models.measurement import NEAR_SENSOR_SIGMAS
    from seatrack.models.measurement import near_sensor

    x = np.array([[30.0, 40.0, 0, 0], [3e3, 4e3, 0, 0], [3e3, 4e3, 0, 0], [np.nan, 0, 0, 0]])
    P = np.stack([np.diag([50.0**2, 50.0**2, 1, 1])] * 3 + [np.eye(4)])
    sensor = np.zeros((4, 4))
    plot_range = np.array([50.0, 5e3, 40.0, 50.0])
    got = near_sensor(x, P, plot_range, sensor, 2, 20.0**2)
    # 50 m < 5 x 70.7 m; 5 km is not; a plot at 40 m is, whatever the prediction; NaN is not
    assert got.tolist() == [True, False, True, False]
    # the range std sets the floor when the prediction is sharp
    sharp = np.stack([np.eye(4) * 1e-6] * 4)
    limit = NEAR_SENSOR_SIGMAS * 20.0
    ranges = np.array([limit - 1, limit + 1, 1e3, 1e3])
    got = near_sensor(np.zeros((4, 4)) + [1e4, 0, 0, 0], sharp, ranges, sensor, 2, 20.0**2)
    assert got.tolist() == [True, False, False, False]


def test_range_rate_is_nan_at_zero_range_without_a_warning():
    import warnings

    from seatrack.models.measurement import range_rate

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rr = range_rate(np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]]), np.array([[1.0, 0, 0]] * 2))
    assert np.isnan(rr[0]) and rr[1] == pytest.approx(0.6)
