"""The multi-target tracker end to end: any filter on the contract, GNN and JPDA."""

import dataclasses

import numpy as np
import pytest

from seatrack.config import ConfigError
from seatrack.config import parse_config
from seatrack.evaluate.multitarget import score_run
from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import common_columns
from seatrack.filters.base import finish_update
from seatrack.filters.base import plot_gaussian
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig
from seatrack.filters.registry import METHODS
from seatrack.filters.registry import method_class
from seatrack.io.multitarget import sensor_noise
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition
from seatrack.simulate.multitarget import TargetPopulation
from seatrack.simulate.multitarget import simulate_multitarget
from seatrack.simulate.scenarios import SensorConfig
from seatrack.tracking import MultiTargetTracker
from seatrack.tracking import TrackerConfig
from seatrack.tracking import TrackStatus
from seatrack.tracking.auto import per_track_filter
from seatrack.tracking.auto import scan_period

SN = SensorNoise(sigma_range=15.0, sigma_azimuth=np.radians(0.3))


class ConvertedCV:
    """A second filter on the contract, written here: a *linear* Kalman filter on the
    plots converted to Cartesian positions (covariance linearised from the polar noise).
    Its innovation for gating is the polar one the contract asks for."""

    def __init__(self, q: float, sensor: SensorNoise) -> None:
        self.q, self.sensor, self.d, self.range_rate = q, sensor, 2, False

    @property
    def state_names(self):
        return ("x", "y", "vx", "vy")

    def initiate(self, t, x, P):
        return TrackState.new(t, x, P)

    def predict(self, state, t):
        tt = np.broadcast_to(np.asarray(t, float), state.t.shape)
        F, Q = cv_transition(tt - state.t, 2), cv_noise(tt - state.t, self.q, 2)
        x = np.einsum("bij,bj->bi", F, state.x)
        P = F @ state.P @ np.swapaxes(F, -1, -2) + Q
        return state.replace(t=tt.copy(), x=x, P=P, status=np.full(len(state), 2, np.int8))

    def innovation(self, state, plots):
        rel = state.x[:, :2] - plots.sensor[:, :2]
        r = np.hypot(rel[:, 0], rel[:, 1])
        h = np.stack([r, np.arctan2(rel[:, 0], rel[:, 1])], -1)
        H = np.zeros((len(state), 2, 4))
        H[:, 0, 0], H[:, 0, 1] = rel[:, 0] / r, rel[:, 1] / r
        H[:, 1, 0], H[:, 1, 1] = rel[:, 1] / r**2, -rel[:, 0] / r**2
        y = plots.polar(False) - h
        y[:, 1] = (y[:, 1] + np.pi) % (2 * np.pi) - np.pi
        R = np.diag([self.sensor.sigma_range**2, self.sensor.sigma_azimuth**2])
        return y, H @ state.P @ np.swapaxes(H, -1, -2) + R

    def update(self, state, plots):
        z, C = plot_gaussian(plots, self.sensor, 1.0)
        z, C = z[:, :2], C[:, :2, :2]
        S = state.P[:, :2, :2] + C
        K = state.P[:, :, :2] @ np.linalg.inv(S)
        y = z - state.x[:, :2]
        x = state.x + np.einsum("bij,bj->bi", K, y)
        P = state.P - K @ state.P[:, :2, :]
        P = 0.5 * (P + np.swapaxes(P, -1, -2))
        nis = np.einsum("bi,bi->b", y, np.linalg.solve(S, y[..., None])[..., 0])
        ll = -0.5 * (nis + np.log(np.linalg.det(S)) + 2 * np.log(2 * np.pi))
        return finish_update(state, x, P, nis, ll, state.t)

    def columns(self, state):
        return common_columns(state.x, state.P, 2)


def _scenario(seed=3, targets=8, clutter=10.0, pd=0.95, duration=150.0):
    radar = SensorConfig(
        "r", "radar2d", ("azimuth", "range"), (SN.sigma_azimuth, SN.sigma_range),
        p_detect=pd, clutter_density=clutter, clutter_range=(500.0, 13000.0), scan_period=2.5,
    )  # fmt: skip
    pop = TargetPopulation(targets=targets, births_per_scan=0.0, mean_life=0.0,
                           range_limits=(2000.0, 12000.0), crossings=1)  # fmt: skip
    return simulate_multitarget(pop, radar, duration, np.random.default_rng(seed))


