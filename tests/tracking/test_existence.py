"""Track existence: the IPDA / JIPDA updates against their definitions in probability space."""

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st

from seatrack.tracking.association import jpda
from seatrack.tracking.existence import UndetectedTargets
from seatrack.tracking.existence import ipda_update
from seatrack.tracking.existence import jipda_update
from seatrack.tracking.existence import logit
from seatrack.tracking.existence import probability
from seatrack.tracking.existence import survive


def test_logit_and_probability_are_inverse_and_stable():
    r = np.array([1e-12, 0.1, 0.5, 0.9, 1 - 1e-12])
    assert np.allclose(probability(logit(r)), r, rtol=1e-9)
    assert probability(np.array([800.0, -800.0])).tolist() == [1.0, 0.0]
    assert np.isinf(logit(np.array([0.0, 1.0]))).all()


@settings(max_examples=60)
@given(st.floats(-30, 30), st.floats(0.5, 1.0))
def test_survival_is_p_times_r(s, ps):
    r = probability(s)
    assert probability(survive(s, np.log(ps))) == pytest.approx(ps * r, rel=1e-9, abs=1e-300)


def test_survival_far_from_one_stays_exact():
    # r = 1 - 1e-15: the survival odds are p_s / (1 - p_s) to full precision
    s = survive(np.array([35.0]), np.log(0.99))
    assert s[0] == pytest.approx(np.log(0.99 / 0.01), rel=1e-9)


@settings(max_examples=60)
@given(st.floats(0.01, 0.99), st.floats(0.5, 0.99), st.floats(0.9, 0.999), st.floats(-5, 10))
def test_ipda_update_is_bayes_rule(r, pd, pg, log_lr):
    """P(exists | plot) with prior r: the plot is the target's (Pd g), it is missed
    (1 - Pd Pg) and the plot clutter, or there is no target (the plot clutter)."""
    s = ipda_update(logit(r), np.log1p(-pd * pg), np.array(log_lr))
    lr = np.exp(log_lr)  # Pd g / lambda
    post = r * (1 - pd * pg + lr) / (r * (1 - pd * pg + lr) + (1 - r))
    assert probability(s) == pytest.approx(post, rel=1e-9)
    miss = ipda_update(logit(r), np.log1p(-pd * pg), np.array(-np.inf))
    assert probability(miss) == pytest.approx(r * (1 - pd * pg) / (1 - r * pd * pg), rel=1e-9)


@settings(max_examples=30)
@given(st.integers(0, 10_000), st.integers(1, 4), st.integers(1, 4))
def test_jipda_update_equals_the_enumeration_over_existence(seed, n_tracks, n_plots):
    """Joint events over existence and association: each track exists (r) or not, each
    existing track is detected (Pd Pg, one gated plot with density ratio e^l / Pd) or not;
    the posterior existence summed over the events equals jipda_update fed with the JPDA
    marginals of the existence-weighted likelihood ratios."""
    rng = np.random.default_rng(seed)
    mask = rng.random((n_tracks, n_plots)) < 0.7
    track, plot = (a.astype(np.int64) for a in np.nonzero(mask))
    log_lr = rng.normal(0, 1.5, track.size)  # log(Pd g / lambda)
    r = rng.uniform(0.05, 0.95, n_tracks)
    pdpg = 0.85
    # JIPDA marginals: detection weight r Pd g / lambda, miss weight 1 - r Pd Pg
    res = jpda(track, plot, log_lr + np.log(r[track]), np.log1p(-r * pdpg), n_plots)
    beta_plot = np.bincount(track, res.beta, minlength=n_tracks)
    got = probability(jipda_update(logit(r), np.log(pdpg), beta_plot, res.beta0))
    # enumeration: per track none / exists-missed / exists with one of its plots
    opts = [[("dead",), ("miss",)] + [("plot", k) for k in np.flatnonzero(track == i)]
            for i in range(n_tracks)]  # fmt: skip
    total, alive = 0.0, np.zeros(n_tracks)
    for ev in itertools.product(*opts):
        used = [plot[o[1]] for o in ev if o[0] == "plot"]
        if len(used) != len(set(used)):
            continue
        w = 1.0
        for i, o in enumerate(ev):
            w *= {"dead": 1 - r[i], "miss": r[i] * (1 - pdpg)}.get(o[0], 0.0) or (
                r[i] * np.exp(log_lr[o[1]]) if o[0] == "plot" else 0.0
            )
        total += w
        alive += w * np.array([o[0] != "dead" for o in ev])
    assert np.allclose(got, alive / total, rtol=1e-9)


def test_undetected_targets_prior():
    u = UndetectedTargets(births_per_scan=0.1)
    assert u.log_prior_odds(0.9, 7.0, n_plots=20) == 0.0  # first scan: odds 1
    assert u.expected == pytest.approx(20 / 2 / 0.9)
    u.advance(0.9, 0.99)
    assert u.expected == pytest.approx(0.99 * 0.1 * 20 / 2 / 0.9 + 0.1)
    lp = u.log_prior_odds(0.9, 10.0, n_plots=30)
    assert lp == pytest.approx(np.log(0.9 * u.expected / 10.0))
    for _ in range(500):
        u.advance(0.9, 0.99)
    assert u.expected == pytest.approx(0.1 / (1 - 0.99 * 0.1))  # steady state


def test_first_scan_share_is_the_em_fixed_point():
    from scipy.special import expit

    from seatrack.tracking.existence import first_scan_share

    rng = np.random.default_rng(3)
    # 40 plots: 10 targets (pairs with strong ratios), 5 clutter pairs (weak), 25 alone
    lr = np.r_[rng.normal(8, 1, 10), rng.normal(0, 1, 5)]
    f = first_scan_share(lr, 40, 0.9)
    lo = np.log(f / (1 - f))
    mean_post = (expit(lo + lr).sum() + 25 * expit(lo + np.log(0.1))) / 40
    assert f == pytest.approx(mean_post, abs=1e-8)
    assert 0.2 < f < 0.35
    assert first_scan_share(np.zeros(0), 40, 0.9) < 1e-3  # no pair: hardly any target
    assert first_scan_share(np.full(20, 10.0), 20, 0.9) > 0.99
