"""Bearings-only TMA benchmark: accuracy vs FilterPy / Stone Soup EKFs, speed vs SciPy.

Run: ``python benchmarks/tma.py [--quick] [--runs N] [--section all|bearings|frequency]``.
Prints one table per section.

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

Frequency section (:func:`frequency_section`) -- random geometries in four classes: own
ship on one steady leg or with one turn (40-140 deg), target straight or on two legs (a
30-90 deg course change at 55-65 % of the time, the leg time given to the solver); 60
bearings every 30 s (sigma 1 deg), one tonal with the base frequency (100-400 Hz) unknown,
frequency sigma 0.05 Hz, ATB sigma 10 deg, sound speed 1500 m/s; range 3-25 km, target
speed 2-10 m/s, own ship 3-8 m/s. Per geometry ``--runs`` noisy realisations are solved
from the automatic start (one :func:`seatrack.tma.solve_many` call) with bearings only,
bearings + frequency, and bearings + frequency + ATB. MSE/CRB: the squared final-position
error of each valid (observable, converged) run divided by the trace of its geometry's
final-position CRB (the joint bound with the base frequency a nuisance parameter),
averaged over the runs -- over every geometry whose CRB exists, and over the geometries
whose CRB range sigma is below 10 % of the range (in the note). "3 sigma" row: steady own
ship, bearings + frequency, every geometry with CRB range sigma below 10 % of the range --
the share of runs whose final range error is within 3 CRB sigma. Last row: 1,000 bearings +
1,000 frequencies of one steady-own-ship
geometry, automatic start, one leg.
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
from seatrack.information import SingularMatrixError
from seatrack.simulate import Leg
from seatrack.simulate import trajectory
from seatrack.simulate.tma import TMAScenario
from seatrack.simulate.tma import classic_scenario
from seatrack.simulate.tma import scenario_from_trajectories
from seatrack.tma import Bearings
from seatrack.tma import bearing_residuals
from seatrack.tma import crb
from seatrack.tma import leg_starts
from seatrack.tma import leg_time_matrix
from seatrack.tma import operator_values
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


MODES = ("bearings only", "bearings + frequency", "bearings + frequency + ATB")
SIGMA_HZ = 0.05
SIGMA_ATB = math.radians(10.0)


def random_case(rng: np.random.Generator, manoeuvre: bool, two_leg: bool, n: int = 60,
                dt: float = 30.0) -> tuple[TMAScenario, float]:  # fmt: skip
    """One geometry of the frequency section (module docstring) and its base frequency."""
    T = (n - 1) * dt
    times = dt * np.arange(n)
    if manoeuvre:
        turn = rng.choice([-1, 1]) * rng.uniform(math.radians(40), math.radians(140))
        legs = [Leg.straight(rng.uniform(0.3, 0.5) * T), Leg.turn(turn, math.radians(2.0)),
                Leg.straight(2 * T)]  # fmt: skip
    else:
        legs = [Leg.straight(2 * T)]
    obs = trajectory([0, 0], rng.uniform(0, 2 * np.pi), rng.uniform(3, 8), legs, times=times)
    r0, b0 = rng.uniform(3000, 25000), rng.uniform(0, 2 * np.pi)
    tlegs, man = [Leg.straight(2 * T)], []
    if two_leg:
        t1 = float(times[int(rng.uniform(0.55, 0.65) * n)])
        change = rng.choice([-1, 1]) * rng.uniform(math.radians(30), math.radians(90))
        rate = math.radians(30.0)  # a quick turn (<= 3 s) at the leg time
        tlegs = [Leg.straight(t1), Leg.turn(change, rate), Leg.straight(2 * T)]
        man = [t1 + 1e-3]
    tgt = trajectory([r0 * math.sin(b0), r0 * math.cos(b0)], rng.uniform(0, 2 * np.pi),
                     rng.uniform(2, 10), tlegs, times=times)  # fmt: skip
    return scenario_from_trajectories(tgt, obs, math.radians(1.0), man), float(
        rng.uniform(100, 400)
    )


def _case_crb(sc: TMAScenario, f0: float, mode: int) -> np.ndarray | None:
    """Joint CRB (state, f0) of a mode, or None when singular."""
    rng = np.random.default_rng(0)  # values are replaced by the noise-free ones
    kw: dict = {}
    if mode >= 1:
        kw = {"frequencies": sc.frequencies(rng, f0, SIGMA_HZ), "base_frequency": {"1": f0}}
    if mode == 2:
        kw["bow_angles"] = sc.bow_angles(rng, SIGMA_ATB)
    try:
        return crb(sc.state, sc.times, sc.observer.pos, sc.sigma, sc.manoeuvres, **kw)
    except SingularMatrixError:
        return None


def frequency_section(n_geom: int, n_runs: int, seed: int) -> list[dict]:
    """Rows of the frequency section (module docstring)."""
    from dataclasses import replace

    rng = np.random.default_rng(seed)
    rows: list[dict] = []
    classes = [(m, tl) for m in (False, True) for tl in (False, True)]
    stats = {(c, k): {"e2": 0.0, "b": 0.0, "e2s": 0.0, "bs": 0.0, "ok": 0, "n": 0, "it": 0,
                      "t": 0.0, "g": 0, "gs": 0} for c in classes for k in range(3)}  # fmt: skip
    shares: list[float] = []
    for c in classes:
        for _ in range(n_geom):
            sc, f0 = random_case(rng, *c)
            tl = float(sc.times[-1])
            truth = sc.target.pos[-1, :2]
            rng_true = float(np.hypot(*(truth - sc.observer.pos[-1, :2])))
            data = []
            for _ in range(n_runs):
                b = sc.bearings(rng)
                fr, ab = sc.frequencies(rng, f0, SIGMA_HZ), sc.bow_angles(rng, SIGMA_ATB)
                data.append((b, replace(b, frequencies=fr), replace(b, frequencies=fr,
                                                                   bow_angles=ab)))  # fmt: skip
            for k in range(3):
                st = stats[(c, k)]
                P = _case_crb(sc, f0, k)
                contacts = {str(i): d[k] for i, d in enumerate(data)}
                t = time.process_time()
                sols = solve_many(contacts, manoeuvres=list(sc.manoeuvres) or None)
                st["t"] += time.process_time() - t
                valid = [s for s in sols.values() if s.valid]
                st["ok"] += len(valid)
                st["n"] += n_runs
                st["it"] += sum(s.iterations for s in sols.values())
                if P is None:
                    continue
                Pp = position_crb(P, sc.starts, tl)
                _, G = operator_values(sc.state, sc.starts, tl, sc.observer.pos[-1, :2])
                s_rng = float(np.sqrt(G[2] @ P[: G.shape[1], : G.shape[1]] @ G[2]))
                e2 = [float(np.sum((s.position_at(np.array([tl]))[0] - truth) ** 2))
                      for s in valid]  # fmt: skip
                st["g"] += 1
                st["e2"] += sum(e2) / float(np.trace(Pp))  # each run's error over its bound
                st["b"] += len(e2)
                if s_rng < 0.1 * rng_true:
                    st["gs"] += 1
                    st["e2s"] += sum(e2) / float(np.trace(Pp))
                    st["bs"] += len(e2)
                    if k == 1 and not c[0]:
                        inside = [abs(s.last.range - rng_true) < 3 * s_rng if s.valid else False
                                  for s in sols.values()]  # fmt: skip
                        shares.append(float(np.mean(inside)))
    for c in classes:
        name = (("own ship turns" if c[0] else "own ship steady") + ", "
                + ("two-leg target" if c[1] else "straight target"))  # fmt: skip
        for k in range(3):
            st = stats[(c, k)]
            ratio = st["e2"] / st["b"] if st["b"] else None
            ratio_s = st["e2s"] / st["bs"] if st["bs"] else None
            note = (f"{st['ok'] / st['n']:.0%} valid, {st['it'] / st['n']:.0f} it, "
                    f"{st['t'] / st['n'] * 1e3:.1f} ms/run; CRB {st['g']}/{n_geom} geometries, "
                    f"range sigma <10%: {st['gs']} (MSE/CRB "
                    + (f"{ratio_s:.2f})" if ratio_s is not None else "n/a)"))  # fmt: skip
            rows.append({"case": name if k == 0 else "", "method": MODES[k], "value": ratio,
                         "unit": "MSE/CRB", "ratio": None, "note": note})  # fmt: skip
    good = sum(x >= 0.95 for x in shares)
    rows.append({"case": "steady own ship, 3 sigma", "method": MODES[1],
                 "value": min(shares) if shares else None, "unit": "worst share",
                 "ratio": None, "note": f"{good}/{len(shares)} geometries with >= 95 % of runs "
                 "within 3 CRB sigma of the final range"})  # fmt: skip
    # speed: 1,000 bearings + 1,000 frequencies, automatic start
    times = np.linspace(0.0, 3600.0, 1000)
    obs = trajectory([0, 0], 0.3, 5.0, [Leg.straight(4000.0)], times=times)
    tgt = trajectory([9000, 7000], 4.2, 6.0, [Leg.straight(4000.0)], times=times)
    sc = scenario_from_trajectories(tgt, obs, math.radians(1.0))
    r = np.random.default_rng(seed + 1)
    b = replace(sc.bearings(r), frequencies=sc.frequencies(r, 300.0, SIGMA_HZ))
    sol = solve(b)
    m = timeit(lambda: solve(b), 20)
    rows.append(
        {
            "case": "1,000 bearings + 1,000 freq.",
            "method": "seatrack, automatic start",
            "value": m[0] * 1e3,
            "unit": "ms",
            "ratio": None,
            "note": f"(min {m[1] * 1e3:.2f}) {sol.iterations} it, valid {sol.valid}",
        }
    )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="few runs and repeats (smoke test)")
    ap.add_argument(
        "--runs",
        type=int,
        default=None,
        help="Monte-Carlo runs (default 300, frequency section 100; quick 30 / 10)",
    )
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--section", choices=("all", "bearings", "frequency"), default="all")
    ap.add_argument(
        "--geometries",
        type=int,
        default=None,
        help="geometries per class in the frequency section (default 40; quick 6)",
    )
    args = ap.parse_args()
    cols = [("case", "case"), ("method", "method"), ("value", "value", ".4g"), ("unit", "unit"),
            ("ratio", "ratio", ".3g"), ("note", "note")]  # fmt: skip
    if args.section in ("all", "frequency"):
        n_geom = args.geometries or (6 if args.quick else 40)
        runs_f = args.runs or (10 if args.quick else 100)
        print(f"TMA with frequency and ATB ({n_geom} geometries per class, {runs_f} runs each)")
        print(format_table(frequency_section(n_geom, runs_f, args.seed), cols))
    if args.section == "frequency":
        return
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
    print(format_table(rows, cols))


if __name__ == "__main__":
    main()
