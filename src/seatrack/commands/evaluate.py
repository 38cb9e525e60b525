"""``seatrack evaluate SCENARIO``: Monte-Carlo comparison of the track methods."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import typer

__all__ = ["register", "print_summary", "write_summary_csv", "write_error_plots"]


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
            True,
            "--progress/--no-progress",
            help="Show the estimate and progress lines of a run estimated at more than a minute.",
        ),
    ) -> None:
        """Run a seeded Monte-Carlo comparison of track methods on a scenario.

        Each run simulates the scenario and runs every method on each target's plots; the
        table gives position/velocity RMSE (after --skip scans), the peak position error,
        per-axis ANEES (1 dof; 1.0 for a consistent filter) with the share of steps inside
        the 95% chi-square bounds, and the time per plot. Results do not depend on
        --processes.
        """
        from seatrack.api.evaluate import EvaluationOptions
        from seatrack.api.evaluate import run_evaluation
        from seatrack.api.options import prepare_outputs
        from seatrack.api.simulate import load
        from seatrack.simulate.scenarios import resolve_scenario

        source = resolve_scenario(scenario)
        prepare_outputs({"--csv": csv_out}, {"--plots": plots}, inputs=[source])
        sc = load(source)
        options = EvaluationOptions(methods, runs, seed, sensor, skip, processes)
        if sc.multitarget is not None:  # unlabelled plots: the multi-target tracker
            from seatrack.api.evaluate import multitarget_options
            from seatrack.evaluate.multitarget import evaluate_multitarget

            n, s, mt = multitarget_options(sc, options)
            typer.echo(
                evaluate_multitarget(sc, n, s, mt, sensor, csv_out, plots, progress=progress)
            )
            return
        pngs = [plots / "pos_rmse.png", plots / "anees.png"] if plots is not None else []
        ev = run_evaluation(sc, options, progress, [csv_out, *pngs], [plots])
        print_summary(ev.rows, ev.title, ev.runs, ev.result.elapsed_s, ev.errors, ev.crb, skip)
        if csv_out is not None:
            write_summary_csv(csv_out, ev.rows)
            typer.echo(f"wrote {csv_out}")
        if pngs:
            ok = [m for m in ev.names if not ev.errors[m]]
            t = ev.sensor.scan_times(sc.duration)
            write_error_plots(ev.result, ok, ev.dims, t, ev.crb, ev.title, ev.runs, pngs)
            typer.echo(f"wrote {pngs[0]} and {pngs[1]}")


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
    import numpy as np
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
        console.print(
            f"position bound (posterior CRB: constant-velocity truth, no process noise, the "
            f"methods' velocity prior): {rms:.1f} m RMS"
        )


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
    import numpy as np

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
