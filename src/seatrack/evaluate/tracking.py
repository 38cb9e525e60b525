"""Monte-Carlo comparison of plot-driven track methods on a scenario.

Each run simulates the scenario (:meth:`seatrack.simulate.scenarios.Scenario.simulate`),
turns each target's detections of one active sensor into an in-memory
:class:`~seatrack.filters.base.Plots` and runs every selected method of
:data:`seatrack.filters.registry.METHODS` on it. Outputs are put back on the full scan grid
(NaN where a scan was missed), so runs stack into fixed-size arrays.

Consistency: the methods report per-axis standard deviations (``std_x_m`` ...), not full
covariances, so the statistic computed is the per-axis normalised error squared
``(e_x / std_x)^2``. Its marginal distribution is chi-square with 1 degree of freedom for
a consistent filter whatever the cross-correlations, so its average over ``N`` independent
runs at one step must lie in :func:`~seatrack.evaluate.metrics.chi2_interval` ``(1, N)``
with probability 95 %. The table reports the time-averaged value and the fraction of
(step, axis) pairs inside those bounds.
"""

from __future__ import annotations

import functools
import math
import time
import warnings
from collections.abc import Mapping
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.evaluate.metrics import chi2_interval
from seatrack.evaluate.metrics import rms_over_time
from seatrack.evaluate.montecarlo import Column
from seatrack.evaluate.montecarlo import MonteCarloResult
from seatrack.evaluate.montecarlo import monte_carlo
from seatrack.progress import Progress
from seatrack.simulate.files import plots_from_measurements
from seatrack.simulate.scenarios import Scenario
from seatrack.simulate.scenarios import SensorConfig
from seatrack.simulate.scenarios import SensorData

FloatArray = NDArray[np.float64]

__all__ = [
    "require_evaluation",
    "MethodRun",
    "method_config",
    "run_methods",
    "tracking_sensor",
    "compare_methods",
    "summarize",
    "time_histories",
    "position_crb",
    "velocity_prior_information",
    "SUMMARY_COLUMNS",
]

#: columns of the comparison table (key, header, format)
SUMMARY_COLUMNS = [
    Column("method", "method"),
    Column("pos_rmse_m", "pos RMSE m", ".1f"),
    Column("vel_rmse_mps", "vel RMSE m/s", ".2f"),
    Column("rmse_over_crb", "RMSE/CRB", ".2f"),
    Column("peak_pos_m", "peak pos m", ".0f"),
    Column("anees_x", "ANEES x", ".2f"),
    Column("anees_y", "ANEES y", ".2f"),
    Column("in_bounds_pct", "in 95% %", ".0f"),
    Column("us_per_plot", "µs/plot", ".0f"),
    Column("failures", "failed"),
]

_AXES = ("x", "y", "z")


def tracking_sensor(scenario: Scenario, name: str | None = None) -> SensorConfig:
    """The sensor whose plots the track methods take: ``name``, or the first active one."""
    for s in scenario.sensors:
        if (name is None and not s.is_passive) or s.name == name:
            if s.is_passive:
                raise ValueError(
                    f"sensor {s.name!r} is a passive sonar; track methods need range and azimuth"
                )
            return s
    if name is None:
        raise ValueError(
            f"scenario {scenario.name!r} has no active sensor (range + azimuth) to track with"
        )
    raise ValueError(f"scenario {scenario.name!r} has no sensor {name!r}")


