"""Moment matching of per-hypothesis states (the JPDA update)."""

import numpy as np
import pytest

from seatrack.filters.base import TrackState
from seatrack.tracking.merge import merge_hypotheses
from seatrack.tracking.merge import moment_match


def _hyps():
    rng = np.random.default_rng(0)
    H = 7
    A = rng.normal(size=(H, 4, 4))
    x = rng.normal(size=(H, 4))
    P = A @ A.transpose(0, 2, 1) + np.eye(4)
    owner = np.array([2, 0, 0, 1, 2, 2, 0])
    w = rng.random(H)
    aux = {"tag": np.arange(H, dtype=float)}
    return TrackState.new(np.zeros(H), x, P, aux), w, owner


def test_moment_match_formula():
    s, w, owner = _hyps()
    mean, cov = moment_match(s.x, s.P, w, owner, 3)
    for i in range(3):
        m = owner == i
        wi = w[m] / w[m].sum()
        mu = (wi[:, None] * s.x[m]).sum(0)
        C = sum(wk * (Pk + np.outer(xk - mu, xk - mu)) for wk, xk, Pk in zip(wi, s.x[m], s.P[m]))
        assert np.allclose(mean[i], mu) and np.allclose(cov[i], C)
        assert np.all(np.linalg.eigvalsh(cov[i]) > 0)


def test_merge_takes_aux_from_the_dominant_hypothesis():
    s, w, owner = _hyps()
    out = merge_hypotheses(object(), s, w, owner, 3)
    for i in range(3):
        m = np.flatnonzero(owner == i)
        assert out.aux["tag"][i] == s.aux["tag"][m[np.argmax(w[m])]]
    with pytest.raises(ValueError, match="at least one"):
        moment_match(s.x, s.P, w, owner, 4)


def test_merge_uses_the_filters_own_merge():
    s, w, owner = _hyps()

    class Own:
        def merge(self, states, weights, own, n):
            return states.take(np.arange(n))

    out = merge_hypotheses(Own(), s, w, owner, 3)
    assert np.array_equal(out.x, s.x[:3])
