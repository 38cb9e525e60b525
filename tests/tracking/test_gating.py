"""Gating: the KD-tree pre-gate never drops a pair the Mahalanobis gate would keep."""

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal

from seatrack.filters.base import Plots, SensorNoise, TrackState, plot_gaussian
from seatrack.filters.ekf import EKF, EKFConfig
from seatrack.tracking.gating import gate, gate_threshold, nis_logpdf, pregate

SN = SensorNoise(sigma_range=15.0, sigma_azimuth=np.radians(0.5))


def _tracks_and_plots(seed, n_tracks=60, n_plots=400, spread=20000.0):
    rng = np.random.default_rng(seed)
    pos = rng.uniform(-spread, spread, (n_tracks, 2))
    vel = rng.normal(0, 8, (n_tracks, 2))
    P = np.zeros((n_tracks, 4, 4))
    s = rng.uniform(20, 400, n_tracks)
    P[:, 0, 0] = P[:, 1, 1] = s**2
    P[:, 2, 2] = P[:, 3, 3] = 25.0
    state = TrackState.new(np.zeros(n_tracks), np.concatenate([pos, vel], 1), P)
    # plots: some near the tracks, the rest anywhere
    near = pos[rng.integers(0, n_tracks, n_plots // 2)] + rng.normal(0, 300, (n_plots // 2, 2))
    far = rng.uniform(-spread, spread, (n_plots - n_plots // 2, 2))
    xy = np.concatenate([near, far])
    plots = Plots(
        np.zeros(n_plots),
        np.hypot(xy[:, 0], xy[:, 1]),
        np.arctan2(xy[:, 0], xy[:, 1]) % (2 * np.pi),
    )
    return state, plots


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pregate_keeps_every_pair_that_passes_the_gate(seed):
    state, plots = _tracks_and_plots(seed)
    flt = EKF(EKFConfig(), SN)
    p = 0.999
    cand = gate(flt, state, plots, plots.positions(), SN, p)
    # brute force: every pair through the filter's innovation
    B, N = len(state), len(plots)
    ti, pj = np.repeat(np.arange(B), N), np.tile(np.arange(N), B)
    y, S = flt.innovation(state.take(ti), plots.take(pj))
    nis = np.einsum("ki,ki->k", y, np.linalg.solve(S, y[..., None])[..., 0])
    keep = nis <= chi2.ppf(p, 2)
    assert keep.sum() > 20  # the test has pairs to find
    want = set(zip(ti[keep].tolist(), pj[keep].tolist(), strict=True))
    got = set(zip(cand.track.tolist(), cand.plot.tolist(), strict=True))
    assert got == want
    order = np.lexsort((pj[keep], ti[keep]))
    mine = np.lexsort((cand.plot, cand.track))
    assert np.allclose(cand.nis[mine], nis[keep][order])


def test_pregate_is_radius_search():
    tp = np.array([[0.0, 0.0], [100.0, 0.0]])
    pp = np.array([[5.0, 0.0], [100.0, 30.0], [500.0, 0.0]])
    ti, pj = pregate(tp, np.array([10.0, 40.0]), pp)
    assert sorted(zip(ti.tolist(), pj.tolist(), strict=True)) == [(0, 0), (1, 1)]
    ti, pj = pregate(np.zeros((0, 2)), np.zeros(0), pp)
    assert ti.size == pj.size == 0


def test_nis_logpdf_matches_scipy_and_rejects_bad_covariances():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(5, 3, 3))
    S = A @ A.transpose(0, 2, 1) + np.eye(3)
    y = rng.normal(size=(5, 3))
    nis, lg = nis_logpdf(y, S)
    for k in range(5):
        assert lg[k] == pytest.approx(multivariate_normal(np.zeros(3), S[k]).logpdf(y[k]))
        assert nis[k] == pytest.approx(y[k] @ np.linalg.solve(S[k], y[k]))
    S[1] = -np.eye(3)
    S[2, 0, 0] = np.nan
    nis, _ = nis_logpdf(y, S)
    assert np.isinf(nis[1]) and np.isinf(nis[2]) and np.isfinite(nis[[0, 3, 4]]).all()


def test_gate_threshold():
    assert gate_threshold(0.99, 2) == pytest.approx(9.2103, abs=1e-4)
    with pytest.raises(ValueError, match="gate probability"):
        gate_threshold(1.0, 2)


def test_gate_uses_the_plot_gaussian_of_the_sensor():
    """A plot at a track's position passes; one 10 sigma away does not."""
    p = Plots(
        np.zeros(2), np.array([10000.0, 10000.0]), np.array([0.5, 0.5 + 10 * SN.sigma_azimuth])
    )
    x, P = plot_gaussian(p.take([0]), SN, 5.0)
    state = TrackState.new([0.0], x, P)
    cand = gate(EKF(EKFConfig(), SN), state, p, p.positions(), SN, 0.999)
    assert cand.plot.tolist() == [0]
