"""``seatrack evaluate SCENARIO``: Monte-Carlo comparison of the track methods."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import typer

from seatrack.commands.options import option_in
from seatrack.commands.options import prepare_outputs
from seatrack.io.table import InputError

#: most worker processes
MAX_PROCESSES = 256


def _methods(arg: str | None) -> list[str]:
    from seatrack.filters.registry import METHODS

    if arg is None or arg.strip() in ("", "all"):
        return list(METHODS)
    names = [m.strip() for m in arg.split(",") if m.strip()]
    for m in names:
        if m not in METHODS:
            raise ValueError(f"--methods: unknown method {m!r}; choose from {', '.join(METHODS)}")
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


def register(app: typer.Typer) -> None:
    @app.command("evaluate")
    def evaluate(
        scenario: str = typer.Argument(..., help="Scenario TOML file or bundled scenario name."),
        runs: int | None = typer.Option(
            None, "--runs", "-n", help="Monte-Carlo runs (default: the scenario's)."
        ),
        methods: str | None = typer.Option(
            None, "--methods", "-m", help="Comma-separated track methods (default: all registered)."
        ),
        processes: int = typer.Option(1, "--processes", "-p", help="Worker processes."),
        seed: int | None = typer.Option(
            None, "--seed", help="Master seed (default: the scenario's)."
        ),
        sensor: str | None = typer.Option(
            None, "--sensor", help="Sensor to track with (default: first active)."
        ),
        skip: int = typer.Option(3, "--skip", help="Initial scans left out of the averages."),
        csv_out: Path | None = typer.Option(
            None, "--csv", help="Also write the table to this CSV file."
        ),
        plots: Path | None = typer.Option(
            None,
            "--plots",
            help="Folder for plots of position RMSE (with the CRB when it applies) and "
            "ANEES against time.",
        ),
        progress: bool = typer.Option(
            True, "--progress/--no-progress", help="Show a progress bar."
        ),
    ) -> None:
        """Run a seeded Monte-Carlo comparison of track methods on a scenario.

        Each run simulates the scenario and runs every method on each target's plots; the
        table gives position/velocity RMSE (after --skip scans), the peak position error,
        per-axis ANEES (1 dof; 1.0 for a consistent filter) with the share of steps inside
        the 95% chi-square bounds, and the time per plot. Results do not depend on
        --processes.
        """
        from seatrack.evaluate.tracking import compare_methods
        from seatrack.evaluate.tracking import position_crb
        from seatrack.evaluate.tracking import require_evaluation
        from seatrack.evaluate.tracking import summarize
        from seatrack.evaluate.tracking import tracking_sensor
        from seatrack.simulate.scenarios import MAX_RUNS
        from seatrack.simulate.scenarios import load_scenario
        from seatrack.simulate.scenarios import resolve_scenario

        source = resolve_scenario(scenario)
        prepare_outputs({"--csv": csv_out}, {"--plots": plots}, inputs=[source])
        sc = load_scenario(source)
        n = sc.runs if runs is None else runs
        s = sc.seed if seed is None else seed
        option_in("--runs", n, 1, MAX_RUNS)
        option_in("--processes", processes, 1, MAX_PROCESSES)
        option_in("--seed", s, 0, 2**63 - 1)
        try:
            sens = tracking_sensor(sc, sensor)
        except ValueError as exc:
            raise InputError(f"{'--sensor' if sensor is not None else sc.path}: {exc}") from None
        check_skip(skip, sens.scan_times(sc.duration).size, sens.name)
        if sc.multitarget is not None:  # unlabelled plots: the multi-target tracker
            from seatrack.evaluate.multitarget import evaluate_multitarget

            mt = None if methods is None else [m.strip() for m in methods.split(",") if m.strip()]
            typer.echo(evaluate_multitarget(sc, n, s, mt, sensor, csv_out, plots))
            return
        names = _methods(methods)
        require_evaluation(sc, sens, names, n, processes)
        pngs = [plots / "pos_rmse.png", plots / "anees.png"] if plots is not None else []
        prepare_outputs([csv_out, *pngs], [plots])
        errors = trial_errors(sc, sens, names, s)
        res = compare_methods(
            sc, names, n, s, sensor=sens.name, processes=processes, progress=progress
        )
        dims = 3 if "elevation" in sens.components else 2
        crb = position_crb(sc, sens.name)
        rows = summarize(res, names, dims=dims, skip=skip, crb=crb)
        title = f"{sc.name}: {n} runs, seed {s}, sensor {sens.name}, {len(sc.targets)} target(s)"
        print_summary(rows, title, n, res.elapsed_s, errors, crb, skip)
        if csv_out is not None:
            write_summary_csv(csv_out, rows)
            typer.echo(f"wrote {csv_out}")
        if pngs:
            ok = [m for m in names if not errors[m]]
            write_error_plots(res, ok, dims, sens.scan_times(sc.duration), crb, title, n, pngs)
            typer.echo(f"wrote {pngs[0]} and {pngs[1]}")


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


def print_summary(
    rows: list[dict[str, Any]],
    title: str,
    n: int,
    elapsed_s: float,
    errors: Mapping[str, str],
    crb: Any,
    skip: int,
) -> None:
    """The summary table (rich on a terminal), the ANEES bounds, failures and the CRB."""
    from rich.console import Console

    from seatrack.evaluate.metrics import chi2_interval
    from seatrack.evaluate.montecarlo import format_table
    from seatrack.evaluate.montecarlo import rich_table
    from seatrack.evaluate.tracking import SUMMARY_COLUMNS

    lo, hi = chi2_interval(1, n)
    console = Console()
    if console.is_terminal:
        console.print(rich_table(rows, SUMMARY_COLUMNS, title=title))
    else:
        typer.echo(f"{title}\n{format_table(rows, SUMMARY_COLUMNS)}")
    console.print(
        f"ANEES 95% bounds per step (1 dof, {n} runs): [{lo:.3f}, {hi:.3f}]; {elapsed_s:.1f} s"
    )
    for m, e in errors.items():
        if e:
            typer.echo(f"{m} failed on this scenario: {e}")
    if crb is not None:
        rms = float(np.sqrt(np.nanmean(crb[:, skip:] ** 2)))
        console.print(f"position CRB (constant-velocity truth, no process noise): {rms:.1f} m RMS")


def write_summary_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    """The summary table as CSV (atomic)."""
    import csv

    from seatrack.evaluate.tracking import SUMMARY_COLUMNS
    from seatrack.io.atomic import atomic_write

    with atomic_write(path, newline="") as fh:
        w = csv.DictWriter(fh, [c.key for c in SUMMARY_COLUMNS], extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def write_error_plots(
    res: Any,
    names: list[str],
    dims: int,
    t: Any,
    crb: Any,
    title: str,
    n: int,
    pngs: list[Path],
) -> None:
    """Position RMSE (with the RMS CRB when it applies) and ANEES against time, as PNGs."""
    from seatrack.evaluate.metrics import chi2_interval
    from seatrack.evaluate.tracking import time_histories
    from seatrack.report.plots import error_figure
    from seatrack.report.plots import save

    hist = time_histories(res, names, dims=dims)
    bounds = None
    if crb is not None:
        finite = np.all(np.isfinite(crb), axis=0)  # NaN while not yet observable
        rms_crb = np.full(crb.shape[1], np.nan)
        rms_crb[finite] = np.sqrt(np.mean(crb[:, finite] ** 2, axis=0))
        bounds = {"CRB": rms_crb}
    fig = error_figure(
        t,
        {m: hist[m]["pos_rmse"] for m in names},
        "position RMSE (m)",
        title=title,
        bounds=bounds,
        logy=True,
    )
    save(fig, pngs[0])
    lo, hi = chi2_interval(1, n)
    fig = error_figure(
        t,
        {m: 0.5 * (hist[m]["anees_x"] + hist[m]["anees_y"]) for m in names},
        "ANEES, mean of x and y (1 dof each)",
        title=title,
        # one axis's 95 % bounds: conservative for the mean of the two axes
        hlines={f"95% bounds of one axis ({n} runs)": lo, "_upper": hi},
        logy=True,
    )
    save(fig, pngs[1])
