"""The noise-level IMM wrapper honours the contract and follows manoeuvres."""

import numpy as np
import pytest

from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import plot_gaussian
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig
from seatrack.models.motion import ct_transition
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory
from seatrack.tracking.adaptive import NoiseLevels

SN = SensorNoise(sigma_range=10.0, sigma_azimuth=np.radians(0.2))


def _plots(legs, seed=0, dt=2.5):
    tr = trajectory([3000.0, 6000.0], np.radians(80), 10.0, legs, dt=dt)
    m = observe(tr, None, ["range", "azimuth"], NoiseModel([10.0, np.radians(0.2)]),
                np.random.default_rng(seed))  # fmt: skip
    return Plots(m.t, m.z[:, 0], m.z[:, 1]), tr


def _run(flt, plots):
    x, P = plot_gaussian(plots.take([0]), SN, 10.0)
    s = flt.initiate(plots.t[:1], x, P)
    out = [s]
    for k in range(1, len(plots)):
        s = flt.update(flt.predict(s, plots.t[k : k + 1]), plots.take([k]))
        out.append(s)
    return out


def test_is_a_recursive_filter_and_equals_the_filter_without_extra_noise():
    plots, _ = _plots([Leg.straight(200.0)])
    base = EKF(EKFConfig(q=0.05), SN)
    imm = NoiseLevels(base, (0.0, 0.0), 0.05)
    assert isinstance(imm, RecursiveFilter)
    a, b = _run(base, plots), _run(imm, plots)
    for sa, sb in zip(a, b, strict=True):
        assert np.allclose(sa.x, sb.x) and np.allclose(sa.P, sb.P)
    y1, S1 = base.innovation(a[-1], plots.take([0]))
    y2, S2 = imm.innovation(b[-1], plots.take([0]))
    assert np.allclose(y1, y2) and np.allclose(S1, S2)
    assert b[-1].status[0] == PlotStatus.UPDATED
    assert np.allclose(np.asarray(b[-1].aux["noise_mu"]).sum(1), 1.0)


def test_manoeuvre_probability_rises_in_a_turn_and_beats_the_low_noise_filter():
    legs = [Leg.straight(150.0), Leg.turn(np.radians(90), np.radians(3)), Leg.straight(100.0)]
    plots, tr = _plots(legs, seed=1)
    low = EKF(EKFConfig(q=0.005), SN)
    imm = NoiseLevels(low, (0.0, 1.0), 0.02)
    s_low, s_imm = _run(low, plots), _run(imm, plots)
    mu = np.array([np.asarray(s.aux["noise_mu"])[0, 1] for s in s_imm])
    t = plots.t
    turn = (t > 155) & (t < 180)
    straight = (t > 60) & (t < 145)
    assert mu[turn].mean() > 0.5 > mu[straight].mean()
    err = lambda ss: np.array([np.linalg.norm(s.x[0, :2] - p[:2]) for s, p in zip(ss, tr.pos)])  # noqa: E731
    late = t > 150
    assert np.sqrt(np.mean(err(s_imm)[late] ** 2)) < 0.6 * np.sqrt(np.mean(err(s_low)[late] ** 2))
    cols = imm.columns(s_imm[-1])
    assert "manoeuvre" in cols and 0 <= cols["manoeuvre"][0] <= 1


def test_new_tracks_start_in_the_first_model_with_the_given_probability():
    x, P = plot_gaussian(_plots([Leg.straight(10.0)])[0].take([0, 1]), SN, 10.0)
    flt = EKF(EKFConfig(q=0.01), SN)
    even = NoiseLevels(flt, (0.0, 0.5, 1.0)).initiate(np.zeros(2), x, P)
    assert np.allclose(even.aux["noise_mu"], 1 / 3)
    mu = np.asarray(NoiseLevels(flt, (0.0, 0.5, 1.0), start=0.8).initiate(np.zeros(2), x, P)
                    .aux["noise_mu"])  # fmt: skip
    assert np.allclose(mu, [[0.8, 0.1, 0.1]] * 2)
    for bad in (0.0, 1.0, 1.5):
        with pytest.raises(ValueError, match="start"):
            NoiseLevels(flt, (0.0, 1.0), start=bad)


