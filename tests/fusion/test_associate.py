"""Radar-AIS association: statistics, assignment, hysteresis, prediction."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from seatrack.fusion.associate import AisStates
from seatrack.fusion.associate import Associator
from seatrack.fusion.associate import FusionConfig
from seatrack.fusion.associate import PairScores
from seatrack.fusion.associate import assign_pairs
from seatrack.fusion.associate import identity_probability
from seatrack.fusion.associate import pair_keys
from seatrack.fusion.associate import pair_statistics
from seatrack.fusion.associate import predict_ais
from seatrack.fusion.associate import report_allowance
from seatrack.fusion.associate import velocity_covariance
from seatrack.models.numdiff import numerical_jacobian


def test_pair_statistics_is_the_gaussian_log_likelihood_ratio() -> None:
    rng = np.random.default_rng(1)
    z, a = rng.normal(0, 50, (5, 2)), rng.normal(0, 50, (5, 2))
    m = rng.normal(0, 10, (5, 2, 2))
    pz = m @ m.transpose(0, 2, 1) + 100 * np.eye(2)
    pa = 400 * np.eye(2) + np.zeros((5, 2, 2))
    d2, llr = pair_statistics(z, pz, a, pa, 1e-6)
    for k in range(5):
        s = pz[k] + pa[k]
        nu = z[k] - a[k]
        assert d2[k] == pytest.approx(nu @ np.linalg.solve(s, nu))
        want = multivariate_normal(np.zeros(2), s).logpdf(nu) - np.log(1e-6)
        assert llr[k] == pytest.approx(want)
    bad = -np.eye(2)[None] * 1e4
    d2b, llrb = pair_statistics(z[:1], bad, a[:1], pa[:1], 1e-6)
    assert np.isinf(d2b[0]) and llrb[0] == -np.inf


def test_velocity_covariance_is_the_linearised_one() -> None:
    c, s, vc, vs = 0.7, 6.0, 0.01, 0.04
    f = lambda u: np.array([u[1] * np.sin(u[0]), u[1] * np.cos(u[0])])  # noqa: E731
    j = numerical_jacobian(f, np.array([c, s]))
    want = j @ np.diag([vc, vs]) @ j.T
    got = velocity_covariance(np.array(c), np.array(s), np.array(vc), np.array(vs))
    assert np.allclose(got, want, rtol=1e-6)


def test_assignment_takes_the_best_total_per_component() -> None:
    rows = np.array([0, 0, 1, 1, 2])
    cols = np.array([0, 1, 0, 1, 2])
    w = np.array([5.0, 4.0, 4.5, 1.0, 2.0])
    got = assign_pairs(rows, cols, w, 3, 3)
    assert got.tolist() == [False, True, True, False, True]  # 4 + 4.5 > 5 + 1
    p = identity_probability(rows, cols, np.log(np.array([9.0, 1e-9, 1e-9, 9.0, 3.0])), 3, 3)
    assert p[0] == pytest.approx(0.9, rel=1e-6) and p[4] == pytest.approx(0.75)


def test_identity_holds_through_a_crossing() -> None:
    # two radar tracks cross; their AIS vessels are noisy: the hysteresis keeps each name
    rng = np.random.default_rng(5)
    cfg = FusionConfig()
    assoc = Associator(cfg)
    flips = 0
    for k in range(200):
        t = k * 3.0
        truth = np.array([[-600 + 6 * t, 0.0], [600 - 6 * t, 30.0]])
        z = truth + rng.normal(0, 20, (2, 2))
        a = truth + rng.normal(0, 30, (2, 2))
        cov_z = np.tile(np.eye(2) * 400.0, (2, 1, 1))
        cov_a = np.tile(np.eye(2) * 1800.0, (2, 1, 1))
        res = assoc.step(np.array([11, 12]), z, cov_z, np.array([0, 1]), a, cov_a)
        if k > 2:
            flips += int(res.ais_row.tolist() != [0, 1])
    assert flips == 0


def test_prediction_moves_the_last_state_and_stops_after_the_limit() -> None:
    st = AisStates(
        np.array([0, 0, 1]), np.array([0.0, 10.0, 0.0]),
        np.array([[0.0, 0.0], [50.0, 0.0], [1000.0, 0.0]]),
        np.array([[5.0, 0.0], [5.0, 0.0], [0.0, 3.0]]), np.tile(np.eye(2) * 25.0, (3, 1, 1)),
        np.tile(np.eye(2) * 0.01, (3, 1, 1)), np.array([30.0, 100.0]),
    )  # fmt: skip
    cfg = FusionConfig()
    p = predict_ais(st, 20.0, cfg)
    assert p.vessel.tolist() == [0, 1]
    assert np.allclose(p.pos, [[100.0, 0.0], [1000.0, 60.0]])
    assert np.all(np.linalg.eigvalsh(p.cov) > 0)
    assert np.allclose(p.cov, p.cov.transpose(0, 2, 1))
    # latency allowance stretches the ellipse along the velocity
    assert p.cov[0, 0, 0] - p.cov[0, 1, 1] == pytest.approx(cfg.sigma_latency**2 * 25.0)
    assert predict_ais(st, 45.0, cfg).vessel.tolist() == [1]  # vessel 0 silent > 30 s
    with pytest.raises(ValueError, match="sorted"):
        AisStates(st.vessel[::-1].copy(), st.t, st.pos, st.vel, st.pos_cov, st.vel_cov, st.limit)


def test_config_built_directly_checks_its_keys():
    with pytest.raises(ValueError, match=r"FusionConfig\.sigma_latency \(sigma_latency_s\)"):
        FusionConfig(sigma_latency=-1.0)
    with pytest.raises(ValueError, match=r"FusionConfig\.gate: must be >= 1"):
        FusionConfig(gate=0.5)


def test_pair_scores_accumulate_bounded_and_forget_or_keep() -> None:
    """Scores add up to ``max_score``; pairs not given are forgotten unless kept; the
    assigned pair gets the hysteresis bonus at the next assignment."""
    ps = PairScores(FusionConfig(max_score=10.0, hysteresis=4.0))
    k = pair_keys(np.array([1, 1, 2]), np.array([5, 6, 5]))
    assert ps.accumulate(k, np.array([6.0, 1.0, 2.0])).tolist() == [6.0, 1.0, 2.0]
    assert ps.accumulate(k[:1], np.array([6.0]), keep=np.array([False, False, True])).tolist() == [
        10.0
    ]
    assert ps.keys.tolist() == sorted([k[0], k[2]]) and ps.scores.tolist() == [10.0, 2.0]
    rows, cols = np.array([0, 1]), np.array([0, 0])  # tracks 1 and 2 both want vessel 5
    chosen, prob = ps.assign(rows, cols, ps.keys, ps.scores, 2, 1)
    assert chosen.tolist() == [True, False]
    assert prob[0] == pytest.approx(np.exp(10) / (1 + np.exp(10) + np.exp(2)))
    # track 2 now scores higher, but not by more than the incumbent's bonus
    chosen, _ = ps.assign(rows, cols, ps.keys, np.array([10.0, 13.0]), 2, 1)
    assert chosen.tolist() == [True, False]
    chosen, _ = ps.assign(rows, cols, ps.keys, np.array([10.0, 15.0]), 2, 1)
    assert chosen.tolist() == [False, True]


def test_report_allowance_is_offset_plus_latency_along_the_velocity() -> None:
    vel = np.array([[3.0, 4.0]])
    np.testing.assert_allclose(report_allowance(vel, 30.0, 2.0)[0],
                               900.0 * np.eye(2) + 4.0 * np.outer(vel[0], vel[0]))  # fmt: skip
