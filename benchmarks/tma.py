"""Bearings-only TMA benchmark: accuracy vs FilterPy / Stone Soup EKFs, speed vs SciPy.

Run: ``python benchmarks/tma.py [--quick] [--runs N]``. Prints one table.

Accuracy -- the classic scenario of Ristic, Arulampalam & Gordon (ch. 6; see
:func:`seatrack.simulate.tma.classic_scenario`), the same seeded bearings for every method; final
position RMSE over the runs and its ratio to sqrt(trace) of the CRB of the final position.

* seatrack: batch solution from the *automatic* start (no prior information at all).
* FilterPy ``ExtendedKalmanFilter`` and Stone Soup ``ExtendedKalmanPredictor/Updater``
  (``Cartesian2DToBearing`` with the observer as ``translation_offset``), Cartesian CV
  state, process noise ``q = 1e-4 m^2/s^3`` (near zero: the target is CV).
  Initialisation (the same for both, the usual operator prior of Ristic et al. ch. 6):
  range 5 km (sigma 2 km) on the first bearing, speed 4 kn (sigma 2 kn), course = first
  bearing + 180 deg (sigma pi/sqrt(12)), polar -> Cartesian by linearisation. This prior
  is *favourable* to the filters: 5 km is almost the true initial range (4.99 km) and
  4 kn the true speed.

Speed -- the classic geometry sampled with 32, 1,000 and 10,000 bearings over the same
31 minutes. seatrack from the automatic start (whole pipeline), seatrack from a given
start, and ``scipy.optimize.least_squares`` (``method="lm"``, analytic Jacobian from
:func:`seatrack.tma.bearing_residuals`, weighted residuals) from the same given start
(the operator prior above); the ratio is SciPy / seatrack-from-the-same-start.
100 contacts: :func:`seatrack.tma.solve_many` (one vectorised call, automatic start) vs
a loop of SciPy solves from the operator prior. Times are medians of the process CPU
time over repeats (the machine is shared; wall-clock time depends on the other jobs); the
minimum is printed in brackets.
"""

from __future__ import annotations

import argparse
import math
import time
from datetime import datetime
from datetime import timedelta

import numpy as np
from scipy.optimize import least_squares

from seatrack.evaluate.montecarlo import format_table
from seatrack.geometry import knots_to_mps
from seatrack.geometry import wrap_pi
from seatrack.simulate.tma import classic_scenario
from seatrack.tma import Bearings
from seatrack.tma import bearing_residuals
from seatrack.tma import crb
from seatrack.tma import leg_starts
from seatrack.tma import leg_time_matrix
from seatrack.tma import position_crb
from seatrack.tma import solve
from seatrack.tma import solve_many

Q_EKF = 1e-4  # m^2/s^3


def operator_prior(b: Bearings) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of [x, y, vx, vy] from the first bearing (see module docstring)."""
    r, sr = 5000.0, 2000.0
    s, ss = float(knots_to_mps(4.0)), float(knots_to_mps(2.0))
    b0 = float(b.bearing[0])
    c, sc = b0 + math.pi, math.pi / math.sqrt(12.0)
    sb = math.radians(1.5)
    x = np.r_[
        b.observer[0] + r * np.array([math.sin(b0), math.cos(b0)]), s * math.sin(c), s * math.cos(c)
    ]
    Jp = np.array([[math.sin(b0), r * math.cos(b0)], [math.cos(b0), -r * math.sin(b0)]])
    Jv = np.array([[math.sin(c), s * math.cos(c)], [math.cos(c), -s * math.sin(c)]])
    P = np.zeros((4, 4))
    P[:2, :2] = Jp @ np.diag([sr**2, sb**2]) @ Jp.T
    P[2:, 2:] = Jv @ np.diag([ss**2, sc**2]) @ Jv.T
    return x, P


def cv_FQ(dt: float) -> tuple[np.ndarray, np.ndarray]:
    """[x, y, vx, vy] constant-velocity F and Q (white-noise acceleration, q = Q_EKF)."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    q = Q_EKF
    Q = np.zeros((4, 4))
    for i in range(2):
        Q[i, i] = q * dt**3 / 3
        Q[i, i + 2] = Q[i + 2, i] = q * dt**2 / 2
        Q[i + 2, i + 2] = q * dt
    return F, Q