def test_batch_operations_keep_the_nested_models():
    plots, _ = _plots([Leg.straight(30.0)])
    imm = NoiseLevels(EKF(EKFConfig(q=0.01), SN), (0.0, 1.0))
    x, P = plot_gaussian(plots.take([0, 1, 2]), SN, 10.0)
    s = imm.initiate(plots.t[:3], x, P)
    assert s.aux["noise_models"].x.shape == (3, 2, 4)
    sub = s.take([2, 0])
    assert np.allclose(sub.aux["noise_models"].x[0, 0], x[2])


def test_rejects_bad_parameters():
    with pytest.raises(ValueError, match="noise levels"):
        NoiseLevels(EKF(), (0.0,))
    with pytest.raises(ValueError, match="p_switch"):
        NoiseLevels(EKF(), (0.0, 1.0), 1.5)


def test_jpda_merge_reduces_each_model_and_keeps_the_mixture():
    """Two hypotheses of one track: the merged outer state is the moment-matched mixture of
    all (hypothesis, model) pairs, and the model probabilities sum the weights."""
    from seatrack.tracking.merge import moment_match

    plots, _ = _plots([Leg.straight(30.0)])
    imm = NoiseLevels(EKF(EKFConfig(q=0.01), SN), (0.0, 1.0), 0.05)
    s = _run(imm, plots.take([0, 1, 2]))[-1]
    pred = imm.predict(s, plots.t[3:4])
    upd = imm.update(pred, plots.take([3]))
    hyps = TrackState.concat([upd, pred])
    w = np.array([0.7, 0.3])
    merged = imm.merge(hyps, w, np.zeros(2, np.int64), 1)
    mu_h = np.asarray(hyps.aux["noise_mu"])  # (2, M)
    joint = (w[:, None] * mu_h).ravel()
    X = hyps.aux["noise_models"].x.reshape(-1, 4)
    P = hyps.aux["noise_models"].P.reshape(-1, 4, 4)
    x, Pm = moment_match(X, P, joint, np.zeros(4, np.int64), 1)
    assert np.allclose(merged.x, x) and np.allclose(merged.P, Pm)
    assert np.allclose(merged.aux["noise_mu"], (w[:, None] * mu_h).sum(0))
    assert merged.aux["noise_models"].x.shape == (1, 2, 4)


def test_extra_noise_per_track_interval():
    plots, _ = _plots([Leg.straight(30.0)])
    imm = NoiseLevels(EKF(EKFConfig(q=0.0), SN), (0.0, 2.0), 0.01)
    x, P = plot_gaussian(plots.take([0, 1]), SN, 10.0)
    s = imm.initiate(np.zeros(2), x, P)
    a = imm.predict(s, np.array([2.0, 5.0]))  # different intervals per track
    b = imm.predict(s.take([1]), np.array([5.0]))
    assert np.allclose(a.x[1], b.x[0]) and np.allclose(a.P[1], b.P[0])


def test_along_track_extra_noise_is_shaped_by_the_velocity():
    """With ``along_track_ratio`` r the extra noise of a level is ``extra * blk (x) A``:
    across a known velocity the isotropic PSD, along it r times it; isotropic while the
    velocity is unknown; r = 1 is the isotropic IMM."""
    from seatrack.models.motion import cv_noise

    base = EKF(EKFConfig(q=0.0), SN)
    shaped = NoiseLevels(base, (0.0, 2.0), 0.05, along_track_ratio=0.3)
    iso = NoiseLevels(base, (0.0, 2.0), 0.05)
    x = np.array([[0.0, 0.0, 8.0, 0.0], [0.0, 0.0, 0.1, 0.0]])  # East at 8 m/s; ~at rest
    P = np.broadcast_to(np.diag([100.0, 100.0, 1.0, 1.0]), (2, 4, 4)).copy()
    outer = TrackState.new(np.zeros(2), x, P)
    zero = np.zeros((4, 4, 4))  # B * M = 2 tracks x 2 levels
    dt = np.full(2, 2.0)  # one interval a track
    Qs = shaped._extra_noise(zero, dt, outer)
    Qi = iso._extra_noise(zero, dt, outer)
    np.testing.assert_allclose(Qi[1], cv_noise(2.0, 2.0, 2))
    np.testing.assert_allclose(Qs[0], 0.0)  # the first level has no extra noise
    # track 0 (level 1): along x (East) 0.3 x, across (North) as the isotropic level
    np.testing.assert_allclose(Qs[1][np.ix_([0, 2], [0, 2])], 0.3 * Qi[1][np.ix_([0, 2], [0, 2])])
    np.testing.assert_allclose(Qs[1][np.ix_([1, 3], [1, 3])], Qi[1][np.ix_([1, 3], [1, 3])])
    # track 1: speed 0.1 m/s with a 1 m/s std -- direction unknown, isotropic
    np.testing.assert_allclose(Qs[3], Qi[3])
    with pytest.raises(ValueError, match="along_track_ratio"):
        NoiseLevels(base, (0.0, 1.0), 0.05, along_track_ratio=0.0)