def method_config(scenario: Scenario, sensor: SensorConfig, method: str) -> dict[str, Any]:
    """Configuration passed to a method: the sensor's sigmas, then ``[evaluate.<method>]``.

    The sensor's noise standard deviations go in as ``sigma_azimuth_deg``,
    ``sigma_range_m``, ``sigma_elevation_deg``, ``sigma_range_rate_mps`` -- the keys every
    track method accepts (:data:`seatrack.filters.registry.SENSOR_KEYS`); a scenario
    table ``[evaluate.<method>]`` adds or overrides keys.
    """
    cfg: dict[str, Any] = {}
    keys = {
        "azimuth": ("sigma_azimuth_deg", True),
        "range": ("sigma_range_m", False),
        "elevation": ("sigma_elevation_deg", True),
        "range_rate": ("sigma_range_rate_mps", False),
    }
    for c, s in zip(sensor.components, sensor.sigma, strict=True):
        k, angle = keys[c]
        cfg[k] = math.degrees(s) if angle else float(s)
    extra = scenario.extra.get(method, {})
    if isinstance(extra, Mapping):
        cfg.update(extra)
    return cfg


@dataclass(frozen=True)
class MethodRun:
    """One method on one target: outputs on the full scan grid (NaN = no plot)."""

    pos: FloatArray  # (N, 3)
    vel: FloatArray  # (N, 3)
    std: FloatArray  # (N, 3)
    seconds: float
    n_plots: int
    error: str = ""


def run_methods(
    data: SensorData,
    methods: Sequence[str],
    configs: Mapping[str, Mapping[str, Any]],
    catch: bool = True,
) -> dict[str, list[MethodRun]]:
    """Run each method on each target's plots of one sensor.

    Parameters
    ----------
    data : one sensor's simulated data
    methods : names in :data:`seatrack.filters.registry.METHODS`
    configs : method -> configuration (see :func:`method_config`)
    catch : record a method's exception as a failed run instead of raising

    Returns
    -------
    dict method -> list (one per target) of MethodRun
    """
    from seatrack.filters.registry import run

    out: dict[str, list[MethodRun]] = {}
    for name in methods:
        cfg = dict(configs.get(name, {}))
        runs = []
        for j, meas in enumerate(data.measurements):
            n = data.t.size
            pos = np.full((n, 3), np.nan)
            vel = np.full((n, 3), np.nan)
            std = np.full((n, 3), np.nan)
            plots = plots_from_measurements(meas, str(j))
            t0 = time.perf_counter()
            try:
                cols = run(name, plots, cfg, source=f"evaluate.{name}")
            except Exception as exc:  # a failing method is reported, not fatal
                if not catch:
                    raise
                runs.append(
                    MethodRun(pos, vel, std, 0.0, len(plots), f"{type(exc).__name__}: {exc}")
                )
                continue
            dt = time.perf_counter() - t0
            idx = plots.line
            for k, a in enumerate(_AXES):
                pos[idx, k] = cols[f"{a}_m"]
                vel[idx, k] = cols[f"v{a}_mps"]
                std[idx, k] = cols[f"std_{a}_m"]
            runs.append(MethodRun(pos, vel, std, dt, len(plots)))
        out[name] = runs
    return out


def _mc_run(
    rng: np.random.Generator,
    run: int,
    scenario: Scenario,
    sensor: str,
    methods: tuple[str, ...],
    configs: Mapping[str, Mapping[str, Any]],
) -> dict[str, Any]:
    sim = scenario.simulate(rng)
    data = sim.sensor(sensor)
    res = run_methods(data, methods, configs)
    truth_pos = np.stack([tr.pos for tr in data.truth])  # (targets, N, 3)
    truth_vel = np.stack([tr.vel for tr in data.truth])
    out: dict[str, Any] = {}
    for m, runs in res.items():
        out[f"{m}/pos_err"] = np.stack([r.pos for r in runs]) - truth_pos
        out[f"{m}/vel_err"] = np.stack([r.vel for r in runs]) - truth_vel
        out[f"{m}/std"] = np.stack([r.std for r in runs])
        out[f"{m}/seconds"] = np.array(sum(r.seconds for r in runs))
        out[f"{m}/plots"] = np.array(sum(r.n_plots for r in runs))
        out[f"{m}/failed"] = np.array(sum(bool(r.error) for r in runs))
    return out


