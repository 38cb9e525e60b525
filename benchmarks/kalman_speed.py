"""Kalman core speed: seatrack vs FilterPy and Stone Soup, side by side in one run.

Cases (issue 2):
1. predict+update of a 4-state CV filter with 2-D position measurements, one track;
2. batch mode: 10,000 independent tracks stepped together (µs per track-step);
3. IMM with two 4-state CV models vs FilterPy's ``IMMEstimator``.

Run: ``python benchmarks/kalman_speed.py`` (``--quick`` for a smoke run).
Timings are best-of-``repeat`` medians of many steps; compare ratios, not absolutes.
"""

from __future__ import annotations

import argparse
import datetime
import time
import warnings

import numpy as np

from seatrack import kalman
from seatrack.filters.imm import IMM
from seatrack.models import ConstantVelocity
from seatrack.models import Position


def _best(fn, n: int, repeat: int) -> float:
    """Best-of-repeat mean seconds per call of ``fn`` over ``n`` calls."""
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn(n)
        best = min(best, (time.perf_counter() - t) / n)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    n = 2000 if args.quick else 20000
    rep = 3 if args.quick else 7
    rng = np.random.default_rng(0)
    dt = 1.0
    cv = ConstantVelocity(q=0.5)
    F = np.ascontiguousarray(cv.transition(np.zeros(4), dt)[1])
    Q = np.ascontiguousarray(cv.noise(dt))
    H = Position(n=4).matrix()
    R = np.eye(2) * 25.0
    Z = rng.normal(size=(1000, 2)) * 5
    x0 = np.zeros(4)
    P0 = np.eye(4) * 100

    # --- 1. single track -----------------------------------------------------
    def seatrack_single(k: int) -> None:
        x, P = x0, P0
        for i in range(k):
            x, P = kalman.predict(x, P, F, Q)
            r = kalman.update(x, P, Z[i % 1000], H, R)
            x, P = r.x, r.P

    from filterpy.kalman import IMMEstimator
    from filterpy.kalman import KalmanFilter

    kf = KalmanFilter(dim_x=4, dim_z=2)
    kf.F, kf.Q, kf.H, kf.R, kf.x, kf.P = F, Q, H, R, x0.copy(), P0.copy()

    def filterpy_single(k: int) -> None:
        for i in range(k):
            kf.predict()
            kf.update(Z[i % 1000])

    seatrack_single(100)
    t_st = _best(seatrack_single, n, rep)
    t_fp = _best(filterpy_single, n // 4, rep)

    # Stone Soup: the same CV model (white-noise acceleration, q) and linear position sensor
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from stonesoup.models.measurement.linear import LinearGaussian
        from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel
        from stonesoup.models.transition.linear import ConstantVelocity as SSCV
        from stonesoup.predictor.kalman import KalmanPredictor
        from stonesoup.types.detection import Detection
        from stonesoup.types.hypothesis import SingleHypothesis
        from stonesoup.types.state import GaussianState
        from stonesoup.updater.kalman import KalmanUpdater

        tm = CombinedLinearGaussianTransitionModel([SSCV(0.5), SSCV(0.5)])
        mm = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=R)
        pred = KalmanPredictor(tm)
        upd = KalmanUpdater(mm)
        t0 = datetime.datetime(2026, 1, 1)

        def stonesoup_single(k: int) -> None:
            s = GaussianState(np.zeros((4, 1)), np.eye(4) * 100, timestamp=t0)
            for i in range(k):
                ts = t0 + datetime.timedelta(seconds=i + 1)
                p = pred.predict(s, timestamp=ts)
                d = Detection(Z[i % 1000].reshape(2, 1), timestamp=ts, measurement_model=mm)
                s = upd.update(SingleHypothesis(p, d))

        stonesoup_single(10)
        t_ss = _best(stonesoup_single, max(200, n // 40), max(2, rep // 2))

    # --- 2. batch of 10,000 tracks -------------------------------------------
    B = 10_000
    xb = np.zeros((B, 4))
    Pb = np.broadcast_to(P0, (B, 4, 4)).copy()
    Zb = rng.normal(size=(B, 2)) * 5

    def seatrack_batch(k: int) -> None:
        x, P = xb, Pb
        for _ in range(k):
            x, P = kalman.predict(x, P, F, Q)
            r = kalman.update(x, P, Zb, H, R)
            x, P = r.x, r.P

    seatrack_batch(2)
    steps = 5 if args.quick else 30
    t_batch = _best(seatrack_batch, steps, rep) / B

    # --- 3. IMM, two 4-state models -------------------------------------------
    PI = np.array([[0.97, 0.03], [0.05, 0.95]])
    models = [ConstantVelocity(q=0.01), ConstantVelocity(q=4.0)]
    imm = IMM(models, PI, Position(n=4))

    def seatrack_imm(k: int) -> None:
        st = imm.initial_state(x0, P0)
        for i in range(k):
            st = imm.step(st, Z[i % 1000], dt, R).state

    fs = []
    for m in models:
        f = KalmanFilter(4, 2)
        f.F = m.transition(x0, dt)[1]
        f.Q, f.H, f.R, f.x, f.P = m.noise(dt), H, R, x0.copy(), P0.copy()
        fs.append(f)
    fimm = IMMEstimator(fs, np.array([0.5, 0.5]), PI)

    def filterpy_imm(k: int) -> None:
        for i in range(k):
            fimm.predict()
            fimm.update(Z[i % 1000])

    seatrack_imm(50)
    t_imm = _best(seatrack_imm, n // 4, rep)
    t_fimm = _best(filterpy_imm, n // 20, rep)

    us = 1e6
    rows = [
        (
            "CV 4-state predict+update, 1 track",
            "seatrack",
            t_st * us,
            "FilterPy KalmanFilter",
            t_fp * us,
            "<= 1/3",
        ),
        ("", "seatrack", t_st * us, "Stone Soup Kalman", t_ss * us, "far below"),
        (
            "same, 10,000 tracks batched (per track-step)",
            "seatrack",
            t_batch * us,
            "target",
            1.0,
            "<= 1 us",
        ),
        (
            "IMM, two 4-state models, 1 track",
            "seatrack IMM",
            t_imm * us,
            "FilterPy IMMEstimator",
            t_fimm * us,
            ">= 10x faster",
        ),
    ]
    print(
        f"{'case':46s} {'seatrack':>14s} {'us':>9s}   {'anchor':>22s} {'us':>9s} {'ratio':>7s}"
        "  target"
    )
    for case, a, ta, b, tb, target in rows:
        print(f"{case:46s} {a:>14s} {ta:9.2f}   {b:>22s} {tb:9.2f} {ta / tb:7.3f}  {target}")
    print(
        f"(ratio = seatrack / anchor; FilterPy/seatrack speed-up: single {t_fp / t_st:.1f}x, "
        f"IMM {t_fimm / t_imm:.1f}x; Stone Soup/seatrack {t_ss / t_st:.0f}x)"
    )


if __name__ == "__main__":
    main()
