"""Tests of the multiple-model filter with range rate (spec multimodel.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import logsumexp

from seatrack import kalman
from seatrack.evaluate.metrics import chi2_interval
from seatrack.evaluate.metrics import nees
from seatrack.filters.multimodel import DEFAULT_ALPHAS
from seatrack.filters.multimodel import MultiModelConfig
from seatrack.filters.multimodel import MultiModelFilter
from seatrack.filters.multimodel import MultiModelState
from seatrack.filters.multimodel import range_rate_row
from seatrack.models import numerical_jacobian
from seatrack.models.measurement import range_rate
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory


# ---------------------------------------------------------------------------
# Independent reference: the spec's steps 1-11 written with explicit matrices
# ---------------------------------------------------------------------------
def reference_step(x, P, beta, T, Z, R, rho, cfg, d, spos=None, svel=None):
    n = 2 * d
    I = np.eye(d)
    Phi = np.block([[I, T * I], [np.zeros((d, d)), I]])
    Gam = np.vstack([T**2 / 2 * I, T * I])
    H = np.hstack([I, np.zeros((d, d))])
    alphas = np.asarray(cfg.alphas, float)[:, :d]
    pi = cfg.transition_matrix()
    Q = cfg.process_noise(d)
    spos = np.zeros(d) if spos is None else spos
    svel = np.zeros(d) if svel is None else svel
    # 1
    xa = np.array([Phi @ x + Gam @ a for a in alphas])
    Pb = Phi @ P @ Phi.T + Gam @ Q @ Gam.T
    # 2
    S = H @ Pb @ H.T + R
    Si = np.linalg.inv(S)
    ll = np.array(
        [
            -0.5 * ((Z - H @ xa_) @ Si @ (Z - H @ xa_) + np.log(np.linalg.det(2 * np.pi * S)))
            for xa_ in xa
        ]
    )
    # 3
    if cfg.use_range_rate and np.isfinite(rho):
        for a in range(len(alphas)):
            rhat, h = range_rate_row(xa[a], spos, svel)
            s = h @ Pb @ h + cfg.sigma_range_rate**2
            ll[a] += -0.5 * ((rho - rhat) ** 2 / s + np.log(2 * np.pi * s))
    # 4
    bm = pi @ beta
    lw = ll + np.log(bm)
    b = np.exp(lw - logsumexp(lw))
    # 5-7
    K = Pb @ H.T @ Si
    u = b @ alphas
    xt = Phi @ x + Gam @ u
    xpost = xt + K @ (Z - H @ xt)
    A = np.eye(n) - K @ H
    Pa = A @ Pb
    # 8
    C = sum(b[a] * np.outer(alphas[a] - u, alphas[a] - u) for a in range(len(alphas)))
    Ppost = Pa + (A @ Gam @ C @ Gam.T @ A.T if cfg.integrated_covariance else 0)
    # 10-11 (the prediction for this scan made at the previous one: mu = pi beta_{k-1})
    ub = bm @ alphas
    xpred = Phi @ x + Gam @ ub
    Cm = sum(bm[a] * np.outer(alphas[a] - ub, alphas[a] - ub) for a in range(len(alphas)))
    Ppred = Pb + (Gam @ Cm @ Gam.T if cfg.integrated_covariance else 0)
    return xpost, Ppost, b, xpred, Ppred, logsumexp(lw), lw


def random_case(rng, d, N=5):
    n = 2 * d
    x = np.concatenate([rng.uniform(5e3, 3e4, d), rng.uniform(-200, 200, d)])
    A = rng.standard_normal((n, n))
    P = A @ A.T * 50 + np.eye(n) * 100
    beta = rng.dirichlet(np.ones(N))
    B = rng.standard_normal((d, d))
    R = B @ B.T * 400 + np.eye(d) * 900
    Z = x[:d] + 1.3 * x[d:] + rng.normal(0, 50, d)
    rr = float(range_rate(x[:d], x[d:])) + rng.normal(0, 20)
    return x, P, beta, Z, R, rr


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("use_rr", [True, False])
@pytest.mark.parametrize("integ", [True, False])
def test_step_matches_reference(d, use_rr, integ):
    rng = np.random.default_rng(10 + d + 2 * use_rr + 4 * integ)
    cfg = MultiModelConfig(
        use_range_rate=use_rr,
        integrated_covariance=integ,
        sigma_w=3.0,
        sigma_range_rate=2.0,
        p_stay=0.8,
    )
    flt = MultiModelFilter(cfg, d=d)
    x, P, beta, Z, R, rr = random_case(rng, d)
    spos, svel = rng.normal(0, 500, d), rng.normal(0, 10, d)
    step = flt.step(MultiModelState(x, P, beta), 1.3, Z, R, rr, spos, svel)
    ref = reference_step(x, P, beta, 1.3, Z, R, rr, cfg, d, spos, svel)
    np.testing.assert_allclose(step.x, ref[0], rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(step.P, ref[1], rtol=1e-7, atol=1e-6)
    np.testing.assert_allclose(step.beta, ref[2], rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(step.x_pred, ref[3], rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(step.P_pred, ref[4], rtol=1e-10, atol=1e-6)
    np.testing.assert_allclose(step.log_likelihood, ref[5], rtol=1e-9)
    assert np.allclose(step.P, step.P.T)
    assert np.all(np.linalg.eigvalsh(step.P) > 0)


def test_range_rate_changes_reliabilities_only_not_the_gain():
    rng = np.random.default_rng(3)
    x, P, beta, Z, R, rr = random_case(rng, 3)
    on = MultiModelFilter(MultiModelConfig(use_range_rate=True))
    off = MultiModelFilter(MultiModelConfig(use_range_rate=False))
    s_on = on.step(MultiModelState(x, P, beta), 1.0, Z, R, rr)
    s_off = off.step(MultiModelState(x, P, beta), 1.0, Z, R, rr)
    assert not np.allclose(s_on.beta, s_off.beta)
    # a NaN range rate is the same as switching it off
    s_nan = on.step(MultiModelState(x, P, beta), 1.0, Z, R, np.nan)
    np.testing.assert_allclose(s_nan.beta, s_off.beta)
    np.testing.assert_allclose(s_nan.x, s_off.x)


# ---------------------------------------------------------------------------
# Range-rate Jacobian (step 3)
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("d", [2, 3])
def test_range_rate_jacobian_numerical(d):
    rng = np.random.default_rng(5)
    for _ in range(20):
        x = np.concatenate([rng.uniform(-4e4, 4e4, d), rng.uniform(-300, 300, d)])
        s, sv = rng.normal(0, 1e3, d), rng.normal(0, 15, d)
        rho, h = range_rate_row(x, s, sv)
        Jn = numerical_jacobian(lambda xx: np.atleast_1d(range_rate_row(xx, s, sv)[0]), x)[0]
        np.testing.assert_allclose(h, Jn, rtol=1e-6, atol=1e-10)
        # the spec's closed form h^a = [(v - rho r / R)^T / R, r^T / R]
        r, v = x[:d] - s, x[d:] - sv
        Rn = np.linalg.norm(r)
        np.testing.assert_allclose(h, np.concatenate([(v - rho * r / Rn) / Rn, r / Rn]), rtol=1e-12)


# ---------------------------------------------------------------------------
# Eq. (81): one reliability equal to 1 -> single-model covariances
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("a", [0, 2, 4])
def test_integrated_covariance_reduces_to_single_model(a):
    rng = np.random.default_rng(7 + a)
    x, P, _, Z, R, rr = random_case(rng, 3)
    prior = np.eye(5)[a]
    cfg = MultiModelConfig(transition=np.eye(5), prior=prior, sigma_w=4.0)
    flt = MultiModelFilter(cfg)
    T = 2.0
    step = flt.step(MultiModelState(x, P, prior), T, Z, R, rr)
    assert step.beta[a] == 1.0 and step.beta.sum() == 1.0
    # the single model a: a Kalman filter with known input alpha_a
    F = np.block([[np.eye(3), T * np.eye(3)], [np.zeros((3, 3)), np.eye(3)]])
    G = np.vstack([T**2 / 2 * np.eye(3), T * np.eye(3)])
    xa = F @ x + G @ np.asarray(DEFAULT_ALPHAS[a])
    Pb = F @ P @ F.T + G @ cfg.process_noise(3) @ G.T
    ref = kalman.update(xa, Pb, Z, np.hstack([np.eye(3), np.zeros((3, 3))]), R)
    np.testing.assert_allclose(step.P, ref.P, rtol=1e-10, atol=1e-8)
    np.testing.assert_allclose(step.x, ref.x, rtol=1e-12, atol=1e-7)
    np.testing.assert_allclose(step.P_pred, Pb, rtol=1e-12, atol=1e-8)
    np.testing.assert_allclose(step.x_pred, xa, rtol=1e-12)
    off = MultiModelFilter(
        MultiModelConfig(
            transition=np.eye(5), prior=prior, sigma_w=4.0, integrated_covariance=False
        )
    )
    s_off = off.step(MultiModelState(x, P, prior), T, Z, R, rr)
    np.testing.assert_allclose(step.P, s_off.P, rtol=1e-12, atol=1e-9)


def test_integrated_covariance_is_mixture_moment():
    """Step 8 = covariance of the beta-mixture of the per-model posteriors; step 11 = of the
    mu-mixture of the per-model predictions."""
    rng = np.random.default_rng(11)
    x, P, beta, Z, R, rr = random_case(rng, 3)
    cfg = MultiModelConfig(p_stay=0.7, sigma_w=3.0)
    flt = MultiModelFilter(cfg)
    T = 1.5
    step = flt.step(MultiModelState(x, P, beta), T, Z, R, rr)
    F = np.block([[np.eye(3), T * np.eye(3)], [np.zeros((3, 3)), np.eye(3)]])
    G = np.vstack([T**2 / 2 * np.eye(3), T * np.eye(3)])
    H = np.hstack([np.eye(3), np.zeros((3, 3))])
    Pb = F @ P @ F.T + G @ cfg.process_noise(3) @ G.T
    al = np.asarray(DEFAULT_ALPHAS)
    posts = [kalman.update(F @ x + G @ a, Pb, Z, H, R) for a in al]
    xm = sum(b * p.x for b, p in zip(step.beta, posts, strict=True))
    Pm = sum(
        b * (p.P + np.outer(p.x - xm, p.x - xm)) for b, p in zip(step.beta, posts, strict=True)
    )
    np.testing.assert_allclose(step.x, xm, rtol=1e-12, atol=1e-7)
    np.testing.assert_allclose(step.P, Pm, rtol=1e-8, atol=1e-6)
    mu = cfg.transition_matrix() @ beta
    preds = [F @ x + G @ a for a in al]
    xp = sum(m * p for m, p in zip(mu, preds, strict=True))
    Pp = sum(m * (Pb + np.outer(p - xp, p - xp)) for m, p in zip(mu, preds, strict=True))
    np.testing.assert_allclose(step.x_pred, xp, rtol=1e-12, atol=1e-7)
    np.testing.assert_allclose(step.P_pred, Pp, rtol=1e-10, atol=1e-6)


# ---------------------------------------------------------------------------
# Log-space reliabilities
# ---------------------------------------------------------------------------
def test_reliabilities_no_nan_when_likelihoods_underflow():
    rng = np.random.default_rng(2)
    x, P, beta, Z, R, rr = random_case(rng, 3)
    cfg = MultiModelConfig()
    flt = MultiModelFilter(cfg)
    Zfar = Z + np.array([3e6, -2e6, 1e6])  # every f_a underflows to 0 in linear space
    step = flt.step(MultiModelState(x, P, beta), 1.0, Zfar, R, rr + 5e4)
    ref = reference_step(x, P, beta, 1.0, Zfar, R, rr + 5e4, cfg, 3)
    with np.errstate(under="ignore", divide="ignore", invalid="ignore"):
        f = np.exp(ref[6])  # linear-space f_a f^D_a beta^-_a
        naive = f / f.sum()
    assert np.all(f == 0.0) and np.all(np.isnan(naive))  # what linear space would give
    assert np.all(np.isfinite(step.beta)) and np.isclose(step.beta.sum(), 1.0)
    np.testing.assert_allclose(step.beta, ref[2], rtol=1e-6, atol=1e-300)
    assert np.all(np.isfinite(step.x)) and np.all(np.isfinite(step.P))
    assert step.log_likelihood < -1e9


def test_reliabilities_keep_prior_when_log_likelihoods_are_minus_inf():
    rng = np.random.default_rng(4)
    x, P, beta, Z, R, rr = random_case(rng, 3)
    cfg = MultiModelConfig()
    with np.errstate(over="ignore"):  # the NIS overflows to inf on purpose
        step = MultiModelFilter(cfg).step(MultiModelState(x, P, beta), 1.0, Z + 1e200, R, rr)
    assert np.all(np.isfinite(step.beta))
    np.testing.assert_allclose(step.beta, cfg.transition_matrix() @ beta)
    assert step.log_likelihood == -np.inf


def test_zero_prior_model_stays_zero_without_nan():
    rng = np.random.default_rng(6)
    x, P, _, Z, R, rr = random_case(rng, 3)
    prior = np.array([0.0, 0.0, 0.5, 0.5, 0.0])
    cfg = MultiModelConfig(transition=np.eye(5), prior=prior)
    step = MultiModelFilter(cfg).step(MultiModelState(x, P, prior), 1.0, Z, R, rr)
    assert np.all(np.isfinite(step.beta))
    assert step.beta[0] == 0.0 and step.beta[4] == 0.0


# ---------------------------------------------------------------------------
# Batch, missing plots, configuration
# ---------------------------------------------------------------------------
def test_batch_equals_single_runs():
    rng = np.random.default_rng(8)
    cases = [random_case(rng, 3) for _ in range(4)]
    flt = MultiModelFilter(MultiModelConfig(p_stay=0.85))
    X, P, B, Z, R, RR = (np.array([c[i] for c in cases]) for i in range(6))
    T = np.array([1.0, 2.0, 3.0, 4.0])
    batch = flt.step(MultiModelState(X, P, B), T, Z, R, RR)
    for i in range(4):
        one = flt.step(MultiModelState(X[i], P[i], B[i]), T[i], Z[i], R[i], RR[i])
        np.testing.assert_allclose(batch.x[i], one.x, rtol=1e-14)
        np.testing.assert_allclose(batch.P[i], one.P, rtol=1e-14)
        np.testing.assert_allclose(batch.beta[i], one.beta, rtol=1e-14)


def test_missing_plot_is_pure_prediction():
    rng = np.random.default_rng(9)
    x, P, beta, Z, R, rr = random_case(rng, 3)
    flt = MultiModelFilter()
    step = flt.step(MultiModelState(x, P, beta), 2.0, np.full(3, np.nan), R, rr)
    np.testing.assert_allclose(step.x, step.x_pred)
    np.testing.assert_allclose(step.P, step.P_pred)
    np.testing.assert_allclose(step.beta, flt.pi @ beta)
    assert np.isnan(step.log_likelihood)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"p_stay": 1.5},
        {
            "transition": [[0.9, 0.1], [0.2, 0.8]],
            "alphas": [(0, 0, 0), (1, 0, 0)],
            "names": ["a", "b"],
        },
        {"prior": [1, 0, 0, 0, 0.5]},
        {"names": ["a"]},
        {"sigma_range_rate": 0.0},
    ],
)
def test_config_errors(kwargs):
    with pytest.raises(ValueError):
        MultiModelConfig(**kwargs)


def test_transition_columns_sum_to_one():
    pi = MultiModelConfig(p_stay=0.6).transition_matrix()
    np.testing.assert_allclose(pi.sum(axis=0), 1.0)
    assert pi[0, 0] == 0.6 and np.isclose(pi[1, 0], 0.1)


# ---------------------------------------------------------------------------
# Consistency (seeded Monte Carlo on the filter's own model)
# ---------------------------------------------------------------------------
def _own_model_data(runs=300, K=70, T=1.0, sw=2.0, seed=12):
    """Truth drawn from the model (constant input alpha = 10 g East plus white
    acceleration sigma_w), linear-Gaussian position plots, Gaussian range-rate noise."""
    rng = np.random.default_rng(seed)
    F = np.block([[np.eye(3), T * np.eye(3)], [np.zeros((3, 3)), np.eye(3)]])
    G = np.vstack([T**2 / 2 * np.eye(3), T * np.eye(3)])
    alpha = np.asarray(DEFAULT_ALPHAS[1])
    x = np.zeros((runs, K, 6))
    x[:, 0] = [2e4, 3e4, 2e3, -100.0, 150.0, 0.0]
    x[:, 0] += rng.normal(0, 30, (runs, 6))
    for k in range(1, K):
        w = rng.normal(0, sw, (runs, 3))
        x[:, k] = x[:, k - 1] @ F.T + (G @ (alpha[:, None] + w.T)).T
    Rm = np.diag([40.0, 60.0, 50.0]) ** 2
    Z = x[..., :3] + rng.normal(0, 1, (runs, K, 3)) @ np.sqrt(Rm)
    rr = range_rate(x[..., :3], x[..., 3:]) + rng.normal(0, 1.0, (runs, K))
    x0 = x[:, 0] + rng.normal(0, 30, (runs, 6))
    return x, Z, np.broadcast_to(Rm, (runs, K, 3, 3)), rr, x0, np.arange(K) * T


def _own_model_run(data, **kw):
    x, Z, R, rr, x0, t = data
    runs = x.shape[0]
    cfg = MultiModelConfig(sigma_w=2.0, sigma_range_rate=1.0, **kw)
    init = MultiModelState(
        x0.copy(),
        np.broadcast_to(np.eye(6) * 30.0**2, (runs, 6, 6)).copy(),
        np.broadcast_to(cfg.prior_vector(), (runs, 5)).copy(),
    )
    return MultiModelFilter(cfg).run(t, Z, R, rr, initial=init)


def test_consistent_on_its_own_model():
    """The patent's filter (range rate + integrated covariances, default pi) on data from
    its own model: once the reliabilities have locked, the time-averaged NEES lies in the
    95 % acceptance interval of chi-square(6)/runs and the NIS in that of chi-square(3).
    (A time average of correlated ANEES values varies less than one time's ANEES, so the
    single-time interval is a valid, slightly loose, acceptance region.)"""
    data = _own_model_data()
    x, runs = data[0], data[0].shape[0]
    late = slice(35, None)
    res = _own_model_run(data)
    assert res.beta[:, late, 1].mean() > 0.999
    lo, hi = chi2_interval(6, runs)
    assert lo < nees(res.x - x, res.P)[:, late].mean() < hi
    lo3, hi3 = chi2_interval(3, runs)
    assert lo3 < np.mean(res.nis[:, late]) < hi3


def test_integrated_covariance_fixes_prior_art_overconfidence():
    """Same data, position-only reliabilities (prior art): without the spread-of-means
    terms the covariance is far too small (NEES above the interval); with them (novelty 2)
    it is no longer optimistic."""
    data = _own_model_data()
    x, runs = data[0], data[0].shape[0]
    late = slice(35, None)
    lo, hi = chi2_interval(6, runs)
    prior_art = _own_model_run(data, use_range_rate=False, integrated_covariance=False)
    integrated = _own_model_run(data, use_range_rate=False, integrated_covariance=True)
    assert nees(prior_art.x - x, prior_art.P)[:, late].mean() > 2 * hi
    assert nees(integrated.x - x, integrated.P)[:, late].mean() < lo


def test_range_rate_stabilises_straight_leg():
    """The prior art's weakness on a straight target: position-only reliabilities wander
    among 10 g hypotheses and inject velocity noise; range rate pins the zero model."""
    rng = np.random.default_rng(13)
    tr = trajectory([2e4, 3e4, 3e3], 1.0, 250.0, [Leg.straight(150)], dt=1.0)
    runs = 60
    Z, Rc, rr = [], [], []
    from seatrack.filters.converted import convert_plots

    for _ in range(runs):
        m = observe(
            tr,
            None,
            ("range", "azimuth", "elevation", "range_rate"),
            NoiseModel([30.0, np.radians(0.3), np.radians(0.3), 1.0]),
            rng,
        )
        cm = convert_plots(m.z[:, 0], m.z[:, 1], m.z[:, 2], 30.0, np.radians(0.3), np.radians(0.3))
        Z.append(cm.z)
        Rc.append(cm.R)
        rr.append(m.z[:, 3])
    Z, Rc, rr = np.array(Z), np.array(Rc), np.array(rr)
    truth = tr.state("cv3")
    err = {}
    for use in (True, False):
        res = MultiModelFilter(MultiModelConfig(sigma_w=0.5, use_range_rate=use)).run(
            tr.t, Z, Rc, rr
        )
        err[use] = np.sqrt(np.mean(np.sum((res.x[:, 40:, 3:] - truth[40:, 3:]) ** 2, -1)))
        if use:
            assert res.beta[:, 40:, 4].mean() > 0.95
    assert err[True] < 0.25 * err[False]


def test_joint_range_rate_likelihood_is_the_stacked_gaussian():
    """The beyond-the-patent "joint" option: reliabilities from the exact joint Gaussian
    likelihood of (Z, rho) with cross-covariance H Pbar h^T."""
    from scipy.stats import multivariate_normal

    rng = np.random.default_rng(31)
    x, P, beta, Z, R, rr = random_case(rng, 3)
    spos, svel = rng.normal(0, 500, 3), rng.normal(0, 10, 3)
    cfg = MultiModelConfig(range_rate_likelihood="joint", sigma_w=3.0, sigma_range_rate=2.0)
    step = MultiModelFilter(cfg).step(MultiModelState(x, P, beta), 1.2, Z, R, rr, spos, svel)
    T = 1.2
    F = np.block([[np.eye(3), T * np.eye(3)], [np.zeros((3, 3)), np.eye(3)]])
    G = np.vstack([T**2 / 2 * np.eye(3), T * np.eye(3)])
    Pb = F @ P @ F.T + G @ cfg.process_noise(3) @ G.T
    lw = []
    for a in np.asarray(DEFAULT_ALPHAS):
        xa = F @ x + G @ a
        rhat, h = range_rate_row(xa, spos, svel)
        Hj = np.vstack([np.hstack([np.eye(3), np.zeros((3, 3))]), h])
        Sj = Hj @ Pb @ Hj.T + np.diag([0, 0, 0, 4.0])
        Sj[:3, :3] += R
        lw.append(multivariate_normal(np.append(xa[:3], rhat), Sj).logpdf(np.append(Z, rr)))
    lw = np.array(lw) + np.log(cfg.transition_matrix() @ beta)
    np.testing.assert_allclose(step.beta, np.exp(lw - logsumexp(lw)), rtol=1e-7, atol=1e-14)
    np.testing.assert_allclose(step.log_likelihood, logsumexp(lw), rtol=1e-10)
    with pytest.raises(ValueError, match="range_rate_likelihood"):
        MultiModelConfig(range_rate_likelihood="product")
