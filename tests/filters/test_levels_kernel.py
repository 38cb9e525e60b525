"""The fused kernels of the level IMM (seatrack.filters.levels_kernel) against the NumPy
composition they replace: IMM mixing / Kalman prediction / combination gufuncs, the polar
measurement, :func:`mixture_update` per level, the IRLS updates of
:mod:`seatrack.filters.robust_baselines` with per-channel thresholds / degrees of freedom --
on random
batches in 2-D and 3-D, with range rate, contaminated patterns, learnt outlier
probabilities, an unusable plot and a non-positive-definite innovation covariance."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from seatrack import kalman
from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import usable
from seatrack.filters.base import wrap_angles
from seatrack.filters.ekf import sensor_state
from seatrack.filters.imm import IMMState
from seatrack.filters.imm import combine
from seatrack.filters.imm import mix
from seatrack.filters.levels import ContaminatedConfig
from seatrack.filters.levels import ContaminatedLevels
from seatrack.filters.levels import HuberLevels
from seatrack.filters.levels import HuberLevelsConfig
from seatrack.filters.levels import LevelIMM
from seatrack.filters.levels import LevelIMMConfig
from seatrack.filters.levels import RamazanovLevels
from seatrack.filters.levels import StudentTLevels
from seatrack.filters.levels import StudentTLevelsConfig
from seatrack.filters.levels import contaminated_loglik
from seatrack.filters.levels import level_noise
from seatrack.filters.levels import mixture_update
from seatrack.filters.levels_kernel import Rule
from seatrack.filters.robust_baselines import HuberConfig
from seatrack.filters.robust_baselines import StudentTConfig
from seatrack.filters.robust_baselines import reweighted_update
from seatrack.models.measurement import polar_measurement
from seatrack.models.motion import along_track_shape
from seatrack.models.motion import cv_matrices

SENSOR = SensorNoise(15.0, math.radians(0.4), sigma_elevation=math.radians(0.4),
                     sigma_range_rate=1.5)  # fmt: skip


def _batch(f: Any, B: int, seed: int, d: int, rr: bool, t: float = 10.0) -> tuple[Any, Plots]:
    """A random prior state of ``B`` tracks (distinct level states, probabilities, outlier
    probabilities) and plots near it; plot 1 is unusable, track 2's covariance makes the
    innovation covariance indefinite."""
    rng = np.random.default_rng(seed)
    n, M = 2 * d, f.M
    base = np.concatenate([rng.uniform(-2e4, 2e4, (B, d)), rng.normal(0, 20, (B, d))], -1)
    if d == 3:
        base[:, 2] = rng.uniform(100, 3e3, B)
    X = base[:, None] + rng.normal(size=(B, M, n)) * np.r_[[40.0] * d, [3.0] * d]
    A = rng.normal(size=(B, M, n, n))
    PP = A @ np.swapaxes(A, -1, -2) * 20 + np.diag([900.0] * d + [25.0] * d)
    PP[2] = -1e9 * np.eye(n)
    mu = rng.dirichlet(np.ones(M), B)
    st = f.initiate(np.full(B, t), X[:, 0], PP[:, 0])
    eps = rng.uniform(0.02, 0.3, (B, f.r.size))
    st = st.replace(aux={**st.aux, "X": X, "PP": PP, "mu": mu, "eps": eps})
    truth = base + rng.normal(size=(B, n)) * np.r_[[60.0] * d, [2.0] * d]
    sens = np.zeros((B, 3))
    sens[:, :2] = rng.normal(0, 500, (B, 2))
    svel = np.zeros((B, 3))
    svel[:, :2] = rng.normal(0, 5, (B, 2))
    z, _ = polar_measurement(truth, np.concatenate([sens[:, :d], svel[:, :d]], -1), d, True)
    z[rng.random(B) < 0.3, 0] += 2e3  # gross range outliers
    z[1, 0] = np.nan
    plots = Plots(np.full(B, t + 2.0), z[:, 0], z[:, 1], z[:, 2] if d == 3 else None,
                  z[:, -1] if rr else None, sensor=sens, sensor_vel=svel)  # fmt: skip
    return st, plots


@dataclass
class _Res:
    x: Any
    P: Any
    y: Any


def _gauss_update(x: Any, P: Any, z: Any, hx: Any, H: Any, R: Any, angular: Any, check: Any):
    """The diagonal-R extended update through :func:`mixture_update` (as main's levels)."""
    ang = np.zeros(z.shape[-1])  # robust_baselines' range and bearing; range rate is linear
    ang[: len(angular)] = angular
    y = wrap_angles(z - hx, ang)
    xo, Po, _, _ = mixture_update(x, P, y, H, np.diagonal(R, axis1=-2, axis2=-1))
    return _Res(xo, Po, y)


def _reference_update(f: Any, st: Any, plots: Plots) -> dict[str, Any]:
    """One update of every level, then the IMM combination, in NumPy."""
    a = st.aux
    X, PP = a["X"], a["PP"]
    B, M, n = X.shape
    s = np.repeat(sensor_state(plots, f.d), M, 0)
    hx, H = polar_measurement(X.reshape(B * M, n), s, f.d, f.range_rate)
    hx, H = hx.reshape(B, M, -1), H.reshape(B, M, -1, n)
    z, ok = usable(plots.polar(f.range_rate), hx[:, 0])
    with np.errstate(all="ignore"):
        y = wrap_angles(z[:, None] - hx, f.angular)
        G, logp, k = f._patterns(a["eps"])
        pat = (G, logp[:, None, :], k)
        if f.rule == Rule.MIXTURE:
            Xo, Po, ll, out = mixture_update(X, PP, y, H, f.r, pat)
        elif f.rule == Rule.RAMAZANOV:
            delta = f._par
            hph = np.einsum("...ij,...jk,...ik->...i", H, PP, H)
            big = y**2 / (hph + f.r) > delta
            r = np.where(big, y**2 / delta - hph, f.r)
            Xo, Po, _, _ = mixture_update(X, PP, y, H, r)
            ll, out = contaminated_loglik(y, H, PP, f.r, pat), big.astype(float)
        else:
            it = int(f._par[0])
            thr = np.broadcast_to(f._thresholds(a["eps"])[:, None], y.shape)  # per channel
            zz = np.broadcast_to(z[:, None], hx.shape)
            huber = f.rule == Rule.HUBER
            cfg = HuberConfig(1.0, it) if huber else StudentTConfig(nu=1.0, iterations=it)
            object.__setattr__(cfg, "c" if huber else "nu", thr)  # per channel, past the check
            res, _ = reweighted_update(X, PP, zz, hx, H, f.R, f.r, cfg, False, _gauss_update)
            Xo, Po = res.x, res.P
            _, _, ll, out = mixture_update(X, PP, y, H, f.r, pat)
        ll = np.where(ok[:, None], ll, 0.0)
        mu, x, P, tot = combine(Xo, Po, a["mu"], ll, np.arange(n))
        yc, S = f.innovation(st, plots)
        nis = kalman.mahalanobis(yc, S)
    outl = np.einsum("bj,bjm->bm", mu, out)
    return {"X": Xo, "PP": Po, "mu": mu, "x": x, "P": P, "tot": tot, "outlier": outl,
            "nis": nis, "ok": ok}  # fmt: skip


def _assert_covariances_close(got: Any, want: Any, key: str) -> None:
    """Covariances equal to ``1e-12`` of each entry's scale ``sqrt(P_ii P_jj)``: a small
    cross term of two large variances carries the rounding of the products that make it
    (the Huber / Student-t updates reach the same matrix by a Cholesky form in the kernel
    and by the reference's full-state iterations)."""
    d = np.sqrt(np.abs(np.diagonal(want, axis1=-2, axis2=-1)))
    scale = d[..., :, None] * d[..., None, :]
    err = np.abs(got - want) / scale
    assert np.all(err <= 1e-12), f"{key}: largest error {err.max():.3g} of sqrt(P_ii P_jj)"


_CASES = [
    (LevelIMM, LevelIMMConfig(), 2, False),
    (LevelIMM, LevelIMMConfig(outlier_probability=0.0, along_track_ratio=1.0), 3, False),
    (LevelIMM, LevelIMMConfig(use_range_rate=True), 3, True),
    (ContaminatedLevels, ContaminatedConfig(), 2, True),
    (ContaminatedLevels, ContaminatedConfig(accel_levels=(0.1, 5.0), sojourn_times=(60.0, 10.0)),
     3, True),
    (RamazanovLevels, None, 2, False),
    (RamazanovLevels, None, 2, True),
    (HuberLevels, None, 2, False),
    (HuberLevels, None, 2, True),
    (HuberLevels, HuberLevelsConfig(c=1.345), 2, False),
    (StudentTLevels, None, 2, False),
    (StudentTLevels, None, 2, True),
    (StudentTLevels, StudentTLevelsConfig(adapt_nu=False), 2, False),
]  # fmt: skip


@pytest.mark.parametrize("cls, cfg, d, rr", _CASES)
def test_update_matches_the_numpy_composition(cls, cfg, d, rr):
    f = cls(cfg, SENSOR, d, rr)
    st, plots = _batch(f, 12, seed=d + 10 * int(rr), d=d, rr=rr)
    ref = _reference_update(f, st, plots)
    new = f.update(st, plots)
    ok = ref["ok"] & np.isfinite(ref["tot"]) & np.isfinite(ref["x"]).all(-1)
    assert not ok[1] and not ok[2]  # the unusable plot, the indefinite covariance
    assert np.array_equal(new.status == PlotStatus.UPDATED, ok)
    assert np.all(new.status[~ok] == PlotStatus.REJECTED)
    assert np.array_equal(new.x[~ok], st.x[~ok]) and np.array_equal(new.P[~ok], st.P[~ok])
    # every usable plot: the same numbers (the NIS differs in the summation order of H P H^T)
    for key, got in (("x", new.x), ("tot", new.log_likelihood), ("X", new.aux["X"]),
                     ("mu", new.aux["mu"]), ("outlier", new.aux["outlier"])):  # fmt: skip
        np.testing.assert_allclose(got[ok], ref[key][ok], rtol=1e-12, atol=1e-12, err_msg=key)
    for key, got in (("P", new.P), ("PP", new.aux["PP"])):
        _assert_covariances_close(got[ok], ref[key][ok], key)
    np.testing.assert_allclose(new.nis[ok], ref["nis"][ok], rtol=1e-10)
    assert np.allclose(new.P[ok], np.swapaxes(new.P[ok], -1, -2), rtol=0, atol=0)
    assert np.all(np.linalg.eigvalsh(new.P[ok]) > 0)


@pytest.mark.parametrize("cls, cfg, d, rr", _CASES[:5])
def test_predict_matches_the_numpy_composition(cls, cfg, d, rr):
    f = cls(cfg, SENSOR, d, rr)
    st, _ = _batch(f, 9, seed=3, d=d, rr=rr)
    for t in (np.full(9, 12.5), 10.0 + np.linspace(0.5, 4.0, 9)):  # regular / irregular scans
        a = st.aux
        dt = t - st.t
        q, PI = level_noise(f.config, dt)
        X0, P0, c = mix(IMMState(a["X"], a["PP"], a["mu"]), PI, np.ones((f.M, 2 * d)))
        F, _ = cv_matrices(dt, 1.0, d)
        F = F[:, None] if F.ndim == 3 else F
        shape = along_track_shape(st.x[:, d:], st.P[:, d:, d:], f.config.along_track_ratio)
        blk = np.stack([np.stack([dt**3 / 3, dt**2 / 2], -1), np.stack([dt**2 / 2, dt], -1)], -2)
        Q1 = np.stack([np.kron(g, a) for g, a in zip(blk, shape)])[:, None]  # per track
        X, PP = kalman.predict(X0, P0, F, q[:, :, None, None] * Q1)
        _, x, P, _ = combine(X, PP, c, np.zeros_like(c), np.arange(2 * d))
        new = f.predict(st, t)
        for got, want in ((new.x, x), (new.P, P), (new.aux["X"], X), (new.aux["PP"], PP),
                          (new.aux["mu"], c), (new.aux["q"], q)):  # fmt: skip
            assert np.array_equal(got, want)
        assert np.all(new.status == PlotStatus.PREDICTED)


def test_gaussian_levels_are_the_kalman_update():
    """epsilon = 0: the update of every level is the (Joseph-form) EKF update."""
    f = LevelIMM(LevelIMMConfig(outlier_probability=0.0), SENSOR)
    assert f.patterns is None
    st, plots = _batch(f, 6, seed=4, d=2, rr=False)
    new = f.update(st, plots)
    X, PP = st.aux["X"], st.aux["PP"]
    B, M, n = X.shape
    s = np.repeat(sensor_state(plots, 2), M, 0)
    hx, H = polar_measurement(X.reshape(B * M, n), s, 2)
    z = plots.polar(False)[:, None]
    with np.errstate(all="ignore"):
        ref = kalman.extended_update(X, PP, z, hx.reshape(B, M, 2), H.reshape(B, M, 2, n), f.R,
                                     f.angular, check=False)  # fmt: skip
    ok = new.status == PlotStatus.UPDATED
    assert ok.sum() >= 4
    assert np.allclose(new.aux["X"][ok], ref.x[ok], rtol=1e-12, atol=1e-9)
    assert np.allclose(new.aux["PP"][ok], ref.P[ok], rtol=1e-9, atol=1e-9)
