"""Multi-target metrics: OSPA, GOSPA (with its decomposition), id switches, fragmentation.

GOSPA (Rahmathullah, Garcia-Fernandez & Svensson, "Generalized optimal sub-pattern
assignment metric", FUSION 2017) with ``alpha = 2``, cut-off ``c`` and order ``p``, between
the true set ``X`` (``n`` targets) and the estimated set ``Y`` (``m`` tracks)::

    d(X, Y) = ( min_gamma sum_{(i,j) in gamma} d(x_i, y_j)^p + c^p/2 (n + m - 2|gamma|) )^(1/p)

over partial assignments ``gamma`` of pairs with ``d(x_i, y_j) < c`` (paper, Proposition 1).
Every truth left out is a *missed* target and every estimate left out a *false* one, each
costing ``c^p / 2``; the assigned pairs make the *localisation* part. The minimum equals the
best complete assignment of ``min(n, m)`` pairs with costs ``min(d^p, c^p)``, plus
``c^p / 2 |n - m|`` (a pair at ``d >= c`` costs exactly one missed plus one false target),
which is how it is computed here: an optimal assignment per cluster of truths and
estimates closer than ``c`` (a KD-tree finds the pairs), so the cost grows about linearly
with the number of targets.

OSPA (Schuhmacher, Vo & Vo 2008) is the normalised form with the same cut-off:
``( (min_perm sum min(d, c)^p + c^p |n - m|) / max(n, m) )^(1/p)``.

Identity metrics over a run match truths to tracks scan by scan as CLEAR MOT does
(Bernardin & Stiefelhagen 2008): a truth keeps last scan's track while that track is
within ``c``, the others are matched by the GOSPA assignment of what is left (so two
targets passing within metres of each other do not count as a swap). An *id switch* is a
truth whose matched track differs from the track it was last matched to; a
*fragmentation* is a truth that was tracked, lost its track, and is tracked again later.

:func:`evaluate_multitarget` runs ``seatrack evaluate`` on a scenario with a
``[multitarget]`` table: seeded runs of :mod:`seatrack.simulate.multitarget`, the tracker of
:mod:`seatrack.tracking` with GNN and JPDA, and these scores.

Positions in metres; times in seconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "GospaResult",
    "gospa",
    "ospa",
    "ScanScores",
    "RunScores",
    "score_run",
    "MULTITARGET_COLUMNS",
    "TrackedRun",
    "simulate_scenario",
    "track_scenario_run",
    "summary_row",
    "gospa_series",
    "evaluate_multitarget",
]


@dataclass(frozen=True)
class GospaResult:
    """GOSPA between two sets at one time (``alpha = 2``).

    Attributes
    ----------
    distance : m -- ``(localisation + missed + false)^(1/p)``
    localisation, missed, false : the three parts of ``distance^p`` (m^p)
    n_missed, n_false : numbers of missed truths and false estimates
    truth_to_est : (n,) int -- estimate assigned to each truth (-1: missed)
    """

    distance: float
    localisation: float
    missed: float
    false: float
    n_missed: int
    n_false: int
    truth_to_est: IntArray


def _as_points(a: ArrayLike) -> FloatArray:
    x = np.asarray(a, dtype=float)
    if x.ndim == 1:
        x = x[:, None] if x.size else x.reshape(0, 1)
    return x


def _check(c: float, p: float) -> None:
    if not (np.isfinite(c) and c > 0):
        raise ValueError(f"cut-off c must be a positive number, got {c}")
    if not (np.isfinite(p) and p >= 1):
        raise ValueError(f"order p must be a number >= 1, got {p}")


def _clusters(X: FloatArray, Y: FloatArray, c: float) -> tuple[IntArray, IntArray, int]:
    """Connected components of truths and estimates closer than ``c`` to each other."""
    n, m = len(X), len(Y)
    pairs = cKDTree(X).sparse_distance_matrix(cKDTree(Y), c, output_type="ndarray")
    i = pairs["i"].astype(np.int64)
    j = pairs["j"].astype(np.int64) + n
    g = coo_matrix((np.ones(i.size), (i, j)), shape=(n + m, n + m))
    k, label = connected_components(g, directed=False)
    return label[:n], label[n:], int(k)


def gospa(truth: ArrayLike, estimates: ArrayLike, c: float = 100.0, p: float = 2.0) -> GospaResult:
    """GOSPA (``alpha = 2``) between truth positions ``(n, d)`` and estimates ``(m, d)``.

    Parameters
    ----------
    truth, estimates : positions, m (rows are points; 1-D input is one coordinate per point)
    c : cut-off distance, m
    p : order, >= 1

    Returns
    -------
    GospaResult
    """
    _check(c, p)
    X, Y = _as_points(truth), _as_points(estimates)
    n, m = len(X), len(Y)
    t2e = np.full(n, -1, np.int64)
    half = c**p / 2.0
    if n == 0 or m == 0:
        return GospaResult((half * (n + m)) ** (1 / p), 0.0, half * n, half * m, n, m, t2e)
    if X.shape[1] != Y.shape[1]:
        raise ValueError(f"truth has {X.shape[1]} coordinates, estimates {Y.shape[1]}")
    lx, ly, k = _clusters(X, Y, c)
    loc = 0.0
    ox, oy = np.argsort(lx, kind="stable"), np.argsort(ly, kind="stable")
    bx = np.searchsorted(lx[ox], np.arange(k + 1))
    by = np.searchsorted(ly[oy], np.arange(k + 1))
    for q in range(k):
        ix, iy = ox[bx[q] : bx[q + 1]], oy[by[q] : by[q + 1]]
        if ix.size == 0 or iy.size == 0:
            continue
        D = np.linalg.norm(X[ix, None, :] - Y[None, iy, :], axis=-1)
        cost = np.minimum(D, c) ** p
        r, s = linear_sum_assignment(cost)
        ok = D[r, s] < c
        loc += float(cost[r[ok], s[ok]].sum())
        t2e[ix[r[ok]]] = iy[s[ok]]
    n_ass = int((t2e >= 0).sum())
    n_missed, n_false = n - n_ass, m - n_ass
    total = loc + half * (n_missed + n_false)
    return GospaResult(
        total ** (1 / p), loc, half * n_missed, half * n_false, n_missed, n_false, t2e
    )


def ospa(truth: ArrayLike, estimates: ArrayLike, c: float = 100.0, p: float = 2.0) -> float:
    """OSPA distance (m) between truth ``(n, d)`` and estimates ``(m, d)``; 0 for two empty
    sets, ``c`` when exactly one is empty."""
    _check(c, p)
    X, Y = _as_points(truth), _as_points(estimates)
    n, m = len(X), len(Y)
    if n == 0 and m == 0:
        return 0.0
    if n == 0 or m == 0:
        return float(c)
    D = np.minimum(np.linalg.norm(X[:, None, :] - Y[None, :, :], axis=-1), c) ** p
    r, s = linear_sum_assignment(D)
    total = float(D[r, s].sum()) + c**p * abs(n - m)
    return float((total / max(n, m)) ** (1 / p))


@dataclass(frozen=True)
class ScanScores:
    """Per-scan GOSPA series of a run (each array has one value per scan time ``t``)."""

    t: FloatArray
    gospa: FloatArray
    localisation: FloatArray
    missed: FloatArray
    false: FloatArray
    n_missed: IntArray
    n_false: IntArray
    n_truth: IntArray


@dataclass(frozen=True)
class RunScores:
    """Scores of one tracker run against the truth.

    Attributes
    ----------
    scans : ScanScores -- the per-scan GOSPA series
    c, p : the GOSPA parameters used
    id_switches : truths whose assigned track changed (summed over the run)
    fragmentations : interruptions of a truth's tracking that were later resumed
    """

    scans: ScanScores
    c: float
    p: float
    id_switches: int
    fragmentations: int

    @property
    def mean_gospa(self) -> float:
        """Mean over scans of the GOSPA distance, m."""
        return float(np.mean(self.scans.gospa)) if self.scans.gospa.size else 0.0

    def rms_parts(self) -> dict[str, float]:
        """``(mean over scans of each part)^(1/p)``: RMS GOSPA and its localisation, missed
        and false parts for p = 2 (their p-th powers add up)."""
        s, q = self.scans, 1.0 / self.p
        if s.gospa.size == 0:
            return {"gospa": 0.0, "localisation": 0.0, "missed": 0.0, "false": 0.0}
        return {
            "gospa": float(np.mean(s.gospa**self.p) ** q),
            "localisation": float(np.mean(s.localisation) ** q),
            "missed": float(np.mean(s.missed) ** q),
            "false": float(np.mean(s.false) ** q),
        }


def _groups(t: FloatArray, times: FloatArray) -> tuple[IntArray, IntArray]:
    """Row order by time and the slice bounds of each of ``times``."""
    order = np.argsort(t, kind="stable")
    ts = t[order]
    return order, np.searchsorted(ts, np.concatenate([times, [np.inf]]), side="left")


def _identity_matches(
    X: FloatArray, Y: FloatArray, previous: IntArray, est_id: IntArray, c: float, p: float
) -> IntArray:
    """Track id matched to each truth for the identity metrics (CLEAR MOT rule): a truth
    keeps last scan's track while it is closer than ``c``; the others are matched by the
    optimal (GOSPA) assignment among what is left. -1: unmatched."""
    out = np.full(len(X), -1, np.int64)
    free_y = np.ones(len(Y), bool)
    pos_of = {int(e): j for j, e in enumerate(est_id)}
    for i, prev in enumerate(previous):
        j = pos_of.get(int(prev), -1) if prev >= 0 else -1
        if j >= 0 and free_y[j] and np.linalg.norm(X[i] - Y[j]) < c:
            out[i] = prev
            free_y[j] = False
    rest_x = np.flatnonzero(out < 0)
    rest_y = np.flatnonzero(free_y)
    if rest_x.size and rest_y.size:
        g = gospa(X[rest_x], Y[rest_y], c, p)
        ok = g.truth_to_est >= 0
        out[rest_x[ok]] = est_id[rest_y[g.truth_to_est[ok]]]
    return out


def score_run(
    times: ArrayLike,
    truth_t: ArrayLike,
    truth_id: Sequence[object] | ArrayLike,
    truth_pos: ArrayLike,
    est_t: ArrayLike,
    est_id: Sequence[object] | ArrayLike,
    est_pos: ArrayLike,
    c: float = 100.0,
    p: float = 2.0,
) -> RunScores:
    """GOSPA per scan, id switches and fragmentation of a tracker run.

    Parameters
    ----------
    times : (K,) s -- the scan times to score (truth and estimates are matched exactly)
    truth_t, truth_id, truth_pos : one row per (scan, live target): time, target id,
        position ``(N, d)`` m
    est_t, est_id, est_pos : one row per (scan, reported track), same layout
    c, p : GOSPA cut-off (m) and order

    Returns
    -------
    RunScores
    """
    tk = np.asarray(times, dtype=float)
    tt, et = np.asarray(truth_t, dtype=float), np.asarray(est_t, dtype=float)
    tpos, epos = _as_points(truth_pos), _as_points(est_pos)
    tid = np.unique(np.asarray(truth_id), return_inverse=True)[1].ravel()
    eid = np.unique(np.asarray(est_id), return_inverse=True)[1].ravel()
    to, tb = _groups(tt, tk)
    eo, eb = _groups(et, tk)
    K = tk.size
    parts = np.zeros((4, K))
    counts = np.zeros((3, K), np.int64)
    last = np.full(int(tid.max(initial=-1)) + 1, -1, np.int64)  # last track of each truth
    lost = np.zeros(last.size, bool)  # tracked before, not tracked now
    switches = frags = 0
    for k in range(K):
        ti, ei = to[tb[k] : tb[k + 1]], eo[eb[k] : eb[k + 1]]
        g = gospa(tpos[ti], epos[ei], c, p)
        parts[:, k] = g.distance, g.localisation, g.missed, g.false
        counts[:, k] = g.n_missed, g.n_false, ti.size
        ids = tid[ti]
        trk = _identity_matches(tpos[ti], epos[ei], last[ids], eid[ei], c, p)
        ok = trk >= 0
        had = last[ids] >= 0
        switches += int(np.count_nonzero(ok & had & (trk != last[ids])))
        frags += int(np.count_nonzero(ok & lost[ids]))
        lost[ids] = ~ok & had
        last[ids[ok]] = trk[ok]
    scans = ScanScores(tk, *parts, *counts)
    return RunScores(scans, float(c), float(p), switches, frags)


# ---------------------------------------------------------------------------
# Multi-target scenarios (``seatrack evaluate`` on a scenario with [multitarget])
# ---------------------------------------------------------------------------
#: columns of the multi-target evaluation table (key, header, format)
MULTITARGET_COLUMNS = [
    ("tracker", "tracker", ""),
    ("gospa", "GOSPA m", ".1f"),
    ("rms", "RMS GOSPA m", ".1f"),
    ("localisation", "loc m", ".1f"),
    ("missed", "missed m", ".1f"),
    ("false", "false m", ".1f"),
    ("n_missed", "missed/scan", ".2f"),
    ("n_false", "false/scan", ".2f"),
    ("id_switches", "id switches", ".1f"),
    ("fragmentations", "fragments", ".1f"),
    ("ms_per_scan", "ms/scan", ".2f"),
]


@dataclass(frozen=True)
class TrackedRun:
    """One tracker on one simulated run: its output, its scores, the wall time per scan."""

    sim: Any
    out: Any
    scores: RunScores
    ms_per_scan: float


def simulate_scenario(scenario: Any, rng: np.random.Generator, sensor: Any) -> Any:
    """One run of a multi-target scenario (``[multitarget]`` population plus the scripted
    ``[[targets]]``) seen by ``sensor`` (fixed, or on the own-ship)."""
    from seatrack.simulate.multitarget import simulate_multitarget

    t = np.arange(0.0, scenario.duration + 1e-9, min(scenario.dt, sensor.scan_period))
    observer = sensor.position if sensor.position is not None else scenario.ownship.trajectory(t)
    return simulate_multitarget(
        scenario.multitarget, sensor, scenario.duration, rng, observer, scenario.targets
    )


def track_scenario_run(
    sim: Any, method: str, table: dict[str, Any], association: str, c: float, p: float
) -> TrackedRun:
    """The multi-target tracker (per-track filter ``method``, configuration ``table`` of
    sensor, tracker and method keys) on one simulated run, scored against its truth."""
    from seatrack.config import parse_config
    from seatrack.io.multitarget import make_filter
    from seatrack.io.multitarget import sensor_noise
    from seatrack.io.multitarget import split_config
    from seatrack.tracking import Tracker
    from seatrack.tracking import TrackerConfig

    t_tab, m_tab = split_config(table, "scenario")
    sensor = sensor_noise(m_tab, "scenario")
    tcfg = parse_config(TrackerConfig, {**t_tab, "association": association}, source="scenario")
    flt, _ = make_filter(method, m_tab, sim.plots, "scenario", tcfg)
    tracker = Tracker(flt.filter, sensor=sensor, config=tcfg)
    out = tracker.run(flt.prepare(sim.plots))
    d = 2
    pos = np.stack([out.columns["x_m"], out.columns["y_m"]], -1) if out.t.size else np.zeros((0, d))
    scores = score_run(
        sim.scan_times, sim.truth_t, sim.truth_id, sim.truth_pos[:, :d], out.t, out.track, pos, c, p
    )
    return TrackedRun(sim, out, scores, 1000 * float(np.median(out.seconds_per_scan)))


def summary_row(
    name: str, scores: Sequence[RunScores], ms_per_scan: Sequence[float]
) -> dict[str, Any]:
    """Averages over runs of the scores of one tracker (one table row; ``ms_per_scan``:
    the median over runs of each run's time per scan)."""
    parts = [s.rms_parts() for s in scores]
    mean = lambda v: float(np.mean(v))  # noqa: E731
    return {
        "tracker": name,
        "gospa": mean([s.mean_gospa for s in scores]),
        "rms": mean([q["gospa"] for q in parts]),
        "localisation": mean([q["localisation"] for q in parts]),
        "missed": mean([q["missed"] for q in parts]),
        "false": mean([q["false"] for q in parts]),
        "n_missed": mean([s.scans.n_missed.mean() for s in scores]),
        "n_false": mean([s.scans.n_false.mean() for s in scores]),
        "id_switches": mean([s.id_switches for s in scores]),
        "fragmentations": mean([s.fragmentations for s in scores]),
        "ms_per_scan": float(np.median(ms_per_scan)),
    }


def gospa_series(scores: RunScores) -> dict[str, FloatArray]:
    """GOSPA and its parts (as ``p``-th roots, m) per scan, for plotting."""
    s, q = scores.scans, 1.0 / scores.p
    return {
        "t": s.t,
        "gospa": s.gospa,
        "localisation": s.localisation**q,
        "missed": s.missed**q,
        "false": s.false**q,
    }


#: peak bytes per run, target and scan of a multi-target evaluation, estimates (not
#: measured): the simulated plots and truth kept for every run, and per method and
#: association the tracker's output
MT_BYTES_PER_STEP = 200
MT_BYTES_PER_STEP_AND_TRACKER = 300
#: seconds per run, target, scan and tracker, an estimate (a plot through gating,
#: association and a filter update)
MT_SECONDS_PER_STEP = 2e-4


def require_multitarget(scenario: Any, sensor: Any, methods: Sequence[str], runs: int) -> float:
    """Refuse a multi-target evaluation over the memory or time budget
    (:mod:`seatrack.io.budget`): runs x expected targets x scans x trackers (each method
    with GNN and JPDA). Returns the estimated run time, seconds."""
    from seatrack.io.budget import require

    scans = int(np.floor(scenario.duration / sensor.scan_period + 1e-9)) + 1
    targets = len(scenario.targets) + scenario.multitarget.expected_targets(
        scenario.duration, sensor.scan_period
    )
    steps = float(runs) * max(targets, 1.0) * scans
    trackers = 2 * len(methods)
    seconds = steps * trackers * MT_SECONDS_PER_STEP
    require(
        f"evaluate: {runs} runs x {targets:.3g} targets x {scans} scans x {trackers} trackers",
        memory_bytes=steps * (MT_BYTES_PER_STEP + trackers * MT_BYTES_PER_STEP_AND_TRACKER),
        seconds=seconds,
    )
    return seconds


def evaluate_multitarget(
    scenario: Any,
    runs: int,
    seed: int,
    methods: Sequence[str] | None = None,
    sensor: str | None = None,
    csv_out: Any = None,
    plots: Any = None,
    c: float = 100.0,
    p: float = 2.0,
    progress: bool = True,
) -> str:
    """``seatrack evaluate`` on a multi-target scenario: every per-track filter in
    ``methods`` (default ``ekf``) with GNN and with JPDA, over ``runs`` seeded runs.

    The tracker is given the sensor's noise and the scenario's ``[evaluate.tracker]`` and
    ``[evaluate.<method>]`` tables, nothing else. Returns the printed report; writes the
    table to ``csv_out`` and, with ``plots`` (a folder), one picture per tracker of the
    first run (plots, tracks, truth, GOSPA over time). ``progress``: the estimate and
    progress lines of a long run (:mod:`seatrack.progress`).
    """
    from pathlib import Path

    from seatrack.evaluate.montecarlo import format_table
    from seatrack.evaluate.tracking import method_config
    from seatrack.evaluate.tracking import tracking_sensor
    from seatrack.io.atomic import atomic_write
    from seatrack.io.multitarget import save_picture
    from seatrack.progress import Progress

    sens = tracking_sensor(scenario, sensor)
    names = list(methods) if methods else ["ekf"]
    seconds = require_multitarget(scenario, sens, names, runs)
    # progress in tracked runs, one per run and tracker
    bar = Progress("seatrack evaluate", runs * 2 * len(names), "tracker runs", seconds,
                   shown=progress)  # fmt: skip
    sims = [
        simulate_scenario(scenario, np.random.default_rng(s), sens)
        for s in np.random.SeedSequence(seed).spawn(runs)
    ]
    tracker_table = scenario.extra.get("tracker", {})
    rows, firsts = [], {}
    for m in names:
        table = {**method_config(scenario, sens, m), **tracker_table}
        for assoc in ("gnn", "jpda"):
            tracked = []
            for sim in sims:
                tracked.append(track_scenario_run(sim, m, table, assoc, c, p))
                bar.advance()
            name = f"{m} + {assoc}"
            rows.append(
                summary_row(name, [r.scores for r in tracked], [r.ms_per_scan for r in tracked])
            )
            firsts[f"{m}_{assoc}"] = tracked[0]
    n_plots = np.mean([len(s.plots) / s.scan_times.size for s in sims])
    title = (
        f"{scenario.name}: {runs} run(s), seed {seed}, sensor {sens.name}, "
        f"{sims[0].scan_times.size} scans, {n_plots:.0f} plots/scan; GOSPA c = {c:g} m, "
        f"p = {p:g} (mean over scans; RMS parts)"
    )
    lines = [title, format_table(rows, MULTITARGET_COLUMNS)]
    if csv_out is not None:
        import csv

        with atomic_write(csv_out, newline="") as fh:
            w = csv.DictWriter(fh, [k for k, _, _ in MULTITARGET_COLUMNS])
            w.writeheader()
            w.writerows(rows)
        lines.append(f"wrote {csv_out}")
    if plots is not None:
        for key, tr in firsts.items():
            sim = tr.sim
            truth = {int(i): sim.truth_pos[sim.truth_id == i, :2] for i in np.unique(sim.truth_id)}
            path = Path(plots) / f"multitarget_{key}.png"
            save_picture(path, sim.plots, tr.out, truth, gospa_series(tr.scores),
                         title=f"{scenario.name}, run 1: {key.replace('_', ' + ')}")  # fmt: skip
            lines.append(f"wrote {path}")
    return "\n".join(lines)
