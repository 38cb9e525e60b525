"""``seatrack.evaluate``: a seeded Monte-Carlo comparison of track methods on a scenario,
as ``seatrack evaluate``; the frame holds the rows of its ``--csv`` table."""

from __future__ import annotations

import dataclasses
import os
import tempfile
from collections.abc import Mapping
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.api.inputs import read_frame
from seatrack.api.options import option_in
from seatrack.io.table import InputError

__all__ = [
    "evaluate",
    "Evaluation",
    "EvaluationOptions",
    "multitarget_options",
    "run_evaluation",
    "method_names",
    "config_error",
    "check_skip",
    "trial_errors",
    "MAX_PROCESSES",
]

#: most worker processes
MAX_PROCESSES = 256


def method_names(arg: str | Sequence[str] | None) -> list[str]:
    """The methods named (a comma-separated text or a list; ``None``/``all``: every one)."""
    from seatrack.filters.registry import METHODS

    if arg is None or (isinstance(arg, str) and arg.strip() in ("", "all")):
        return list(METHODS)
    parts = arg.split(",") if isinstance(arg, str) else list(arg)
    names = [m.strip() for m in parts if m.strip()]
    for m in names:
        if m not in METHODS:
            raise InputError(f"--methods: unknown method {m!r}; choose from {', '.join(METHODS)}")
    return names


def config_error(path: str, method: str, table: Mapping[str, Any], error: str) -> InputError:
    """A method that failed with its ``[evaluate.<method>]`` table as a scenario error.

    A string where the method wants a number is named by its key (``evaluate.ekf.q =
    'abc' is not a number``); any other failure is reported with the table's key path.
    """
    if error.startswith("ConfigError: "):  # the config layer names the key already
        return InputError(f"{path}: {error.removeprefix('ConfigError: ')}")
    for k, v in table.items():
        if isinstance(v, str) and f"to float: {v!r}" in error:
            return InputError(f"{path}: evaluate.{method}.{k} = {v!r} is not a number")
    return InputError(f"{path}: evaluate.{method}: {error}")


def check_skip(skip: int, n_scans: int, sensor: str) -> None:
    """``--skip`` must leave at least one scan to average."""
    if not 0 <= skip < n_scans:
        raise InputError(
            f"--skip = {skip} must be in [0, {n_scans - 1}]: sensor {sensor} has {n_scans} scans"
        )


def trial_errors(sc: Any, sens: Any, names: list[str], seed: int) -> dict[str, str]:
    """One trial run in this process, before the timed runs (not part of the statistics):
    it compiles the numba kernels and reports why a method cannot run on this scenario
    (a method the scenario configured in ``[evaluate.<method>]`` failing is a scenario error).
    """
    from seatrack.evaluate.tracking import method_config
    from seatrack.evaluate.tracking import run_methods

    trial = sc.simulate(np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0]))
    configs = {m: method_config(sc, sens, m) for m in names}
    errors = {}
    for m, rr in run_methods(trial.sensor(sens.name), names, configs).items():
        errors[m] = next((r.error for r in rr if r.error), "")
        if errors[m] and m in sc.extra:
            raise config_error(sc.path, m, sc.extra[m], errors[m])
    return errors


@dataclasses.dataclass(frozen=True)
class Evaluation:
    """A finished comparison: the summary ``rows`` (one per method) and what the command
    prints and draws from them."""

    rows: list[dict[str, Any]]
    result: Any
    names: list[str]
    errors: dict[str, str]
    crb: Any
    sensor: Any
    dims: int
    runs: int
    seed: int
    skip: int
    title: str

    def frame(self) -> Any:
        """The rows as a pandas DataFrame with the columns of the ``--csv`` file."""
        import pandas as pd

        from seatrack.evaluate.tracking import SUMMARY_COLUMNS

        keys = [c.key for c in SUMMARY_COLUMNS]
        return pd.DataFrame([{k: r.get(k) for k in keys} for r in self.rows], columns=keys)


@dataclasses.dataclass(frozen=True)
class EvaluationOptions:
    """The options of a comparison, by the names of :func:`evaluate` (``None``: the
    scenario's, or every method); checked by :func:`evaluation_options`."""

    methods: str | Sequence[str] | None = None
    runs: int | None = None
    seed: int | None = None
    sensor: str | None = None
    skip: int = 3
    processes: int = 1


