"""GNN and JPDA against brute-force enumeration of joint association events."""

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
from scipy.special import logsumexp

from seatrack.tracking.association import components
from seatrack.tracking.association import contested
from seatrack.tracking.association import gnn
from seatrack.tracking.association import group_logsumexp
from seatrack.tracking.association import jpda


def _problem(seed, n_tracks, n_plots, density):
    rng = np.random.default_rng(seed)
    mask = rng.random((n_tracks, n_plots)) < density
    t, p = np.nonzero(mask)
    return t.astype(np.int64), p.astype(np.int64), rng.normal(0, 2, t.size), rng


def _events(track, plot, n_tracks):
    """Every feasible joint event: a plot (pair index) or None per track, plots unique."""
    options = [[None] + [k for k in range(track.size) if track[k] == i] for i in range(n_tracks)]
    for ev in itertools.product(*options):
        used = [plot[k] for k in ev if k is not None]
        if len(used) == len(set(used)):
            yield ev


@settings(max_examples=40)
@given(st.integers(0, 10_000), st.integers(1, 5), st.integers(1, 5))
def test_gnn_is_the_best_joint_assignment(seed, n_tracks, n_plots):
    track, plot, gain, _ = _problem(seed, n_tracks, n_plots, 0.6)
    got = gnn(track, plot, gain, n_tracks, n_plots)
    value = lambda assign: sum(  # noqa: E731
        gain[(track == i) & (plot == j)][0] for i, j in enumerate(assign) if j >= 0
    )
    best = max(
        (sum(gain[k] for k in ev if k is not None) for ev in _events(track, plot, n_tracks)),
        default=0.0,
    )
    assert value(got) == pytest.approx(max(best, 0.0), abs=1e-9)
    used = got[got >= 0]
    assert len(used) == len(set(used.tolist()))


@settings(max_examples=40)
@given(st.integers(0, 10_000), st.integers(1, 5), st.integers(1, 6))
def test_jpda_marginals_equal_the_enumeration(seed, n_tracks, n_plots):
    track, plot, log_lr, rng = _problem(seed, n_tracks, n_plots, 0.5)
    log_miss = rng.normal(-1, 1, n_tracks)
    res = jpda(track, plot, log_lr, log_miss, n_plots)
    beta = np.zeros(track.size)
    beta0 = np.zeros(n_tracks)
    weights = []
    events = list(_events(track, plot, n_tracks))
    for ev in events:
        weights.append(sum(log_lr[k] if k is not None else log_miss[i] for i, k in enumerate(ev)))
    w = np.exp(np.array(weights) - logsumexp(weights))
    for ev, wi in zip(events, w, strict=True):
        for i, k in enumerate(ev):
            if k is None:
                beta0[i] += wi
            else:
                beta[k] += wi
    assert np.allclose(res.beta, beta, atol=1e-12)
    assert np.allclose(res.beta0, beta0, atol=1e-12)
    assert res.fallbacks == 0


def test_jpda_falls_back_on_huge_clusters():
    track, plot, log_lr, rng = _problem(3, 6, 8, 1.0)
    res = jpda(track, plot, log_lr, np.zeros(6), 8, max_nodes=4)
    assert res.fallbacks == 1
    # per-track PDA: each track's probabilities still sum to one
    tot = np.bincount(track, res.beta, minlength=6) + res.beta0
    assert np.allclose(tot, 1.0)


def test_components_and_contested():
    track = np.array([0, 0, 1, 2, 3])
    plot = np.array([0, 1, 1, 2, 4])
    lt, lp, k = components(track, plot, 4, 5)
    assert k == 4  # {t0, t1, p0, p1}, {t2, p2}, {t3, p4}, {p3}
    assert lt[0] == lt[1] == lp[0] == lp[1] and lt[2] == lp[2] and lt[3] == lp[4]
    assert contested(track, plot, 4, 5).tolist() == [True, True, True, False, False]


def test_group_logsumexp():
    v = np.array([1.0, 2.0, -3.0, 700.0])
    owner = np.array([0, 0, 2, 2])
    base = np.array([0.5, -1.0, 0.0])
    got = group_logsumexp(v, owner, 3, base)
    assert got[0] == pytest.approx(logsumexp([0.5, 1.0, 2.0]))
    assert got[1] == pytest.approx(-1.0)
    assert got[2] == pytest.approx(logsumexp([0.0, -3.0, 700.0]))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_gnn_equals_scipy_on_large_clusters(seed):
    """Dense clusters of up to 40 tracks: the compiled assignment reaches the optimum that
    linear_sum_assignment finds on the same problem (plots plus one dummy per track)."""
    from scipy.optimize import linear_sum_assignment

    rng = np.random.default_rng(seed)
    n_tracks, n_plots = 40, 50
    mask = rng.random((n_tracks, n_plots)) < 0.3
    track, plot = (a.astype(np.int64) for a in np.nonzero(mask))
    gain = rng.normal(1.0, 2.0, track.size)
    got = gnn(track, plot, gain, n_tracks, n_plots)
    C = np.full((n_tracks, n_plots + n_tracks), 1e9)
    C[:, n_plots:] = 0.0
    ok = gain > 0
    C[track[ok], plot[ok]] = -gain[ok]
    r, c = linear_sum_assignment(C)
    best = -C[r, c].sum()
    value = sum(gain[(track == i) & (plot == j)][0] for i, j in enumerate(got) if j >= 0)
    assert value == pytest.approx(best, abs=1e-9)
    used = got[got >= 0]
    assert len(used) == len(set(used.tolist()))