def run_filterpy(b: Bearings, sigma: float) -> np.ndarray:
    from filterpy.kalman import ExtendedKalmanFilter

    from seatrack.models.measurement import Bearing

    model = Bearing(n=4)
    ekf = ExtendedKalmanFilter(dim_x=4, dim_z=1)
    ekf.x, ekf.P = operator_prior(b)
    ekf.R = np.array([[sigma**2]])
    for k in range(len(b)):
        if k:
            ekf.F, ekf.Q = cv_FQ(float(b.t[k] - b.t[k - 1]))
            ekf.predict()
        o = b.observer[k]
        ekf.update(
            np.array([b.bearing[k]]),
            lambda x, o=o: model.jacobian(x, o)[0:1].reshape(1, 4),
            lambda x, o=o: model.h(x, o),
            residual=lambda a, c: np.atleast_1d(wrap_pi(np.asarray(a) - np.asarray(c))),
        )
    return np.asarray(ekf.x[:2], dtype=float)


def run_stonesoup(b: Bearings, sigma: float) -> np.ndarray:
    from stonesoup.models.measurement.nonlinear import Cartesian2DToBearing
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel
    from stonesoup.models.transition.linear import ConstantVelocity
    from stonesoup.predictor.kalman import ExtendedKalmanPredictor
    from stonesoup.types.angle import Bearing as SSBearing
    from stonesoup.types.detection import Detection
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.state import GaussianState
    from stonesoup.updater.kalman import ExtendedKalmanUpdater

    trans = CombinedLinearGaussianTransitionModel(
        [ConstantVelocity(Q_EKF), ConstantVelocity(Q_EKF)]
    )
    predictor = ExtendedKalmanPredictor(trans)
    x, P = operator_prior(b)
    perm = [0, 2, 1, 3]  # seatrack [x, y, vx, vy] -> Stone Soup [x, vx, y, vy]
    t0 = datetime(2024, 1, 1)
    state = GaussianState(x[perm].reshape(-1, 1), P[np.ix_(perm, perm)], timestamp=t0)
    R = np.array([[sigma**2]])
    updater = ExtendedKalmanUpdater(measurement_model=None)
    for k in range(len(b)):
        ts = t0 + timedelta(seconds=float(b.t[k] - b.t[0]))
        mm = Cartesian2DToBearing(
            ndim_state=4, mapping=(0, 2), noise_covar=R,
            translation_offset=np.array([[b.observer[k, 0]], [b.observer[k, 1]]]),
        )  # fmt: skip
        # Stone Soup angles are counter-clockwise from the x (East) axis
        det = Detection(
            np.array([[SSBearing(math.pi / 2 - b.bearing[k])]]), timestamp=ts, measurement_model=mm
        )
        pred = predictor.predict(state, timestamp=ts) if k else state
        if not k:
            from stonesoup.types.prediction import GaussianStatePrediction

            pred = GaussianStatePrediction(state.state_vector, state.covar, timestamp=ts)
        state = updater.update(SingleHypothesis(pred, det))
    sv = np.asarray(state.state_vector, dtype=float).ravel()
    return sv[[0, 2]]


def scipy_solve(b: Bearings, sigma: float, x0: np.ndarray) -> np.ndarray:
    C = leg_time_matrix(b.t, leg_starts(b.t[0]))
    w = 1.0 / sigma

    def fun(x: np.ndarray) -> np.ndarray:
        return -w * bearing_residuals(x, C, b.observer, b.bearing)[0]

    def jac(x: np.ndarray) -> np.ndarray:
        return w * bearing_residuals(x, C, b.observer, b.bearing)[1]

    return np.asarray(least_squares(fun, x0, jac=jac, method="lm").x)