def evaluation_options(sc: Any, options: EvaluationOptions) -> tuple[int, int, Any]:
    """The number of runs, the seed and the tracking sensor of an evaluation of scenario
    ``sc``, every option checked (by its command-line name) before any work."""
    from seatrack.evaluate.tracking import tracking_sensor
    from seatrack.simulate.scenarios import MAX_RUNS

    n = sc.runs if options.runs is None else options.runs
    s = sc.seed if options.seed is None else options.seed
    option_in("--runs", n, 1, MAX_RUNS)
    option_in("--processes", options.processes, 1, MAX_PROCESSES)
    option_in("--seed", s, 0, 2**63 - 1)
    try:
        sens = tracking_sensor(sc, options.sensor)
    except ValueError as exc:
        where = "--sensor" if options.sensor is not None else sc.path
        raise InputError(f"{where}: {exc}") from None
    check_skip(options.skip, sens.scan_times(sc.duration).size, sens.name)
    return n, s, sens


def multitarget_options(sc: Any, options: EvaluationOptions) -> tuple[int, int, list[str] | None]:
    """The number of runs, the seed and the per-track methods (None: the default) of an
    evaluation of a ``[multitarget]`` scenario, every option checked as
    :func:`evaluation_options` and :func:`method_names` check them."""
    n, s, _ = evaluation_options(sc, options)
    return n, s, None if options.methods is None else method_names(options.methods)


def run_evaluation(
    sc: Any,
    options: EvaluationOptions,
    progress: bool = False,
    outputs: Sequence[Path | None] = (),
    folders: Sequence[Path | None] = (),
) -> Evaluation:
    """The comparison of ``seatrack evaluate`` on a loaded single-target scenario; the
    ``outputs`` and ``folders`` are checked after the options, before any work."""
    from seatrack.api.options import prepare_outputs
    from seatrack.evaluate.tracking import compare_methods
    from seatrack.evaluate.tracking import position_crb
    from seatrack.evaluate.tracking import require_evaluation
    from seatrack.evaluate.tracking import summarize
    from seatrack.progress import Progress

    names = method_names(options.methods)
    n, s, sens = evaluation_options(sc, options)
    processes, skip = options.processes, options.skip
    seconds = require_evaluation(sc, sens, names, n, processes)
    prepare_outputs(outputs, folders)
    errors = trial_errors(sc, sens, names, s)
    bar = Progress("seatrack evaluate", n, "runs", seconds, shown=progress)
    res = compare_methods(sc, names, n, s, sensor=sens.name, processes=processes, progress=bar)
    dims = 3 if "elevation" in sens.components else 2
    crb = position_crb(sc, sens.name, names)
    rows = summarize(res, names, dims=dims, skip=skip, crb=crb)
    title = f"{sc.name}: {n} runs, seed {s}, sensor {sens.name}, {len(sc.targets)} target(s)"
    return Evaluation(rows, res, names, errors, crb, sens, dims, n, s, skip, title)


def evaluate(
    scenario: str | os.PathLike[str] | Mapping[str, Any],
    *,
    methods: str | Sequence[str] | None = None,
    runs: int | None = None,
    seed: int | None = None,
    sensor: str | None = None,
    skip: int = 3,
    processes: int = 1,
) -> Any:
    """Compare track methods over seeded Monte-Carlo runs of a scenario, as ``seatrack
    evaluate``.

    Parameters
    ----------
    scenario : str, path or dict
        A bundled scenario name, a scenario TOML file, or a dict with its keys.
    methods : str or sequence of str, optional
        Methods to compare (default: every registered method; for a ``[multitarget]``
        scenario ``ekf``, each with GNN and with JPDA).
    runs : int, optional
        Monte-Carlo runs (default: the scenario's).
    seed : int, optional
        Master seed (default: the scenario's).
    sensor : str, optional
        Sensor to track with (default: the first active one).
    skip : int
        Initial scans left out of the averages (single-target scenarios).
    processes : int
        Worker processes (single-target scenarios); results do not depend on it.

    Returns
    -------
    pandas.DataFrame
        One row per method with the columns of the command's ``--csv`` table: position
        and velocity RMSE, peak error, ANEES and time per plot (single target); GOSPA and
        its parts (multi-target).

    Examples
    --------
    >>> import seatrack
    >>> table = seatrack.evaluate("linear_cv", methods=["ekf"], runs=2)
    >>> list(table["method"])
    ['ekf']
    >>> bool(table["pos_rmse_m"].iloc[0] > 0)
    True
    """
    from seatrack.api.simulate import load

    sc = load(scenario)
    options = EvaluationOptions(methods, runs, seed, sensor, skip, processes)
    if sc.multitarget is None:
        return run_evaluation(sc, options).frame()
    from seatrack.evaluate.multitarget import evaluate_multitarget

    n_mt, s_mt, mt = multitarget_options(sc, options)
    with tempfile.TemporaryDirectory(prefix="seatrack-") as folder:
        out = Path(folder) / "evaluate.csv"
        evaluate_multitarget(sc, n_mt, s_mt, mt, sensor, out)
        return read_frame(out, ("method",))
