"""Gating: the KD-tree pre-gate never drops a pair the Mahalanobis gate would keep."""

import numpy as np
import pytest
from scipy.stats import chi2
from scipy.stats import multivariate_normal

from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import plot_gaussian
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig
from seatrack.tracking.gating import gate
from seatrack.tracking.gating import gate_threshold
from seatrack.tracking.gating import nis_logpdf
from seatrack.tracking.gating import pregate

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


def test_pregate_brute_force_equals_the_kd_tree():
    rng = np.random.default_rng(7)
    tp = rng.uniform(0, 5000, (30, 2))
    pp = rng.uniform(0, 5000, (200, 2))  # 6000 pairs: the KD-tree path
    radius = rng.uniform(100, 600, 30)
    ti, pj = pregate(tp, radius, pp)
    small_t, small_p = pregate(tp[:10], radius[:10], pp[:100])  # 1000 pairs: brute force
    want = {(i, j) for i in range(30) for j in range(200)
            if np.linalg.norm(tp[i] - pp[j]) <= radius[i]}  # fmt: skip
    assert set(zip(ti.tolist(), pj.tolist(), strict=True)) == want
    assert set(zip(small_t.tolist(), small_p.tolist(), strict=True)) == {
        (i, j) for i, j in want if i < 10 and j < 100
    }
    assert np.all(np.diff(small_t) >= 0)  # in track order


def test_innovation_space_is_measured():
    from seatrack.filters import registry
    from seatrack.tracking.gating import CARTESIAN
    from seatrack.tracking.gating import POLAR
    from seatrack.tracking.gating import innovation_space

    spaces = {m: innovation_space(registry.build(m).filter, SN)
              for m in ("ekf", "imm", "mm", "mm-spec", "turning", "ekf-rb")}  # fmt: skip
    # mm's default is a level IMM on the polar plots; mm-spec converts them (its source)
    assert spaces == {"ekf": POLAR, "imm": CARTESIAN, "mm": POLAR, "mm-spec": CARTESIAN,
                      "turning": POLAR, "ekf-rb": POLAR}  # fmt: skip
    assert innovation_space(registry.build("ekf", d=3).filter, SN) == POLAR
    assert innovation_space(registry.build("imm", d=3).filter, SN) == CARTESIAN

    class Scaled(EKF):
        def innovation(self, state, plots):
            y, S = super().innovation(state, plots)
            return 7.0 * y, 49.0 * S

    with pytest.raises(ValueError, match="neither polar nor"):
        innovation_space(Scaled(EKFConfig(), SN), SN)


def test_cartesian_likelihoods_are_carried_to_the_polar_space():
    """The same plot under a polar and a Cartesian filter: densities differ by |J| = r."""
    from seatrack.filters import registry
    from seatrack.tracking.gating import CARTESIAN
    from seatrack.tracking.gating import log_jacobian

    p = Plots(np.zeros(1), np.array([8000.0]), np.array([0.3]))
    x, P = plot_gaussian(p, SN, 5.0)
    P[:, :2, :2] *= 4.0
    for name in ("ekf", "imm"):
        flt = registry.build(name, {"sigma_range_m": 15.0, "sigma_azimuth_deg": 0.5}).filter
        state = flt.predict(flt.initiate(np.zeros(1), x, P), np.ones(1))
        space = "polar" if name == "ekf" else CARTESIAN
        c = gate(flt, state, p, p.positions(), SN, 0.999, space)
        if name == "ekf":
            ekf_log_g = c.log_g[0]
        else:
            assert c.log_g[0] == pytest.approx(ekf_log_g, abs=0.05)  # same density, 1e-2
    assert log_jacobian(CARTESIAN, p)[0] == pytest.approx(np.log(8000.0))