def _score(sim, out):
    pos = np.stack([out.columns["x_m"], out.columns["y_m"]], -1)
    return score_run(sim.scan_times, sim.truth_t, sim.truth_id, sim.truth_pos[:, :2],
                     out.t, out.track, pos)  # fmt: skip


@pytest.mark.parametrize(
    "make, association",
    [
        (lambda: EKF(EKFConfig(q=0.1), SN), "gnn"),
        (lambda: EKF(EKFConfig(q=0.1), SN), "jpda"),
        (lambda: ConvertedCV(0.1, SN), "gnn"),
        (lambda: ConvertedCV(0.1, SN), "jpda"),
    ],
)
def test_tracks_every_target_with_any_filter(make, association):
    flt = make()
    assert isinstance(flt, RecursiveFilter)
    sim = _scenario()
    trk = MultiTargetTracker(flt, SN, TrackerConfig(association=association))
    out = trk.run(sim.plots)
    s = _score(sim, out)
    late = sim.scan_times >= 20.0  # after initiation
    # every target held, hardly any false track, localisation well inside the noise
    assert s.scans.n_missed[late].mean() < 0.3
    assert s.scans.n_false[late].mean() < 0.3
    loc = s.scans.localisation[late] / np.maximum(s.scans.n_truth[late] - s.scans.n_missed[late], 1)
    assert np.sqrt(loc.mean()) < 40.0  # raw cross-range noise is 30-60 m
    assert s.id_switches <= 2
    # plots of a target go to one track; clutter mostly stays clutter
    target = sim.origin >= 0
    assert (out.plot_track[target] >= 0).mean() > 0.9
    assert (out.plot_track[~target] >= 0).mean() < 0.05
    for k in np.unique(sim.origin[target]):
        ids, n = np.unique(out.plot_track[sim.origin == k], return_counts=True)
        assert n.max() / n.sum() > 0.8


@pytest.mark.parametrize("rule", ["existence", "m-of-n"])
def test_ids_are_stable_and_rows_consistent(rule):
    sim = _scenario(seed=5)
    trk = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN, TrackerConfig(confirmation=rule))
    out = trk.run(sim.plots, all_tracks=True)
    # one row per (scan, track); a track's rows are at consecutive scans while it lives
    key = out.t * 1e6 + out.track
    assert np.unique(key).size == key.size
    for tid in np.unique(out.track):
        tt = np.sort(out.t[out.track == tid])
        assert np.allclose(np.diff(tt), 2.5)
        st = out.status[out.track == tid][np.argsort(out.t[out.track == tid])]
        first_conf = np.flatnonzero(st != TrackStatus.TENTATIVE)
        if first_conf.size and rule == "m-of-n":  # tentative rows only before confirmation
            assert np.all(st[first_conf[0] :] != TrackStatus.TENTATIVE)
    # reported exactly while the existence probability is high enough
    reported = out.status != TrackStatus.TENTATIVE
    if rule == "existence":
        assert np.array_equal(reported, out.existence >= TrackerConfig().confirm_existence)
    assert np.all((out.existence > 0) & (out.existence <= 1))
    # the plot of a row is a plot of that scan; coasting rows have none
    has = out.plot >= 0
    assert np.allclose(sim.plots.t[out.plot[has]], out.t[has])
    assert np.all(out.plot[out.status == TrackStatus.COASTING] < 0)
    # every plot that updated a track is labelled with it
    assert np.array_equal(out.plot_track[out.plot[has]], out.track[has])


def test_existence_confirms_by_the_clutter_density():
    """Sparse clutter: every target reported at its second plot, surely. Dense clutter
    (300 plots per scan): the first scan's target share is estimated from the pairs, the
    second-plot tracks are less sure, and the few false ones are gone a scan later."""
    sim = _scenario(seed=12, targets=6, clutter=2.0, pd=1.0, duration=30.0)
    trk = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN)
    out = trk.run(sim.plots)
    s = _score(sim, out)
    n0 = s.scans.n_truth[0]
    assert s.scans.n_missed[0] == n0 > 0  # one plot: nothing reported
    assert s.scans.n_missed[1] == 0 and s.scans.n_false[1] == 0  # two plots: all reported
    sure = out.existence[out.t == 2.5]
    dense = _scenario(seed=12, targets=6, clutter=300.0, pd=1.0, duration=30.0)
    trk = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN)
    out = trk.run(dense.plots)
    s = _score(dense, out)
    share = n0 / np.count_nonzero(dense.plots.t == 0.0)
    assert trk.initiator.undetected.first_plots > 250
    assert np.median(out.existence[out.t == 2.5]) < np.median(sure)
    assert s.scans.n_false[2:].sum() == 0 and s.scans.n_missed[2:].sum() == 0
    assert 0.5 * share < trk.initiator.undetected.first_share < 2 * share


