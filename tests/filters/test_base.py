"""The filter contract: batch containers, initiation, isolation, the batched track driver."""

import numpy as np
import pytest

from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import common_columns
from seatrack.filters.base import finish_update
from seatrack.filters.base import plot_gaussian
from seatrack.filters.base import two_point_gaussian
from seatrack.filters.driver import run_tracks
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig


def _state(B, n=4, seed=0):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(B, n, n))
    inner = TrackState.new(np.zeros(B), rng.normal(size=(B, 2)), np.eye(2)[None].repeat(B, 0))
    return TrackState.new(
        np.arange(B, dtype=float),
        rng.normal(size=(B, n)),
        A @ A.transpose(0, 2, 1) + np.eye(n),
        aux={"mu": rng.random((B, 3)), "model": inner},
    )


def test_take_put_where_concat_recurse_into_aux():
    s = _state(5)
    sub = s.take([3, 1])
    assert len(sub) == 2 and np.array_equal(sub.x, s.x[[3, 1]])
    assert np.array_equal(sub.aux["model"].x, s.aux["model"].x[[3, 1]])
    changed = sub.replace(x=sub.x + 1.0)
    back = s.put([3, 1], changed)
    assert np.array_equal(back.x[[3, 1]], s.x[[3, 1]] + 1.0)
    assert np.array_equal(back.x[[0, 2, 4]], s.x[[0, 2, 4]])
    assert np.array_equal(s.x, _state(5).x)  # put returns a copy
    w = s.where(np.array([True, False, True, False, False]), back)
    assert np.array_equal(w.aux["mu"], s.aux["mu"])
    both = TrackState.concat([s.take([0]), s.take([1, 2])])
    assert np.array_equal(both.aux["model"].P, s.aux["model"].P[:3])


def _plots(rng_m, az, el=None, rr=None, sensor=None):
    n = np.size(rng_m)
    return Plots(
        np.zeros(n),
        np.atleast_1d(np.asarray(rng_m, float)),
        np.atleast_1d(np.asarray(az, float)),
        None if el is None else np.atleast_1d(np.asarray(el, float)),
        None if rr is None else np.atleast_1d(np.asarray(rr, float)),
        np.zeros((n, 3)) if sensor is None else sensor,
    )


@pytest.mark.parametrize("d", [2, 3])
def test_plot_gaussian_matches_monte_carlo(d):
    sn = SensorNoise(sigma_range=20.0, sigma_azimuth=np.radians(0.3), sigma_elevation=0.004)
    r, a, e = 15000.0, np.radians(40.0), (0.05 if d == 3 else None)
    x, P = plot_gaussian(_plots(r, a, e), sn, speed_sigma=30.0)
    rng = np.random.default_rng(1)
    K = 200_000
    rr = r + sn.sigma_range * rng.normal(size=K)
    aa = a + sn.sigma_azimuth * rng.normal(size=K)
    if d == 2:
        pts = np.stack([rr * np.sin(aa), rr * np.cos(aa)], -1)
    else:
        ee = e + sn.sigma_elevation * rng.normal(size=K)
        pts = np.stack(
            [rr * np.cos(ee) * np.sin(aa), rr * np.cos(ee) * np.cos(aa), rr * np.sin(ee)], -1
        )
    C = np.cov(pts.T)
    # whitened by the linearised covariance, the sample covariance is I within sampling error
    W = np.linalg.inv(np.linalg.cholesky(P[0, :d, :d]))
    assert np.abs(W @ C @ W.T - np.eye(d)).max() < 6 * np.sqrt(2 / K)
    assert np.allclose(x[0, :d], pts.mean(0), atol=3 * np.sqrt(np.diag(C) / K) + 0.2)
    assert np.allclose(P[0, d:, d:], np.eye(d) * 900.0)
    assert np.allclose(x[0, d:], 0.0)