# -- coordinated-turn models ----------------------------------------------------------------
TURNS = (np.radians(3.0), -np.radians(3.0))


def _batch_run(flt, plots_list):
    """Run tracks side by side in one batch (each track its own plots, same times)."""
    x, P = plot_gaussian(_cat([p.take([0]) for p in plots_list]), SN, 10.0)
    s = flt.initiate(plots_list[0].t[:1].repeat(len(plots_list)), x, P)
    out = [s]
    for k in range(1, len(plots_list[0])):
        pk = _cat([p.take([k]) for p in plots_list])
        s = flt.update(flt.predict(s, pk.t), pk)
        out.append(s)
    return out


def _cat(plots):
    return Plots(np.concatenate([p.t for p in plots]), np.concatenate([p.range for p in plots]),
                 np.concatenate([p.azimuth for p in plots]))  # fmt: skip


def test_turn_models_never_evaluated_leave_the_level_imm_unchanged():
    """A threshold no track reaches: the levels alone, exactly, turn probabilities zero."""
    plots, _ = _plots([Leg.straight(120.0)])
    base = EKF(EKFConfig(q=0.001), SN)
    two = NoiseLevels(base, (0.0, 1.0), 0.01, start=0.99)
    four = NoiseLevels(base, (0.0, 1.0), 0.01, start=0.99, turn_rates=TURNS, turn_noise=0.01,
                       turn_threshold=0.9)  # fmt: skip
    for a, b in zip(_run(two, plots), _run(four, plots), strict=True):
        mu = np.asarray(b.aux["noise_mu"])
        assert np.all(mu[:, 2:] == 0.0)
        assert np.allclose(a.x, b.x) and np.allclose(a.P, b.P)
        assert np.allclose(a.aux["noise_mu"], mu[:, :2])


def test_turn_model_prediction_is_the_coordinated_turn():
    """A noiseless state predicted by a turn model at rate w lands on the circle."""
    w, T, v = np.radians(2.0), 2.5, 8.0
    imm = NoiseLevels(EKF(EKFConfig(q=0.0), SN), (0.0, 1.0), 0.05, turn_rates=(w,))
    x = np.array([[1000.0, 2000.0, v, 0.0]])
    s = imm.initiate(np.zeros(1), x, np.eye(4)[None] * 1e-6)
    p = imm.predict(s, np.array([T]))
    got = p.aux["noise_models"].x[0, 2]
    # the project's coordinated turn, clockwise positive: heading East, a turn to starboard
    want = ct_transition(np.append(x[0], w), T)[:4]
    assert want[1] < 2000.0 and want[3] < 0.0
    np.testing.assert_allclose(got, want, rtol=1e-12)
    np.testing.assert_allclose(p.aux["noise_models"].x[0, 0], [1000.0 + v * T, 2000.0, v, 0.0])


