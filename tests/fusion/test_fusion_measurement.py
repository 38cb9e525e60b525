"""AIS reports as measurements of the radar tracks: rounds, noise, the update, consistency."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from seatrack.config import ConfigError
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig
from seatrack.filters.imm import combine
from seatrack.filters.registry import build
from seatrack.fusion.associate import FusionConfig
from seatrack.fusion.measurement import AisMeasurements
from seatrack.fusion.measurement import ReportUpdater
from seatrack.fusion.measurement import check_filter
from seatrack.fusion.measurement import measurement_noise
from seatrack.fusion.measurement import position_update
from seatrack.fusion.measurement import vessel_rounds
from seatrack.geometry import cart_to_polar
from seatrack.kalman import update
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition
from seatrack.tracking.adaptive import NoiseLevels


def test_rounds_hold_one_report_per_vessel_in_time_order() -> None:
    vessel = np.array([3, 1, 3, 3, 1, 7])
    t = np.array([5.0, 2.0, 1.0, 9.0, 4.0, 3.0])
    assert vessel_rounds(vessel, t).tolist() == [1, 0, 0, 2, 1, 0]
    assert vessel_rounds(np.zeros(0, np.int64), np.zeros(0)).size == 0


def test_measurement_noise_adds_the_allowances() -> None:
    cfg = FusionConfig(sigma_antenna_offset=30.0, sigma_latency=2.0)
    vel = np.array([[3.0, 4.0], [0.0, 0.0]])
    r = measurement_noise(np.array([10.0, 5.0]), np.array([0.5, 0.5]), vel, cfg)
    want0 = 1000.0 * np.eye(2) + 4.25 * np.outer(vel[0], vel[0])
    np.testing.assert_allclose(r[0], want0)
    np.testing.assert_allclose(r[1], 925.0 * np.eye(2))


def test_position_update_is_the_kalman_update_of_the_position() -> None:
    rng = np.random.default_rng(0)
    flt = EKF(EKFConfig(q=0.1), sensor=SensorNoise())
    a = rng.normal(size=(3, 4, 4))
    p = a @ a.transpose(0, 2, 1) + 4 * np.eye(4)
    s = flt.initiate(np.zeros(3), rng.normal(size=(3, 4)), p)
    z, r = rng.normal(size=(3, 2)), np.tile(np.diag([2.0, 3.0]), (3, 1, 1))
    new = position_update(s, z, r)
    h = np.hstack([np.eye(2), np.zeros((2, 2))])
    want = update(s.x, s.P, z, h, r)
    np.testing.assert_allclose(new.x, want.x)
    np.testing.assert_allclose(new.P, want.P)
    np.testing.assert_allclose(new.log_likelihood, want.log_likelihood)


def test_position_update_of_the_adaptive_noise_updates_every_model() -> None:
    flt = NoiseLevels(EKF(EKFConfig(q=0.01), sensor=SensorNoise()), extra=(0.0, 5.0))
    s = flt.initiate(np.zeros(1), np.array([[0.0, 0.0, 5.0, 0.0]]),
                     np.diag([100.0, 100.0, 4.0, 4.0])[None])  # fmt: skip
    s = flt.predict(s, np.array([10.0]))
    z, r = np.array([[150.0, 80.0]]), np.diag([25.0, 25.0])[None]
    new = position_update(s, z, r)
    models, c = s.aux["noise_models"], s.aux["noise_mu"]
    h = np.hstack([np.eye(2), np.zeros((2, 2))])
    per = update(models.x[0], models.P[0], z[0], h, r[0])
    mu, x, p, tot = combine(per.x, per.P, c[0], per.log_likelihood, np.arange(4))
    np.testing.assert_allclose(new.x[0], x)
    np.testing.assert_allclose(new.P[0], p)
    np.testing.assert_allclose(new.aux["noise_mu"][0], mu)
    assert new.log_likelihood[0] == pytest.approx(tot)
    # the agile model explains a 130 m miss after 10 s better: its probability rises
    assert mu[1] > c[0, 1]
    np.testing.assert_allclose(new.P[0], new.P[0].T)
    assert np.linalg.eigvalsh(new.P[0]).min() > 0


def test_filters_with_states_of_their_own_are_refused() -> None:
    check_filter(EKF(sensor=SensorNoise()))
    check_filter(NoiseLevels(EKF(sensor=SensorNoise())))
    with pytest.raises(ConfigError, match="measurement"):
        check_filter(build("imm", {}).filter)


def _reports(vessel: np.ndarray, t: np.ndarray, pos: np.ndarray, sigma: float) -> AisMeasurements:
    o = np.argsort(t, kind="stable")
    cov = np.tile(sigma**2 * np.eye(2), (t.size, 1, 1))
    return AisMeasurements(vessel[o], t[o], pos[o], cov)


def test_reports_go_to_their_own_tracks_and_identities_hold() -> None:
    """Two tracks 400 m apart, each vessel reporting every 4 s: every report updates its
    own vessel's track, the identities never swap, and a report far from every track
    (a spoofed position) updates nothing."""
    cfg = FusionConfig(sigma_antenna_offset=0.0, sigma_latency=0.0)
    flt = EKF(EKFConfig(q=0.01), sensor=SensorNoise())
    p0 = np.array([[1000.0, 0.0], [1000.0, 400.0]])
    v = np.array([[5.0, 0.0], [5.0, 0.0]])
    t = np.arange(1.0, 60.0, 4.0)
    rng = np.random.default_rng(3)
    pos = p0[:, None] + v[:, None] * t[None, :, None] + rng.normal(0, 5, (2, t.size, 2))
    vessel = np.repeat([5, 9], t.size)
    times = np.tile(t, 2)
    spoof = np.array([[9000.0, 9000.0]])
    rep = _reports(np.r_[vessel, 7], np.r_[times, 30.5], np.r_[pos.reshape(-1, 2), spoof], 5.0)
    p = np.tile(np.diag([400.0, 400.0, 4.0, 4.0]), (2, 1, 1))
    state = flt.initiate(np.zeros(2), np.hstack([p0, v]), p)
    up = ReportUpdater(flt, rep, cfg)
    ids = np.array([11, 12])
    for scan in np.arange(3.0, 62.0, 3.0):
        state = up.update(state, ids, np.ones(2, bool), scan)
        a = up.assignment(ids, np.array([5, 7, 9]))
        if scan > 4.0:
            assert a.ais_row.tolist() == [0, 2]
            assert np.all(a.identity_prob > 0.99)
    assert sum(x.size for x in up.nis) == 2 * t.size
    truth = p0 + v * t[-1]
    assert np.all(np.hypot(*(state.x[:, :2] - truth).T) < 15.0)


def test_tracks_updated_with_ais_are_consistent() -> None:
    """NEES of radar tracks updated with radar plots and AIS reports, over 300 independent
    vessels with the filter's own motion model, lies in the two-sided 99 % chi-square
    interval (4 dof) at several times."""
    rng = np.random.default_rng(7)
    n, q = 300, 0.05
    sensor = SensorNoise(sigma_range=20.0, sigma_azimuth=np.radians(0.3))
    flt = EKF(EKFConfig(q=q), sensor=sensor)
    cfg = FusionConfig(sigma_antenna_offset=0.0, sigma_latency=0.0)
    # truth on a 1 s grid: vessels 2 km apart in range, spread in bearing
    r0 = 3000.0 + 2000.0 * np.arange(n) / 10
    b0 = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x = np.stack([r0 * np.sin(b0), r0 * np.cos(b0), rng.normal(0, 4, n), rng.normal(0, 4, n)], -1)
    f1, q1 = cv_transition(1.0, 2), cv_noise(1.0, q, 2)
    lq = np.linalg.cholesky(q1)
    steps = 120
    truth = np.empty((steps + 1, n, 4))
    truth[0] = x
    for k in range(steps):
        truth[k + 1] = truth[k] @ f1.T + rng.normal(size=(n, 4)) @ lq.T
    # AIS every 5 s (per-vessel offset), 10 m noise; radar scans every 3 s
    sig = 10.0
    phase = rng.integers(0, 5, n)
    rv, rt, rp = [], [], []
    for k in range(1, steps + 1):
        who = np.flatnonzero((k - phase) % 5 == 0)
        rv.append(who)
        rt.append(np.full(who.size, float(k)))
        rp.append(truth[k, who, :2] + rng.normal(0, sig, (who.size, 2)))
    rep = _reports(np.concatenate(rv), np.concatenate(rt), np.concatenate(rp), sig)
    p0 = np.diag([400.0, 400.0, 25.0, 25.0])
    state = flt.initiate(np.zeros(n), truth[0] + rng.multivariate_normal(np.zeros(4), p0, n),
                         np.tile(p0, (n, 1, 1)))  # fmt: skip
    up = ReportUpdater(flt, rep, cfg)
    ids = np.arange(n)
    lo, hi = chi2.ppf([0.005, 0.995], 4 * n) / n
    checked = 0
    for scan in range(3, steps + 1, 3):
        state = up.update(state, ids, np.ones(n, bool), float(scan))
        state = flt.predict(state, np.full(n, float(scan)))
        rng_b = cart_to_polar(truth[scan, :, :2])
        plots = Plots(
            np.full(n, float(scan)),
            rng_b[0] + rng.normal(0, sensor.sigma_range, n),
            rng_b[1] + rng.normal(0, sensor.sigma_azimuth, n),
            sensor=np.zeros((n, 3)), sensor_vel=np.zeros((n, 3)),
            line=np.arange(n),
        )  # fmt: skip
        state = flt.update(state, plots)
        if scan % 30 == 0:
            e = state.x - truth[scan]
            nees = np.einsum("ni,nij,nj->n", e, np.linalg.inv(state.P), e)
            assert lo <= nees.mean() <= hi, (scan, nees.mean(), lo, hi)
            checked += 1
    assert checked == 4
    used = np.concatenate(up.nis)
    # (a few first reports, against the wide initial covariance, fall outside the gate)
    assert used.size >= 0.995 * rep.t.size
    nis_lo, nis_hi = chi2.ppf([0.005, 0.995], 2 * used.size) / used.size
    assert nis_lo <= used.mean() <= nis_hi
