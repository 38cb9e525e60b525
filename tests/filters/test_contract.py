"""The filter contract, checked on every registered method (``seatrack track --method``).

Same plots in, same columns out (COMMON_COLUMNS, status, nis, then the method's own),
NaN-free on good plots, covariances symmetric positive definite, a batch of tracks equal to
each track run alone, and a bad plot isolated: flagged ``rejected``, every other row finite,
the other tracks untouched.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from seatrack.filters import registry
from seatrack.filters.base import COMMON_COLUMNS
from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import RecursiveFilter
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory

METHODS = list(registry.METHODS)
SIGMA = (15.0, math.radians(0.3), math.radians(0.3), 1.0)
CFG = {"sigma_range_m": 15.0, "sigma_azimuth_deg": 0.3, "sigma_elevation_deg": 0.3}


def make_plots(d: int = 2, seed: int = 3) -> Plots:
    """Three labelled tracks with different scan times and lengths (partial batches)."""
    rng = np.random.default_rng(seed)
    parts = []
    specs = [
        ((8e3, 6e3, 500.0), 2.0, 0.0, 60),
        ((-5e3, 9e3, 800.0), 3.0, 1.0, 40),
        ((2e3, -7e3, 300.0), 2.0, 7.0, 50),
    ]
    for j, (start, dt, t0, n) in enumerate(specs):
        legs = [Leg.straight(n * dt / 2), Leg.turn_g(math.pi / 3, 1.0, 60.0), Leg.straight(n * dt)]
        times = t0 + dt * np.arange(n)
        tr = trajectory(list(start[:d]), 1.0 + j, 60.0, legs, times=times, t0=t0)
        comps = (
            ("range", "azimuth", "elevation", "range_rate")
            if d == 3
            else ("range", "azimuth", "range_rate")
        )
        sig = list(SIGMA) if d == 3 else [SIGMA[0], SIGMA[1], SIGMA[3]]
        m = observe(tr, None, comps, NoiseModel(sig), rng)
        el = m.z[:, 2] if d == 3 else None
        parts.append(
            Plots(tr.t, m.z[:, 0], m.z[:, 1], el, m.z[:, -1], m.sensor_pos, m.sensor_vel,
                  np.arange(n) + 2, np.full(n, f"T{j}"))
        )  # fmt: skip
    order = np.argsort(np.concatenate([p.t for p in parts]), kind="stable")
    return _concat(parts).take(order)


def _concat(parts: list[Plots]) -> Plots:
    def cat(name: str) -> object:
        vals = [getattr(p, name) for p in parts]
        return None if vals[0] is None else np.concatenate(vals)

    return Plots(*(cat(f) for f in ("t", "range", "azimuth", "elevation", "range_rate",
                                      "sensor", "sensor_vel", "line", "track")))  # fmt: skip


def _states(name: str, plots: Plots) -> list:
    """Every state of every track, plot by plot through the contract."""
    m = registry.build(name, CFG, d=plots.d, range_rate=plots.has_range_rate)
    f = m.filter
    out = []
    for label in dict.fromkeys(plots.track.tolist()):
        p = m.prepare(plots.take(plots.track == label))
        s = f.initiate(p.t[:1], *m.initiate(p.take([0])))
        out.append(s)
        for k in range(1, len(p)):
            s = f.update(f.predict(s, p.t[k : k + 1]), p.take([k]))
            out.append(s)
    return out


@pytest.mark.parametrize("name", METHODS)
def test_method_honours_the_protocol(name):
    m = registry.build(name, CFG, d=2, range_rate=True)
    assert isinstance(m.filter, RecursiveFilter)
    names = m.filter.state_names
    assert names[:4] == ("x", "y", "vx", "vy")


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("name", METHODS)
def test_same_columns_nan_free(name, d):
    plots = make_plots(d)
    cols = registry.run(name, plots, CFG)
    keys = list(cols)
    assert keys[: len(COMMON_COLUMNS) + 2] == [*COMMON_COLUMNS, "status", "nis"]
    extra = keys[len(COMMON_COLUMNS) + 2 :]
    other = registry.run(name, make_plots(5 - d), CFG)  # the other dimension: same columns
    assert list(other) == keys, (keys, list(other))
    assert all(len(v) == len(plots) for v in cols.values())
    tracked_3d = d == 3 and 3 in registry.method_class(name).dims
    for c in COMMON_COLUMNS:
        if c.startswith(("z", "vz", "std_z")) and not tracked_3d:
            assert np.isnan(cols[c]).all(), c  # 2-D tracking: z columns empty
        else:
            assert np.isfinite(cols[c]).all(), c
    first = np.isin(cols["status"], ["initiated"])
    assert first.sum() == 3
    assert (cols["status"][~first] == "updated").all()
    assert np.isfinite(cols["nis"][~first]).all() and (cols["nis"][~first] >= 0).all()
    for c in extra:
        v = cols[c]
        if v.dtype.kind == "f" and c not in ("turn_rate_dps", "turn_rate_std_dps"):
            assert np.isfinite(v).all(), c


@pytest.mark.parametrize("name", METHODS)
def test_covariances_symmetric_positive_definite(name):
    for s in _states(name, make_plots(2)):
        P = s.P
        np.testing.assert_allclose(P, np.swapaxes(P, -1, -2), rtol=1e-9, atol=1e-9)
        assert (np.linalg.eigvalsh(P) > 0).all()


@pytest.mark.parametrize("name", METHODS)
def test_batch_equals_single_tracks(name):
    plots = make_plots(2)
    batch = registry.run(name, plots, CFG)
    for label in ("T0", "T1", "T2"):
        idx = np.flatnonzero(plots.track == label)
        single = registry.run(name, plots.take(idx), CFG)
        for c, v in single.items():
            if v.dtype.kind == "f":
                np.testing.assert_allclose(batch[c][idx], v, rtol=1e-9, atol=1e-9, err_msg=c)
            else:
                np.testing.assert_array_equal(batch[c][idx], v, err_msg=c)


def _with_bad_plot(plots: Plots, label: str, k: int, value: float) -> tuple[Plots, int]:
    idx = np.flatnonzero(plots.track == label)[k]
    rng = plots.range.copy()
    rng[idx] = value
    return Plots(plots.t, rng, plots.azimuth, plots.elevation, plots.range_rate, plots.sensor,
                 plots.sensor_vel, plots.line, plots.track), int(idx)  # fmt: skip


@pytest.mark.parametrize("value", [1e308, np.inf, np.nan])
@pytest.mark.parametrize("name", METHODS)
def test_bad_plot_is_isolated(name, value):
    """Issue 13 item 1: one absurd plot is flagged, nothing is blanked, other tracks untouched."""
    plots = make_plots(2)
    bad, row = _with_bad_plot(plots, "T1", 10, value)
    with np.errstate(all="raise"):  # no warning may escape either
        cols = registry.run(name, bad, CFG)
    good = registry.run(name, plots, CFG)
    assert cols["status"][row] == PlotStatus.REJECTED.label
    others = np.arange(len(plots)) != row
    assert (cols["status"][others] != "rejected").all()
    for c in ("x_m", "y_m", "vx_mps", "vy_mps", "std_x_m", "std_y_m"):
        assert np.isfinite(cols[c]).all(), c
    # the other tracks are exactly as without the bad plot; this track before it, too
    t1 = plots.track == "T1"
    before = t1 & (plots.t < plots.t[row])
    same = ~t1 | before
    for c in ("x_m", "y_m", "vx_mps", "vy_mps", "std_x_m", "nis"):
        np.testing.assert_array_equal(cols[c][same], good[c][same], err_msg=c)
    # after it the track goes on, close to the run without the plot
    after = t1 & (plots.t > plots.t[row])
    err = np.hypot(cols["x_m"][after] - good["x_m"][after], cols["y_m"][after] - good["y_m"][after])
    assert err[-1] < 3 * good["std_x_m"][after][-1] + 3 * good["std_y_m"][after][-1]


def test_unknown_config_key_lists_valid_keys():
    with pytest.raises(
        ValueError,
        match=r"unknown key 'sigma_rnage_m'.*valid keys: .*q.*sensor keys: sigma_range_m",
    ):
        registry.build("ekf", {"sigma_rnage_m": 3.0})


def test_wrong_type_names_file_and_key():
    with pytest.raises(ValueError, match=r"cfg.toml: sigma_range_m: expected a number, got 'abc'"):
        registry.build("turning", {"sigma_range_m": "abc"}, source="cfg.toml")


def test_sensor_table_and_flat_keys_agree():
    a = registry.build("mm", {"sensor": {"sigma_range_m": 7.0, "sigma_azimuth_deg": 0.2}})
    b = registry.build("mm", {"sigma_range_m": 7.0, "sigma_azimuth_deg": 0.2})
    assert a.filter.sensor == b.filter.sensor
    assert a.filter.sensor.sigma_azimuth == pytest.approx(math.radians(0.2))
    with pytest.raises(ValueError, match="both flat and in"):
        registry.build("mm", {"sensor": {"sigma_range_m": 7.0}, "sigma_range_m": 7.0})


@pytest.mark.parametrize("name", METHODS)
def test_one_sensor_default_for_every_method(name):
    from seatrack.filters.base import SensorNoise

    assert registry.build(name, {}, range_rate=True).filter.sensor == SensorNoise()


def test_mm_rangerate_needs_range_rate():
    with pytest.raises(ValueError, match="needs a range_rate_mps column"):
        registry.build("mm-rangerate", {}, range_rate=False)


@pytest.mark.parametrize("name", METHODS)
def test_bad_first_plot_track_starts_on_the_next(name):
    plots = make_plots(2)
    bad, row = _with_bad_plot(plots, "T1", 0, 1e308)
    with np.errstate(all="raise"):
        cols = registry.run(name, bad, CFG)
    t1 = np.flatnonzero(plots.track == "T1")
    assert cols["status"][row] == "rejected"
    assert cols["status"][t1[1]] == "initiated"
    assert (cols["status"][t1[2:]] == "updated").all()
    assert np.isfinite(cols["x_m"][t1[1:]]).all()
    good = registry.run(name, plots, CFG)
    other = plots.track != "T1"
    np.testing.assert_array_equal(cols["x_m"][other], good["x_m"][other])