def compare_methods(
    scenario: Scenario,
    methods: Sequence[str],
    runs: int,
    seed: int,
    sensor: str | None = None,
    processes: int = 1,
    progress: Progress | None = None,
) -> MonteCarloResult:
    """Monte-Carlo runs of ``methods`` on ``scenario`` (see module docstring); ``progress``
    is told of every finished run.

    Returns
    -------
    MonteCarloResult
        Per method ``m``: ``m/pos_err``, ``m/vel_err``, ``m/std`` of shape
        ``(runs, targets, scans, 3)`` (m, m/s; NaN where no plot), and per run
        ``m/seconds``, ``m/plots``, ``m/failed``.
    """
    from seatrack.filters.registry import METHODS

    for k in scenario.extra:
        if k not in METHODS:
            raise ValueError(
                f"{scenario.path}: evaluate.{k}: no track method {k!r}; known: {', '.join(METHODS)}"
            )
    s = tracking_sensor(scenario, sensor)
    configs = {m: method_config(scenario, s, m) for m in methods}
    fn = functools.partial(
        _mc_run,
        scenario=scenario,
        sensor=s.name,
        methods=tuple(methods),
        configs=configs,
    )
    return monte_carlo(fn, runs, seed, processes=processes, progress=progress)


#: peak bytes per method, run, target and scan of an evaluation: position and velocity
#: errors and sigmas (9 floats) in each run's result and in the stacked arrays
EVAL_BYTES_PER_STEP = 144
#: seconds per method, run, target and scan (one plot through a filter, with the
#: simulation and bookkeeping: 3.4e-4 s measured for ekf, 200 runs of linear_cv on a
#: loaded 2-core machine)
EVAL_SECONDS_PER_STEP = 3e-4


def require_evaluation(
    scenario: Scenario, sensor: SensorConfig, methods: Sequence[str], runs: int, processes: int
) -> float:
    """Refuse an evaluation over the memory or time budget (:mod:`seatrack.io.budget`):
    runs x methods x targets x scans, each held as :data:`EVAL_BYTES_PER_STEP` bytes and
    taking :data:`EVAL_SECONDS_PER_STEP` seconds (divided among the processes). Returns
    the estimated run time, seconds."""
    from seatrack.io.budget import require

    scans = int(sensor.scan_times(scenario.duration).size)
    targets = max(len(scenario.targets), 1)
    steps = float(runs) * len(methods) * targets * scans
    seconds = steps * EVAL_SECONDS_PER_STEP / max(processes, 1)
    require(
        f"evaluate: {runs} runs x {len(methods)} methods x {targets} target(s) x {scans} scans",
        memory_bytes=steps * EVAL_BYTES_PER_STEP,
        seconds=seconds,
    )
    return seconds


def velocity_prior_information(
    scenario: Scenario, sensor: str | None, methods: Sequence[str], d: int
) -> FloatArray:
    """Information ``(2d, 2d)`` of the velocity prior the ``methods`` start from.

    Every method starts a track from one plot with a zero-mean velocity prior of standard
    deviation ``initial_speed_sigma`` per axis (:func:`seatrack.filters.base.plot_gaussian`,
    read here from each configured method's initiator). The bound takes the most
    informative of them (the smallest sigma), so that it stays below every method's own.
    """
    from seatrack.filters.base import Plots
    from seatrack.filters.registry import build

    s = tracking_sensor(scenario, sensor)
    probe = Plots(np.zeros(1), np.full(1, 1000.0), np.zeros(1),
                  np.zeros(1) if d == 3 else None)  # fmt: skip
    info = np.zeros((2 * d, 2 * d))
    rr = "range_rate" in s.components
    for m in methods:
        try:
            method = build(m, method_config(scenario, s, m), d=d, range_rate=rr)
        except ValueError:  # a method these plots cannot run (it is reported as failed)
            continue
        _, P = method.initiate(probe)
        Pv = np.asarray(P)[0, -d:, -d:]
        info[d:, d:] = np.maximum(info[d:, d:], np.linalg.inv(Pv))
    return info