def test_existence_drops_dead_tracks_quickly_and_keeps_live_ones():
    """Pd 0.95: a target that vanishes is no longer reported after 3 missed scans, the
    M-of-N rule needs its max_misses; a live target at Pd 0.7 keeps its id."""
    sim = _scenario(seed=13, targets=5, clutter=5.0, pd=0.95, duration=100.0)
    gone = sim.origin == sim.origin[sim.origin >= 0].min()
    stop = 50.0
    cut = ~(gone & (sim.plots.t > stop))  # target 0 dies after t = 50 s
    plots = sim.plots.take(np.flatnonzero(cut))
    out = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN).run(plots)
    tid = np.bincount(out.plot_track[np.flatnonzero(gone[cut])] + 1).argmax() - 1
    assert tid >= 0 and out.t[out.track == tid].max() <= stop + 3 * 2.5
    live = _scenario(seed=14, targets=3, clutter=5.0, pd=0.7, duration=150.0)
    out = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN).run(live.plots)
    s = _score(live, out)
    assert s.id_switches == 0 and s.scans.n_missed[live.scan_times > 30].mean() < 0.5


def test_deterministic():
    sim = _scenario(seed=6)
    a = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN).run(sim.plots)
    b = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN).run(sim.plots)
    assert np.array_equal(a.track, b.track) and np.array_equal(a.columns["x_m"], b.columns["x_m"])


def test_clutter_and_detection_estimates():
    sim = _scenario(seed=7, clutter=40.0, pd=0.8, duration=200.0)
    trk = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN)
    trk.run(sim.plots)
    assert trk.clutter.per_scan == pytest.approx(40.0, rel=0.25)
    assert trk.detection.pd == pytest.approx(0.8, abs=0.06)
    assert trk.max_misses >= 4  # (0.2)^k < 0.001 for a live target


def test_bad_plots_are_skipped_and_tracks_coast():
    sim = _scenario(seed=8, clutter=0.0)
    p = sim.plots
    rng_m = p.range.copy()
    late = np.flatnonzero(p.t == 100.0)
    rng_m[late] = np.nan  # a whole scan of unusable plots
    bad = Plots(p.t, rng_m, p.azimuth, None, None, p.sensor, p.sensor_vel)
    out = MultiTargetTracker(EKF(EKFConfig(q=0.1), SN), SN).run(bad)
    at = out.t == 100.0
    assert at.any() and np.all(out.status[at] == TrackStatus.COASTING)
    assert np.all(out.plot_track[late] == -1)
    assert np.isfinite(out.columns["x_m"]).all()


def test_step_errors():
    trk = MultiTargetTracker(EKF(), SN)
    p = Plots(np.array([5.0, 6.0]), np.array([1000.0, 1000.0]), np.array([0.1, 0.2]))
    with pytest.raises(ValueError, match="scan time 5 s"):
        trk.step(5.0, p)
    with pytest.raises(ValueError, match="finite"):
        trk.step(np.nan, p.take(np.zeros(0, int)))
    trk.step(6.0, p.take([1]))
    with pytest.raises(ValueError, match="not after"):
        trk.step(5.0, p.take([0]))


def test_config_validation_and_edge_units():
    cfg = parse_config(TrackerConfig, {"m_of_n": [4, 6], "max_speed_kn": 30, "association": "jpda"})
    assert cfg.m_of_n == (4, 6) and cfg.max_speed == pytest.approx(30 * 1852 / 3600)
    with pytest.raises(ConfigError, match="m_of_n"):
        parse_config(TrackerConfig, {"m_of_n": [5, 3]})
    with pytest.raises(ConfigError, match="association"):
        parse_config(TrackerConfig, {"association": "mht"})
    with pytest.raises(ValueError, match="integers"):
        dataclasses.replace(TrackerConfig(), m_of_n=(2.5, 4))