def timeit(fn, repeats: int) -> tuple[float, float]:
    """Median and minimum CPU time (s) of this process per call (the machine is shared, so
    wall-clock time mostly measures the other jobs)."""
    ts = []
    for _ in range(repeats):
        t = time.process_time()
        fn()
        ts.append(time.process_time() - t)
    return float(np.median(ts)), float(np.min(ts))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="few runs and repeats (smoke test)")
    ap.add_argument(
        "--runs", type=int, default=None, help="Monte-Carlo runs (default 300; quick 30)"
    )
    ap.add_argument("--seed", type=int, default=2024)
    args = ap.parse_args()
    n_runs = args.runs or (30 if args.quick else 300)
    reps = 3 if args.quick else 20
    rows: list[dict] = []

    # ---------------- accuracy ----------------
    sc = classic_scenario()
    rng = np.random.default_rng(args.seed)
    runs = sc.bearings_batch(rng, n_runs)
    t_last = float(sc.times[-1])
    truth = sc.target.pos[-1, :2]
    P = crb(sc.state, sc.times, sc.observer.pos, sc.sigma)
    bound = float(np.sqrt(np.trace(position_crb(P, sc.starts, t_last))))
    t = time.process_time()
    sols = solve_many({str(i): b for i, b in enumerate(runs)}, sigma=sc.sigma)
    t_st = (time.process_time() - t) / n_runs
    est = {
        "seatrack batch (auto start)": np.array(
            [s.position_at(np.array([t_last]))[0] for s in sols.values()]
        )
    }
    conv = float(np.mean([s.converged for s in sols.values()]))
    per_run = {"seatrack batch (auto start)": t_st}
    for name, fn in (("FilterPy EKF", run_filterpy), ("Stone Soup EKF", run_stonesoup)):
        t = time.process_time()
        est[name] = np.array([fn(b, sc.sigma) for b in runs])
        per_run[name] = (time.process_time() - t) / n_runs

    def add(case, method, value, unit, ratio=None, note=None):
        rows.append({"case": case, "method": method, "value": value, "unit": unit, "ratio": ratio,
                     "note": note})  # fmt: skip

    add(f"classic scenario, {n_runs} runs", "CRB sqrt(trace), final position", bound, "m", 1.0)
    for name, e in est.items():
        err = e - truth
        rmse = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
        note = f"{per_run[name] * 1e3:.2f} ms/run"
        if name.startswith("seatrack"):
            note += f", {conv:.1%} converged"
        add("  final-position RMSE", name, rmse, "m", rmse / bound, note)

    # ---------------- speed ----------------
    for n in (32, 1000, 10000):
        sc_n = classic_scenario(n=n, dt=60.0 * 31 / (n - 1))
        b = sc_n.bearings(np.random.default_rng(n))
        x0, _ = operator_prior(b)
        auto = solve(b, sigma=sc_n.sigma)
        given = solve(b, sigma=sc_n.sigma, initial=x0)
        xs = scipy_solve(b, sc_n.sigma, x0)
        same = "yes" if np.allclose(given.state, xs, rtol=1e-4, atol=0.5) else "NO"
        r = max(1, reps // (1 if n < 5000 else 4))
        m_auto = timeit(lambda b=b, s=sc_n.sigma: solve(b, sigma=s), r)
        m_given = timeit(lambda b=b, s=sc_n.sigma, x0=x0: solve(b, sigma=s, initial=x0), r)
        m_scipy = timeit(lambda b=b, s=sc_n.sigma, x0=x0: scipy_solve(b, s, x0), r)
        case = f"solve time, {n} bearings"
        add(case, "seatrack, operator start", m_given[0] * 1e3, "ms", 1.0,
            f"(min {m_given[1] * 1e3:.2f}) {given.iterations} it")  # fmt: skip
        note = f"(min {m_scipy[1] * 1e3:.2f}) same solution: {same}"
        add(case, "scipy least_squares lm, same start", m_scipy[0] * 1e3, "ms",
            m_scipy[0] / m_given[0], note)  # fmt: skip
        add(case, "seatrack, automatic start", m_auto[0] * 1e3, "ms", m_auto[0] / m_given[0],
            f"(min {m_auto[1] * 1e3:.2f}) {auto.iterations} it")  # fmt: skip

    contacts = {str(i): b for i, b in enumerate(sc.bearings_batch(np.random.default_rng(7), 100))}
    inits = {cid: operator_prior(b)[0] for cid, b in contacts.items()}
    r = max(1, reps // 4)
    m_many_op = timeit(lambda: solve_many(contacts, sigma=sc.sigma, initial=inits), r)
    m_loop = timeit(lambda: [scipy_solve(b, sc.sigma, inits[c]) for c, b in contacts.items()], r)
    m_many = timeit(lambda: solve_many(contacts, sigma=sc.sigma), r)
    m_one = timeit(lambda: [solve(b, sigma=sc.sigma) for b in contacts.values()], 1)
    case = "100 contacts x 32 bearings"
    add(case, "seatrack solve_many, operator start", m_many_op[0] * 1e3, "ms", 1.0,
        f"(min {m_many_op[1] * 1e3:.1f})")  # fmt: skip
    add(case, "scipy least_squares loop, same start", m_loop[0] * 1e3, "ms",
        m_loop[0] / m_many_op[0], f"(min {m_loop[1] * 1e3:.1f})")  # fmt: skip
    add(case, "seatrack solve_many, automatic start", m_many[0] * 1e3, "ms",
        m_many[0] / m_many_op[0], f"(min {m_many[1] * 1e3:.1f})")  # fmt: skip
    add(case, "seatrack solve loop, automatic start", m_one[0] * 1e3, "ms", m_one[0] / m_many_op[0])

    print(
        "Bearings-only TMA (ratio: accuracy rows vs the CRB; time rows vs the ratio-1 row of the "
        "case; times are CPU ms)"
    )
    cols = [("case", "case"), ("method", "method"), ("value", "value", ".4g"), ("unit", "unit"),
            ("ratio", "ratio", ".3g"), ("note", "note")]  # fmt: skip
    print(format_table(rows, cols))


if __name__ == "__main__":
    main()
