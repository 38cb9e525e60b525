"""Tests of seatrack.simulate.families: shapes, seeds, truth consistent with the plots."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2

from seatrack.geometry import G0
from seatrack.geometry import angle_diff
from seatrack.geometry import bearing
from seatrack.models.measurement import range_rate
from seatrack.models.targets import target_class
from seatrack.simulate.families import ACTIVE_SONAR
from seatrack.simulate.families import COASTAL_RADAR
from seatrack.simulate.families import HEADLINE_SEEDS
from seatrack.simulate.families import MANOEUVRE_SPECS
from seatrack.simulate.families import OUTLIER_SCALE
from seatrack.simulate.families import TUNING_SEEDS
from seatrack.simulate.families import Scenario
from seatrack.simulate.families import ais_replay
from seatrack.simulate.families import ais_stretches
from seatrack.simulate.families import random_manoeuvres
from seatrack.simulate.families import seed_split
from seatrack.simulate.families import weaving

DEG = math.pi / 180
H0 = HEADLINE_SEEDS[0]


def normalised_errors(sc: Scenario) -> np.ndarray:
    """Plot errors against the truth divided by their nominal (or outlier) sigma."""
    p = sc.plots
    d = sc.truth[:, :2] - p.sensor[:, :2]
    dv = sc.truth[:, 2:] - p.sensor_vel[:, :2]
    cols = [p.range - np.hypot(d[:, 0], d[:, 1]), angle_diff(p.azimuth, bearing(*d.T))]
    sig = [sc.sensor.sigma_range, sc.sensor.sigma_azimuth]
    if p.range_rate is not None:
        cols.append(p.range_rate - range_rate(d, dv))
        sig.append(sc.sensor.sigma_range_rate)
    e = np.stack(cols, -1) / np.array(sig)
    scale = np.sqrt(np.array(sc.outlier_scale))
    return np.asarray(np.where(sc.outlier, e / scale, e))


def assert_chi2(e: np.ndarray) -> None:
    n = e.size
    lo, hi = chi2.ppf([0.0005, 0.9995], n)
    assert lo < float(np.sum(e**2)) < hi


def test_seed_ranges_are_disjoint_and_checked() -> None:
    assert seed_split(0) == "tuning" and seed_split(H0) == "headline"
    assert TUNING_SEEDS.stop <= HEADLINE_SEEDS.start
    with pytest.raises(ValueError, match="neither"):
        seed_split(-1)
    with pytest.raises(ValueError, match="neither"):
        random_manoeuvres("ship", HEADLINE_SEEDS.stop)


def test_same_seed_same_scenario_other_seed_other() -> None:
    a, b = random_manoeuvres("aircraft", 7), random_manoeuvres("aircraft", 7)
    np.testing.assert_array_equal(a.plots.range, b.plots.range)
    c = random_manoeuvres("aircraft", 8)
    assert not np.allclose(a.truth, c.truth)


@pytest.mark.parametrize("target", list(MANOEUVRE_SPECS))
def test_random_manoeuvres(target: str) -> None:
    spec = MANOEUVRE_SPECS[target]
    for seed in (3, H0 + 3):
        sc = random_manoeuvres(target, seed, epsilon=0.2 if target == "submarine" else 0.0)
        N = sc.plots.t.size
        assert sc.truth.shape == (N, 4) and sc.outlier.shape[0] == N
        assert sc.plots.t[-1] == pytest.approx(spec.duration)
        assert np.allclose(np.diff(sc.plots.t), spec.sensor.dt)
        assert sc.plots.has_range_rate == (spec.sensor.sigma_range_rate is not None)
        assert sc.split == seed_split(seed)
        assert_chi2(normalised_errors(sc))
        w = np.abs(sc.turn_rate[sc.turn_rate != 0])
        assert w.size > 0 and sc.manoeuvring.any() and not sc.manoeuvring.all()
        speed = np.hypot(sc.truth[:, 2], sc.truth[:, 3])
        lo, hi = min(spec.speed[0], spec.speed_range[0]), max(spec.speed[1], spec.speed_range[1])
        assert lo - 1e-6 <= speed.min() and speed.max() <= hi + 1e-6
        if spec.turn_g is None:
            assert w.min() >= spec.turn_rate[0] - 1e-12 and w.max() <= spec.turn_rate[1] + 1e-12
        else:  # lateral acceleration in g: w v / G0 at the speed of the turn
            g = (np.abs(sc.turn_rate) * speed / G0)[sc.turn_rate != 0]
            assert g.min() >= spec.turn_g[0] - 1e-9 and g.max() <= spec.turn_g[1] + 1e-9


def test_air_traffic_case_is_the_issue_case() -> None:
    spec = MANOEUVRE_SPECS["aircraft"]
    assert spec.sensor.dt == 4.0 and spec.sensor.sigma_range == 40.0
    assert spec.sensor.sigma_azimuth == pytest.approx(0.08 * DEG)
    assert spec.turn_rate == pytest.approx((1.5 * DEG, 3 * DEG)) and spec.speed == (90.0, 150.0)


def test_contamination_fraction() -> None:
    sc = random_manoeuvres("submarine", 11, epsilon=0.2)
    n = sc.outlier.size
    assert abs(sc.outlier.mean() - 0.2) < 4 * math.sqrt(0.2 * 0.8 / n)
    assert sc.outlier_scale == OUTLIER_SCALE[:2] and sc.epsilon == 0.2
    clean = random_manoeuvres("submarine", 11)
    assert not clean.outlier.any()


@pytest.mark.parametrize("target", ["ship", "aircraft", "fighter"])
def test_weaving(target: str) -> None:
    sc = weaving(target, H0 + 1)
    assert_chi2(normalised_errors(sc))
    tc = target_class(target)
    w = sc.turn_rate[sc.manoeuvring]
    speed = np.hypot(sc.truth[0, 2], sc.truth[0, 3])
    wa = tc.accel_typical / speed if target == "fighter" else tc.turn_rate_typical
    assert np.abs(w).max() <= wa * (1 + 1e-9)
    assert np.abs(w).max() >= 0.95 * wa  # the sinusoid reaches its amplitude
    assert np.all(sc.turn_rate[~sc.manoeuvring] == 0)
    # the heading swings +-20..45 deg around its mean: never a steady turn
    crs = np.unwrap(np.arctan2(sc.truth[:, 2], sc.truth[:, 3]))[sc.manoeuvring]
    assert 40 * DEG * 0.9 <= crs.max() - crs.min() <= 90 * DEG * 1.01


def test_ais_stretches_split_by_vessel() -> None:
    st = ais_stretches()
    tune = {(s.source, s.mmsi) for s in st if s.split == "tuning"}
    head = {(s.source, s.mmsi) for s in st if s.split == "headline"}
    assert tune and head and not (tune & head)
    assert all(s.turn >= 45 * DEG for s in st)


@pytest.mark.parametrize("sensor", [COASTAL_RADAR, ACTIVE_SONAR], ids=lambda s: s.name)
def test_ais_replay(sensor) -> None:
    for seed in (2, H0 + 2):
        sc = ais_replay(seed, sensor, epsilon=0.2 if sensor is ACTIVE_SONAR else 0.0)
        assert sc.truth.shape == (sc.plots.t.size, 4) and sc.split == seed_split(seed)
        assert_chi2(normalised_errors(sc))
        speed = np.hypot(sc.truth[:, 2], sc.truth[:, 3])
        assert speed.min() >= 1.5 and speed.max() < 20.0
        crs = np.unwrap(np.arctan2(sc.truth[:, 2], sc.truth[:, 3]))
        assert crs.max() - crs.min() >= 45 * DEG - 1e-6
        assert sc.manoeuvring.any()
        # velocity is the derivative of position (the spline and its derivative agree)
        dp = np.diff(sc.truth[:, :2], axis=0) / np.diff(sc.plots.t)[:, None]
        vm = 0.5 * (sc.truth[1:, 2:] + sc.truth[:-1, 2:])
        assert np.abs(dp - vm).max() < 0.05


def test_ais_truth_follows_the_real_reports() -> None:
    from seatrack.data import ais_sample
    from seatrack.io.ais import read_ais_csv
    from seatrack.io.ais import to_local
    from seatrack.io.ais import validate_reports

    st = ais_stretches()[0]
    r = validate_reports(read_ais_csv(ais_sample(st.source)))
    sel = r.valid & (r.mmsi == st.mmsi) & (r.t >= st.t0) & (r.t <= st.t0 + st.duration)
    loc = to_local(r)
    tt = r.t[sel] - st.t0 + st.start
    res = np.hypot(st.sx(tt) - loc.enu[sel, 0], st.sy(tt) - loc.enu[sel, 1])
    assert np.median(res) < 5.0
    sog = r.sog_kn[sel] * 1852 / 3600
    spd = np.hypot(st.sx.derivative()(tt), st.sy.derivative()(tt))
    ok = np.isfinite(sog)
    assert np.median(np.abs(spd[ok] - sog[ok])) < 0.5


def test_sensor_table_is_what_a_user_gives() -> None:
    """The nominal noise in the documented keys parses back to the scenario's sensor."""
    from seatrack.filters.registry import build

    for sc in (random_manoeuvres("ship", 5), random_manoeuvres("fighter", 5)):
        table = sc.sensor_table()
        assert math.isclose(table["sigma_azimuth_deg"], math.degrees(sc.sensor.sigma_azimuth))
        assert ("sigma_range_rate_mps" in table) == sc.plots.has_range_rate
        m = build("ekf", table, d=2, range_rate=sc.plots.has_range_rate)
        assert math.isclose(m.filter.sensor.sigma_range, sc.sensor.sigma_range)
        assert math.isclose(m.filter.sensor.sigma_azimuth, sc.sensor.sigma_azimuth)