def test_new_tracks_take_the_velocity_prior_of_the_config():
    """A new track is the first plot with the configured velocity prior, updated with the
    second: with the plain EKF it equals that fusion done by hand; a tighter prior gives a
    smaller velocity variance."""
    p = Plots(np.array([0.0, 2.5]), np.array([8000.0, 8010.0]), np.radians([30.0, 30.01]))
    ekf = EKF(EKFConfig(q=0.1), SN)
    var = []
    for kn in (6.0, 24.0):
        cfg = TrackerConfig(initial_speed_sigma=kn * 1852 / 3600)
        trk = MultiTargetTracker(ekf, SN, cfg)
        trk.step(0.0, p.take([0]))
        res = trk.step(2.5, p.take([1]))
        x, P = plot_gaussian(p.take([0]), SN, cfg.initial_speed_sigma)
        want = ekf.update(ekf.predict(ekf.initiate(p.t[:1], x, P), p.t[1:]), p.take([1]))
        assert res.track.size == 1
        assert np.allclose(res.state.x, want.x) and np.allclose(res.state.P, want.P)
        var.append(np.trace(res.state.P[0, 2:, 2:]))
    assert var[0] < var[1]
    cfg = parse_config(TrackerConfig, {"initial_speed_sigma_kn": 10})
    assert cfg.initial_speed_sigma == pytest.approx(10 * 1852 / 3600)


def test_rejected_update_counts_as_a_miss():
    class Rejecting(EKF):
        def update(self, state, plots):
            s = super().update(state, plots)
            return s.replace(status=np.full(len(s), PlotStatus.REJECTED, np.int8))

    sim = _scenario(seed=9, clutter=0.0, targets=3)
    out = MultiTargetTracker(Rejecting(EKFConfig(q=0.1), SN), SN).run(sim.plots)
    assert np.all(out.status != TrackStatus.CONFIRMED)


def test_3d_plots_with_range_rate():
    sn = SensorNoise(sigma_range=15.0, sigma_azimuth=np.radians(0.3),
                     sigma_elevation=np.radians(0.3), sigma_range_rate=0.5)  # fmt: skip
    radar = SensorConfig(
        "r", "radar3d", ("azimuth", "range", "elevation", "range_rate"),
        (sn.sigma_azimuth, sn.sigma_range, sn.sigma_elevation, sn.sigma_range_rate),
        p_detect=0.95, clutter_density=5.0, clutter_range=(500.0, 13000.0), scan_period=2.5,
    )  # fmt: skip
    pop = TargetPopulation(targets=4, births_per_scan=0.0, mean_life=0.0, crossings=0,
                           range_limits=(2000.0, 12000.0))  # fmt: skip
    sim = simulate_multitarget(pop, radar, 80.0, np.random.default_rng(11), observer=[0, 0, 30])
    flt = EKF(EKFConfig(q=0.1), sn, d=3, range_rate=True)
    out = MultiTargetTracker(flt, sn).run(sim.plots)
    assert out.existence.size == out.t.size
    s = _score(sim, out)
    assert s.scans.n_missed[sim.scan_times >= 20].mean() < 0.3
    assert np.isfinite(out.columns["z_m"]).all()


def _rr_scenario(seed=11):
    sn = SensorNoise(sigma_range=15.0, sigma_azimuth=np.radians(0.3), sigma_range_rate=0.5)
    radar = SensorConfig(
        "r", "radar2d", ("azimuth", "range", "range_rate"),
        (sn.sigma_azimuth, sn.sigma_range, sn.sigma_range_rate),
        p_detect=0.95, clutter_density=5.0, clutter_range=(500.0, 13000.0), scan_period=2.5,
    )  # fmt: skip
    pop = TargetPopulation(targets=4, births_per_scan=0.0, mean_life=0.0, crossings=0,
                           range_limits=(2000.0, 12000.0))  # fmt: skip
    return simulate_multitarget(pop, radar, 100.0, np.random.default_rng(seed))


@pytest.mark.parametrize("name", sorted(METHODS))
def test_every_registered_method_is_a_per_track_filter(name):
    """Issue 15: any registered method (the IMM and the sources' methods included) tracks
    unlabelled plots with clutter, given only the sensor noise."""
    needs_rr = getattr(method_class(name), "needs_range_rate", False)
    sim = _rr_scenario() if needs_rr else _scenario(targets=4, duration=100.0)
    table = {"sigma_range_m": 15.0, "sigma_azimuth_deg": 0.3}
    if needs_rr:
        table["sigma_range_rate_mps"] = 0.5
    method, _ = per_track_filter(name, table, 2, needs_rr, scan_period(sim.plots.t))
    out = MultiTargetTracker(method.filter, sensor_noise(table)).run(method.prepare(sim.plots))
    s = _score(sim, out)
    late = sim.scan_times >= 30.0
    assert s.scans.n_missed[late].mean() < 0.5  # every target held after initiation
    assert s.scans.n_false[late].mean() < 0.5
    assert np.isfinite(out.columns["x_m"]).all() and np.isfinite(out.columns["vx_mps"]).all()
