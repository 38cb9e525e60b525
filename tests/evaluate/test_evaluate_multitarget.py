"""OSPA / GOSPA against brute force and known values; id switches and fragmentation."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st

from seatrack.evaluate.multitarget import gospa
from seatrack.evaluate.multitarget import ospa
from seatrack.evaluate.multitarget import score_run


def _gospa_brute(X, Y, c, p):
    """GOSPA by definition: minimum over every partial assignment (any pair distance)."""
    n, m = len(X), len(Y)
    best = math.inf
    for k in range(min(n, m) + 1):
        for rows in itertools.combinations(range(n), k):
            for cols in itertools.permutations(range(m), k):
                loc = sum(np.linalg.norm(X[i] - Y[j]) ** p for i, j in zip(rows, cols))
                best = min(best, loc + c**p / 2 * (n + m - 2 * k))
    return best ** (1 / p)


def _ospa_brute(X, Y, c, p):
    n, m = len(X), len(Y)
    if n == 0 and m == 0:
        return 0.0
    if n == 0 or m == 0:
        return c
    if n > m:
        X, Y, n, m = Y, X, m, n
    best = min(
        sum(min(np.linalg.norm(X[i] - Y[j]), c) ** p for i, j in enumerate(perm))
        for perm in itertools.permutations(range(m), n)
    )
    return ((best + c**p * (m - n)) / m) ** (1 / p)


points = st.lists(
    st.tuples(st.floats(-300, 300), st.floats(-300, 300)), min_size=0, max_size=5
).map(lambda v: np.array(v, float).reshape(-1, 2))


@settings(max_examples=60)
@given(points, points, st.sampled_from([1.0, 2.0, 3.0]), st.sampled_from([50.0, 100.0]))
def test_gospa_and_ospa_equal_brute_force(X, Y, p, c):
    g = gospa(X, Y, c, p)
    assert g.distance == pytest.approx(_gospa_brute(X, Y, c, p), rel=1e-9, abs=1e-9)
    total = g.localisation + g.missed + g.false
    assert total ** (1 / p) == pytest.approx(g.distance, rel=1e-12, abs=1e-12)
    assert g.missed == pytest.approx(c**p / 2 * g.n_missed)
    assert g.false == pytest.approx(c**p / 2 * g.n_false)
    assert len(X) - g.n_missed == len(Y) - g.n_false == int((g.truth_to_est >= 0).sum())
    assert ospa(X, Y, c, p) == pytest.approx(_ospa_brute(X, Y, c, p), rel=1e-9, abs=1e-9)


def test_gospa_known_values():
    """Values from the definition in the paper (alpha = 2: each missed or false target
    costs c^p / 2; a pair farther apart than c is one missed plus one false target)."""
    c, p = 100.0, 2.0
    # one missed target: (c^p / 2)^(1/p) = c / sqrt(2)
    g = gospa([[0.0, 0.0]], np.zeros((0, 2)), c, p)
    assert g.distance == pytest.approx(100 / math.sqrt(2)) and g.n_missed == 1
    # one target, estimate 30 m off: localisation only
    g = gospa([[0.0, 0.0]], [[30.0, 0.0]], c, p)
    assert g.distance == pytest.approx(30.0) and g.n_missed == g.n_false == 0
    # one target, estimate 150 m off: one missed + one false = c
    g = gospa([[0.0, 0.0]], [[150.0, 0.0]], c, p)
    assert g.distance == pytest.approx(100.0) and g.n_missed == g.n_false == 1
    # two targets, one well estimated (10 m) and one false estimate far away:
    # 10^2 + c^2/2 (missed) + c^2/2 (false) = 10100
    g = gospa([[0.0, 0.0], [1000.0, 0.0]], [[10.0, 0.0], [5000.0, 0.0]], c, p)
    assert g.distance == pytest.approx(math.sqrt(10100.0))
    # OSPA cannot tell a missed target from a far estimate; GOSPA with alpha=2 at p=1
    # counts the far estimate as missed + false (c), the missing one as c/2
    assert ospa([[0.0], [1000.0]], [[0.0]], c, 1) == pytest.approx(50.0)
    assert gospa([[0.0], [1000.0]], [[0.0]], c, 1).distance == pytest.approx(50.0)
    assert gospa([[0.0], [1000.0]], [[0.0], [3000.0]], c, 1).distance == pytest.approx(100.0)


def test_gospa_matches_stone_soup():
    from datetime import datetime

    from stonesoup.metricgenerator.ospametric import GOSPAMetric
    from stonesoup.types.state import State

    rng = np.random.default_rng(3)
    X = rng.uniform(0, 500, (8, 2))
    Y = np.concatenate([X[:6] + rng.normal(0, 40, (6, 2)), rng.uniform(0, 500, (3, 2))])
    now = datetime(2024, 1, 1)
    gen = GOSPAMetric(c=100.0, p=2.0)
    ss, _ = gen.compute_gospa_metric(
        [State(y[:, None], timestamp=now) for y in Y], [State(x[:, None], timestamp=now) for x in X]
    )
    assert gospa(X, Y, 100.0, 2.0).distance == pytest.approx(ss.value["distance"], rel=1e-9)


def test_gospa_rejects_bad_parameters():
    with pytest.raises(ValueError, match="cut-off"):
        gospa([[0.0]], [[1.0]], c=0.0)
    with pytest.raises(ValueError, match="order"):
        gospa([[0.0]], [[1.0]], p=0.5)


def test_id_switches_and_fragmentation():
    times = np.arange(6.0)
    # truth A at x = 0, truth B at x = 1000, six scans
    tt = np.repeat(times, 2)
    tid = np.tile(["A", "B"], 6)
    tpos = np.stack([np.tile([0.0, 1000.0], 6), np.zeros(12)], -1)
    # A: track 1 at scans 0-2, track 7 at 3-5 (one switch)
    # B: track 2 at 0-1, nothing at 2-3, track 2 again at 4-5 (one fragmentation)
    rows = [(k, 1 if k < 3 else 7, 5.0) for k in range(6)]
    rows += [(k, 2, 1003.0) for k in (0, 1, 4, 5)]
    et = np.array([r[0] for r in rows], float)
    eid = np.array([r[1] for r in rows])
    epos = np.stack([[r[2] for r in rows], np.zeros(len(rows))], -1)
    s = score_run(times, tt, tid, tpos, et, eid, epos)
    assert s.id_switches == 1
    assert s.fragmentations == 1
    assert list(s.scans.n_missed) == [0, 0, 1, 1, 0, 0]
    assert list(s.scans.n_false) == [0] * 6
    assert s.scans.gospa[0] == pytest.approx(math.sqrt(25 + 9))
    assert s.scans.gospa[2] == pytest.approx(math.sqrt(25 + 5000))
    parts = s.rms_parts()
    assert parts["gospa"] ** 2 == pytest.approx(
        parts["localisation"] ** 2 + parts["missed"] ** 2 + parts["false"] ** 2
    )


def test_targets_passing_close_do_not_count_as_a_swap():
    """Two targets cross within 2 m; their tracks keep their own targets: no id switch
    (a per-scan optimal assignment alone would swap them at the crossing)."""
    times = np.arange(5.0)
    xa = np.array([-20.0, -10.0, 0.0, 10.0, 20.0])
    tt = np.repeat(times, 2)
    tid = np.tile(["A", "B"], 5)
    tpos = np.stack([np.stack([xa, xa], -1).ravel(), np.stack([xa, -xa], -1).ravel()], -1)
    # track 1 follows A, track 2 follows B, both 1 m off towards the other target
    est = tpos + np.stack([np.zeros(10), np.tile([-1.0, 1.0], 5)], -1)
    est[4] = [0.0, 1.0]  # at the crossing A's track is nearer B ...
    est[5] = [0.0, -1.0]  # ... and B's nearer A
    s = score_run(times, tt, tid, tpos, tt, np.tile([1, 2], 5), est)
    assert s.id_switches == 0 and s.fragmentations == 0