def test_plot_gaussian_uses_range_rate_along_the_line_of_sight():
    sn = SensorNoise(sigma_range_rate=0.5)
    sensor = np.array([[100.0, 0.0, 0.0]])
    p = Plots(
        np.zeros(1), np.array([1000.0]), np.array([np.pi / 2]), None, np.array([-7.0]),
        sensor, np.array([[2.0, 0.0, 0.0]]),
    )  # fmt: skip
    x, P = plot_gaussian(p, sn, speed_sigma=40.0)
    # target due East of the sensor: radial = x axis; sensor moves +2 m/s along it
    assert np.allclose(x[0, 2:], [-5.0, 0.0])
    assert np.allclose(P[0, 2:, 2:], np.diag([0.25, 1600.0]))


def test_two_point_gaussian_matches_monte_carlo():
    sn = SensorNoise(sigma_range=10.0, sigma_azimuth=np.radians(0.5))
    a = _plots(8000.0, 0.3)
    b = Plots(np.array([4.0]), np.array([8040.0]), np.array([0.31]))
    x, P = two_point_gaussian(a, b, sn)
    rng = np.random.default_rng(2)
    K = 200_000

    def draw(r, az):
        rr = r + 10.0 * rng.normal(size=K)
        aa = az + np.radians(0.5) * rng.normal(size=K)
        return np.stack([rr * np.sin(aa), rr * np.cos(aa)], -1)

    p1, p2 = draw(8000.0, 0.3), draw(8040.0, 0.31)
    s = np.concatenate([p2, (p2 - p1) / 4.0], -1)
    W = np.linalg.inv(np.linalg.cholesky(P[0]))
    assert np.abs(W @ np.cov(s.T) @ W.T - np.eye(4)).max() < 6 * np.sqrt(2 / K)


def test_finish_update_isolates_bad_elements():
    prior = _state(3)
    x = prior.x + 1.0
    x[1] = np.nan
    ll = np.array([-1.0, np.nan, -2.0])
    new = finish_update(prior, x, prior.P, np.ones(3), ll, prior.t, ok=np.array([1, 1, 0], bool))
    assert list(new.status) == [PlotStatus.UPDATED, PlotStatus.REJECTED, PlotStatus.REJECTED]
    assert np.array_equal(new.x[0], prior.x[0] + 1.0)
    assert np.array_equal(new.x[1:], prior.x[1:])
    assert np.isnan(new.nis[1:]).all() and new.nis[0] == 1.0


def test_common_columns_leave_z_empty_in_2d():
    cols = common_columns(np.ones((2, 4)), np.eye(4)[None].repeat(2, 0), 2)
    assert np.isnan(cols["z_m"]).all() and np.isnan(cols["std_z_m"]).all()
    assert np.allclose(cols["std_x_m"], 1.0)


def _straight_plots(n_tracks, n, seed, sn, d=2, rr=False, dt=2.0):
    """Noisy polar plots of straight targets, track labels 0..n_tracks-1 (interleaved)."""
    rng = np.random.default_rng(seed)
    p0 = rng.uniform(5000, 20000, (n_tracks, d)) * rng.choice([-1, 1], (n_tracks, d))
    if d == 3:
        p0[:, 2] = np.abs(p0[:, 2]) / 5
    v = rng.normal(0, 15, (n_tracks, d))
    t = np.arange(n) * dt
    pos = p0[:, None, :] + v[:, None, :] * t[None, :, None]  # (T, n, d)
    rel = pos.reshape(-1, d)
    rng_m = np.linalg.norm(rel, axis=-1)
    az = np.arctan2(rel[:, 0], rel[:, 1]) % (2 * np.pi)
    el = np.arcsin(rel[:, 2] / rng_m) if d == 3 else None
    rdot = np.einsum("ij,ij->i", rel, np.repeat(v, n, 0)) / rng_m
    plots = Plots(
        np.tile(t, n_tracks),
        rng_m + sn.sigma_range * rng.normal(size=rng_m.size),
        (az + sn.sigma_azimuth * rng.normal(size=az.size)) % (2 * np.pi),
        None if el is None else el + sn.sigma_elevation * rng.normal(size=el.size),
        (rdot + sn.sigma_range_rate * rng.normal(size=rdot.size)) if rr else None,
    )
    truth = np.concatenate([pos, np.repeat(v[:, None, :], n, 1)], -1).reshape(-1, 2 * d)
    return plots, np.repeat(np.arange(n_tracks), n), truth