@pytest.mark.parametrize("threshold", [0.0, 0.1])
def test_turn_models_batched_subset_is_per_track_and_consistent(threshold):
    """Tracks in one batch (some evaluating their turn models, some not) get what each gets
    alone; probabilities sum to one, covariances stay symmetric positive definite."""
    legs = [
        [Leg.straight(60.0), Leg.turn(np.radians(90), np.radians(3)), Leg.straight(40.0)],
        [Leg.straight(190.0)],
        [Leg.turn(np.radians(-120), np.radians(2)), Leg.straight(130.0)],
    ]
    plots = [_plots(lg, seed=k)[0] for k, lg in enumerate(legs)]
    n = min(len(p) for p in plots)
    plots = [p.take(np.arange(n)) for p in plots]
    imm = NoiseLevels(
        EKF(EKFConfig(q=0.001), SN),
        (0.0, 1.0),
        0.01,
        along_track_ratio=0.5,
        start=0.9,
        turn_rates=TURNS,
        turn_noise=0.01,
        turn_threshold=threshold,
    )
    together = _batch_run(imm, plots)
    for k, p in enumerate(plots):
        alone = _run(imm, p)
        for a, b in zip(alone, together, strict=True):
            np.testing.assert_allclose(b.x[k], a.x[0], rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(b.P[k], a.P[0], rtol=1e-9, atol=1e-9)
    for s in together:
        mu = np.asarray(s.aux["noise_mu"])
        assert np.allclose(mu.sum(1), 1.0) and np.all(mu >= 0)
        for P in [*s.P, *s.aux["noise_models"].P.reshape(-1, 4, 4)]:
            assert np.allclose(P, P.T) and np.all(np.linalg.eigvalsh(P) > 0)
    if threshold > 0:
        assert 0 < np.mean([np.mean(1 - np.asarray(s.aux["noise_mu"])[:, 0] > threshold)
                            for s in together]) < 1  # fmt: skip


def test_turn_models_lower_the_error_in_a_turn():
    legs = [Leg.straight(150.0), Leg.turn(np.radians(120), np.radians(2)), Leg.straight(60.0)]
    err2, err4 = [], []
    for seed in range(4):
        plots, tr = _plots(legs, seed=seed)
        base = EKF(EKFConfig(q=0.001), SN)
        two = NoiseLevels(base, (0.0, 0.6), 0.01, along_track_ratio=0.5, start=0.9)
        four = NoiseLevels(
            base,
            (0.0, 0.6),
            0.01,
            along_track_ratio=0.5,
            start=0.9,
            turn_rates=(np.radians(2), -np.radians(2)),
            turn_noise=0.005,
        )
        turn = (plots.t > 160) & (plots.t < 220)
        for flt, out in ((two, err2), (four, err4)):
            est = _run(flt, plots)
            e = np.array([np.linalg.norm(s.x[0, :2] - p[:2]) for s, p in zip(est, tr.pos)])
            out.append(e[turn])
    rms = lambda e: np.sqrt(np.mean(np.concatenate(e) ** 2))  # noqa: E731
    assert rms(err4) < 0.85 * rms(err2)


def test_turn_models_in_the_jpda_merge_and_columns():
    plots, _ = _plots([Leg.straight(30.0)])
    imm = NoiseLevels(EKF(EKFConfig(q=0.01), SN), (0.0, 1.0), 0.05, turn_rates=TURNS)
    s = _run(imm, plots.take([0, 1, 2]))[-1]
    pred = imm.predict(s, plots.t[3:4])
    hyps = TrackState.concat([imm.update(pred, plots.take([3])), pred])
    merged = imm.merge(hyps, np.array([0.7, 0.3]), np.zeros(2, np.int64), 1)
    mu = np.asarray(merged.aux["noise_mu"])
    assert mu.shape == (1, 4) and np.isclose(mu.sum(), 1.0)
    assert np.isclose(imm.columns(merged)["manoeuvre"][0], mu[0, 1:].sum())


def test_turn_parameters_are_checked():
    with pytest.raises(ValueError, match="turn_threshold"):
        NoiseLevels(EKF(), (0.0, 1.0), turn_rates=TURNS, turn_threshold=1.0)
    with pytest.raises(ValueError, match="turn_noise"):
        NoiseLevels(EKF(), (0.0, 1.0), turn_rates=TURNS, turn_noise=-1.0)