def position_crb(
    scenario: Scenario, sensor: str | None = None, methods: Sequence[str] | None = None
) -> FloatArray | None:
    """Cramér–Rao bound of the position of constant-velocity targets, per target and scan.

    The bound is :func:`~seatrack.evaluate.bounds.crb_deterministic` (no process noise:
    the target is known to move in a straight line at constant speed and is tracked from
    its first plot) with the expected measurement information ``p_detect H^T R^-1 H``
    (exact for missed detections without clutter, which is what the methods receive: each
    target's own plots). Jacobians are evaluated on the truth. With ``methods`` it is the
    posterior CRB with the velocity prior those methods start from
    (:func:`velocity_prior_information`) added at the first scan; without, no prior.

    Returns
    -------
    ndarray (targets, scans) or None
        ``sqrt(trace)`` of the position block (m; NaN while not yet observable), or None
        when the bound does not apply: a target manoeuvres, the noise is contaminated
        (``epsilon > 0``), a 2-D sensor sees height differences, or a target is on the
        sensor at a scan (its bearing, and the information, undefined).
    """
    from seatrack.evaluate.bounds import crb_deterministic
    from seatrack.models.measurement import RangeBearing
    from seatrack.models.measurement import RangeBearingElevation
    from seatrack.models.measurement import RangeRate
    from seatrack.models.measurement import Stacked
    from seatrack.models.motion import cv_transition

    s = tracking_sensor(scenario, sensor)
    if s.epsilon > 0 or any(len(p.legs) for p in scenario.targets):
        return None
    d = 3 if "elevation" in s.components else 2
    t = s.scan_times(scenario.duration)
    if s.position is None:
        own = scenario.ownship.trajectory(t)
        spos, svel = own.pos, own.vel
    else:
        spos, svel = np.broadcast_to(s.position, (t.size, 3)), np.zeros((t.size, 3))
    sig = dict(zip(s.components, s.sigma, strict=True))
    base: Any
    if d == 2:
        base = RangeBearing(n=4, pos=(0, 1))
    else:
        base = RangeBearingElevation(n=6, pos=(0, 1, 2))
    order = ["range", "azimuth"] + (["elevation"] if d == 3 else [])
    model: Any = base
    if "range_rate" in s.components:
        rr = RangeRate(n=2 * d, pos=tuple(range(d)), vel=tuple(range(d, 2 * d)))
        model = Stacked([base, rr])
        order.append("range_rate")
    Ri = np.diag([1.0 / sig[c] ** 2 for c in order])
    sensor_state = np.concatenate([spos[:, :d], svel[:, :d]], axis=-1)
    prior = None if methods is None else velocity_prior_information(scenario, sensor, methods, d)
    F = [cv_transition(float(h), d) for h in np.diff(t)]
    out = []
    for p in scenario.targets:
        tr = p.trajectory(t)
        if d == 2 and np.any(tr.pos[:, 2] != spos[:, 2]):
            return None  # slant range of a 2-D sensor: the 2-D model does not apply
        x = np.concatenate([tr.pos[:, :d], tr.vel[:, :d]], axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            H = model.jacobian(x, sensor_state)  # (scans, m, 2d)
        if not np.isfinite(H).all():
            return None  # a target on the sensor: the bearing and its information undefined
        info = s.p_detect * np.einsum("kji,jl,klm->kim", H, Ri, H)
        bound = crb_deterministic(info, F, prior=prior)
        out.append(np.sqrt(np.trace(bound[:, :d, :d], axis1=-2, axis2=-1)))
    return np.stack(out)


def time_histories(
    result: MonteCarloResult, methods: Sequence[str], dims: int = 2
) -> dict[str, dict[str, FloatArray]]:
    """Per-scan statistics of each method, over runs and targets.

    Returns
    -------
    dict method -> {"pos_rmse": (scans,) m, "vel_rmse": (scans,) m/s,
    "anees_x": (scans,), "anees_y": (scans,)} -- NaN where no run has a plot.
    """
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for m in methods:
            pe = result[f"{m}/pos_err"][..., :dims]
            ve = result[f"{m}/vel_err"][..., :dims]
            sd = result[f"{m}/std"][..., :dims]
            q = np.where(sd > 0, (pe / np.where(sd > 0, sd, 1.0)) ** 2, np.nan)
            out[m] = {
                "pos_rmse": np.sqrt(np.nanmean(np.sum(pe * pe, axis=-1), axis=(0, 1))),
                "vel_rmse": np.sqrt(np.nanmean(np.sum(ve * ve, axis=-1), axis=(0, 1))),
                "anees_x": np.nanmean(q[..., 0], axis=(0, 1)),
                "anees_y": np.nanmean(q[..., 1], axis=(0, 1)),
            }
    return out


def summarize(
    result: MonteCarloResult,
    methods: Sequence[str],
    dims: int = 2,
    skip: int = 3,
    crb: FloatArray | None = None,
) -> list[dict[str, Any]]:
    """One table row per method from :func:`compare_methods` results.

    Parameters
    ----------
    dims : 2 or 3 -- position dimensions scored
    skip : number of initial scans left out of the averages (track initialisation)
    crb : (targets, scans) position bound from :func:`position_crb`, or None; adds the
        column ``rmse_over_crb`` (position RMSE / RMS bound over the same scans)
    """
    rows = []
    n = result.n_runs
    lo, hi = chi2_interval(1, n)
    for m in methods:
        pe = result[f"{m}/pos_err"][..., skip:, :dims]
        ve = result[f"{m}/vel_err"][..., skip:, :dims]
        sd = result[f"{m}/std"][..., skip:, :dims]
        pn = np.sqrt(np.sum(pe * pe, axis=-1))
        vn = np.sqrt(np.sum(ve * ve, axis=-1))
        row: dict[str, Any] = {"method": m}
        failed = int(result[f"{m}/failed"].sum())
        row["failures"] = failed
        if np.all(np.isnan(pn)):
            rows.append(row)
            continue
        row["pos_rmse_m"] = rms_over_time(pn)
        if crb is not None:
            b = np.broadcast_to(crb[None, :, skip:], pn.shape)
            ok = np.isfinite(pn) & np.isfinite(b)
            row["rmse_over_crb"] = float(np.sqrt(np.mean(pn[ok] ** 2) / np.mean(b[ok] ** 2)))
        row["vel_rmse_mps"] = rms_over_time(vn)
        row["peak_pos_m"] = float(np.nanmax(pn))
        with np.errstate(divide="ignore", invalid="ignore"):
            q = (pe / sd) ** 2  # (runs, targets, scans, dims)
            q = np.where(sd > 0, q, np.nan)
        # per-step average over runs (NaN where some run missed the scan is skipped)
        with warnings.catch_warnings():  # scans missed in every run give an all-NaN slice
            warnings.simplefilter("ignore", RuntimeWarning)
            per_step = np.nanmean(q, axis=0)  # (targets, scans, dims)
        counts = np.sum(np.isfinite(q), axis=0)
        full = counts == n
        for k in range(min(dims, 2)):
            row[f"anees_{_AXES[k]}"] = float(np.nanmean(per_step[..., k]))
        inside = (per_step >= lo) & (per_step <= hi) & full
        row["in_bounds_pct"] = 100.0 * float(inside.sum()) / max(int(full.sum()), 1)
        plots = float(result[f"{m}/plots"].sum())
        row["us_per_plot"] = 1e6 * float(result[f"{m}/seconds"].sum()) / max(plots, 1.0)
        rows.append(row)
    return rows