@pytest.mark.parametrize("d, rr", [(2, False), (3, True)])
def test_ekf_is_consistent_on_straight_targets(d, rr):
    """NEES of the batched EKF over 40 straight targets sits in its chi-square interval."""
    sn = SensorNoise(sigma_range=20.0, sigma_azimuth=np.radians(0.2), sigma_elevation=0.003)
    plots, ti, truth = _straight_plots(40, 60, 3, sn, d=d, rr=rr)
    flt = EKF(EKFConfig(q=1e-6, initial_speed_sigma=60.0), sn, d=d, range_rate=rr)
    cols = run_tracks(flt, plots, ti, lambda p: plot_gaussian(p, sn, 60.0))
    assert (cols["status"][np.tile(np.arange(60), 40) == 0] == "initiated").all()
    assert (cols["status"][np.tile(np.arange(60), 40) > 0] == "updated").all()
    # NIS of the later updates: mean of 40*40 (independent, for a consistent filter)
    # chi-square(m) draws; 5 sigma
    m = 2 + (d == 3) + rr
    late = np.tile(np.arange(60), 40) >= 20
    assert abs(np.mean(cols["nis"][late]) - m) < 5 * np.sqrt(2 * m / late.sum())
    err = np.stack([cols["x_m"], cols["y_m"]], -1)[late] - truth[late, :2]
    assert np.sqrt(np.mean(err**2)) < 30.0


def test_batch_equals_single_track_runs():
    sn = SensorNoise()
    plots, ti, _ = _straight_plots(6, 25, 4, sn)
    # shorten two tracks: unequal lengths
    keep = ~(
        ((ti == 2) & (np.arange(ti.size) % 25 > 10)) | ((ti == 5) & (np.arange(ti.size) % 25 > 3))
    )
    plots, ti = plots.take(keep), ti[keep]
    flt = EKF()
    init = lambda p: plot_gaussian(p, sn, 50.0)  # noqa: E731
    batch = run_tracks(flt, plots, ti, init)
    for k in range(6):
        m = ti == k
        single = run_tracks(flt, plots.take(m), np.zeros(m.sum(), np.int64), init)
        for c in ("x_m", "vy_mps", "std_x_m", "nis"):
            assert np.allclose(batch[c][m], single[c], equal_nan=True, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("bad", [np.nan, np.inf, 1e308, -5.0])
def test_ekf_isolates_a_bad_plot(bad):
    sn = SensorNoise()
    plots, ti, _ = _straight_plots(2, 30, 5, sn)
    rng_m = plots.range.copy()
    rng_m[12] = bad  # track 0, plot 12
    bad_plots = Plots(plots.t, rng_m, plots.azimuth)
    init = lambda p: plot_gaussian(p, sn, 50.0)  # noqa: E731
    cols = run_tracks(EKF(), bad_plots, ti, init)
    good = run_tracks(EKF(), plots, ti, init)
    for c in ("x_m", "y_m", "vx_mps", "std_x_m"):
        assert np.isfinite(cols[c]).all()
    # the other track is untouched
    assert np.allclose(cols["x_m"][30:], good["x_m"][30:])
    if not np.isfinite(bad):
        assert cols["status"][12] == "rejected"


def test_cartesian_state_names_follow_d():
    from seatrack.filters.base import CartesianState

    class Shell(CartesianState):
        def __init__(self, d: int) -> None:
            self.d = d

    assert Shell(2).state_names == ("x", "y", "vx", "vy")
    assert Shell(3).state_names == ("x", "y", "z", "vx", "vy", "vz")


@pytest.mark.parametrize(
    ("key", "value"),
    [("sigma_range_m", 1e308), ("sigma_azimuth_deg", 400.0), ("sigma_elevation_deg", 1e200),
     ("sigma_range_rate_mps", 1e9)],
)  # fmt: skip
def test_absurd_sensor_noise_is_an_error_naming_the_key(key, value):
    """Every method shares the sensor section; a value no sensor has (which overflowed when
    squared in algorithm R) is refused with the key and the bound, for every method."""
    from seatrack.config import ConfigError
    from seatrack.filters import registry

    for name in ("ekf", "robust-spec", "mm-rangerate", "turning"):
        with pytest.raises(ConfigError, match=f"{key}: must be <="):
            registry.build(name, {key: value}, d=2, range_rate=True)
