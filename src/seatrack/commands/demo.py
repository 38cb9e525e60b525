"""``seatrack demo``: the main job on the bundled scenarios, end to end.

1. Simulate the bundled ``demo`` scenario once and write its CSV files (as
   ``seatrack simulate`` does) to ``OUT/data``.
2. Run every registered track method on each target's radar plots; plot the tracks
   and the position errors.
3. A small seeded Monte-Carlo comparison of the methods (RMSE, ANEES, time) as a table,
   also written to ``OUT/results.txt``.
4. If the TMA solver is available, bearings-only TMA on the bundled ``tma_classic``
   scenario, compared with the truth.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import typer

from seatrack.commands.options import option_in, prepare_outputs


def _plot_xy(meas: Any) -> np.ndarray:
    """Measured positions (m) of the detected plots of one target."""
    from seatrack.geometry import polar_to_cart, spherical_to_cart

    ok = meas.detected
    comps = meas.components
    r = meas.z[ok, comps.index("range")]
    a = meas.z[ok, comps.index("azimuth")]
    if "elevation" in comps:
        rel = spherical_to_cart(r, a, meas.z[ok, comps.index("elevation")])[..., :2]
    else:
        rel = polar_to_cart(r, a)
    return np.asarray(rel) + meas.sensor_pos[ok, :2]


def _tma_demo(out: Path, echo: Any) -> list[str]:
    """Bearings-only TMA on ``tma_classic``; returns lines of text (empty if no solver)."""
    try:
        from seatrack.tma.solver import Bearings, solve
    except ImportError:
        return []
    from seatrack.geometry import course_speed, mps_to_knots, rad2deg
    from seatrack.report.plots import save, track_figure
    from seatrack.simulate.scenarios import bundled_scenario, load_scenario

    sc = load_scenario(bundled_scenario("tma_classic"))
    rng = np.random.default_rng(np.random.SeedSequence(sc.seed).spawn(1)[0])
    sim = sc.simulate(rng)
    sd = sim.sensors[0]
    m = sd.measurements[0]
    ok = m.detected
    b = Bearings(m.t[ok], m.z[ok, 0], m.sensor_pos[ok, :2])
    sol = solve(b, sigma=float(sd.sensor.sigma[0]))
    truth = sd.truth[0]
    t_last = float(b.t[-1])
    est = sol.position_at(np.array([t_last]))[0]
    true_p = truth.pos[-1, :2]
    rel = true_p - sd.observer.pos[-1, :2] if sd.observer is not None else true_p
    true_range = float(np.hypot(*rel))
    tc, ts = course_speed(truth.vel[-1, 0], truth.vel[-1, 1])
    last = sol.last
    lines = [
        f"TMA on tma_classic ({len(b)} bearings, sigma {np.degrees(sd.sensor.sigma[0]):.1f} deg): "
        f"{'observable' if sol.observable else 'NOT observable'}, {sol.iterations} iterations, "
        f"residual RMS {np.degrees(sol.residual_rms):.2f} deg",
        f"  range  {last.range / 1000:7.2f} km +- {last.sigma_range / 1000:.2f}   "
        f"(truth {true_range / 1000:.2f})",
        f"  course {rad2deg(last.course):7.1f} deg +- {np.degrees(last.sigma_course):.1f}   "
        f"(truth {rad2deg(tc) % 360:.1f})",
        f"  speed  {float(mps_to_knots(last.speed)):7.2f} kn "
        f"+- {float(mps_to_knots(last.sigma_speed)):.2f}   "
        f"(truth {float(mps_to_knots(ts)):.2f})",
        f"  position error at the last bearing: {np.hypot(*(est - true_p)):.0f} m",
    ]
    est_track = sol.position_at(truth.t)
    fig = track_figure(
        {"target": truth.pos},
        {"TMA estimate": est_track},
        ownship=sd.observer.pos if sd.observer is not None else None,
        title="Bearings-only TMA (tma_classic)",
    )
    save(fig, out / "tma.png")
    for line in lines:
        echo(line)
    return lines


def register(app: typer.Typer) -> None:
    @app.command("demo")
    def demo(
        out: Path = typer.Option(
            Path("seatrack-demo"), "--out", "-o", help="Folder for data, plots and results."
        ),
        runs: int | None = typer.Option(
            None,
            "--runs",
            "-n",
            help="Monte-Carlo runs of the comparison (default: the scenario's, 10).",
        ),
        processes: int = typer.Option(
            2,
            "--processes",
            "-p",
            help="Worker processes for the Monte-Carlo runs (results do not depend on it).",
        ),
        progress: bool = typer.Option(
            False, "--progress/--no-progress", help="Show a progress bar."
        ),
    ) -> None:
        """Run the main job on the bundled demo scenario and write plots and a results table.

        Simulates a radar/sonar scenario with a manoeuvring target, runs every registered
        track method, prints a Monte-Carlo comparison (position/velocity RMSE, per-axis
        ANEES, time per plot) and writes PNG plots and CSV data to --out. Also runs
        bearings-only TMA on the classic TMA scenario when the solver is available.
        """
        from rich.console import Console

        from seatrack.commands.evaluate import MAX_PROCESSES
        from seatrack.commands.simulate import simulation_files, write_simulation
        from seatrack.evaluate.metrics import chi2_interval
        from seatrack.evaluate.montecarlo import format_table, rich_table
        from seatrack.evaluate.tracking import (
            SUMMARY_COLUMNS,
            compare_methods,
            method_config,
            position_crb,
            run_methods,
            summarize,
            tracking_sensor,
        )
        from seatrack.filters.registry import METHODS
        from seatrack.io.atomic import atomic_write
        from seatrack.report.plots import error_figure, save, track_figure
        from seatrack.simulate.scenarios import MAX_RUNS, bundled_scenario, load_scenario

        console = Console()
        sc = load_scenario(bundled_scenario("demo"))
        n = sc.runs if runs is None else runs
        option_in("--runs", n, 1, MAX_RUNS)
        option_in("--processes", processes, 1, MAX_PROCESSES)
        methods = list(METHODS)
        sensor = tracking_sensor(sc)
        pngs = [out / "tracks.png", *(out / f"errors_{name}.png" for name in sc.target_names)]
        extra = [out / "tma.png", out / "results.txt"]
        prepare_outputs([*simulation_files(sc, out / "data"), *pngs, *extra], [out, out / "data"])

        # 1. one run: data files
        rng = np.random.default_rng(np.random.SeedSequence(sc.seed).spawn(1)[0])
        sim = sc.simulate(rng)
        files = write_simulation(sim, out / "data")
        console.print(f"[bold]{sc.name}[/bold]: {sc.description}")
        console.print(
            f"simulated {sc.duration:g} s; wrote {len(files)} CSV files to {out / 'data'}"
        )

        # 2. the methods on that run: plots
        sd = sim.sensor(sensor.name)
        configs = {m: method_config(sc, sensor, m) for m in methods}
        res = run_methods(sd, methods, configs)
        for m, rr in res.items():
            for name, r in zip(sc.target_names, rr, strict=True):
                if r.error:
                    typer.echo(f"{m} failed on {name}: {r.error}")
        estimates = {m: [r.pos for r in rr if not r.error] for m, rr in res.items()}
        plots_xy = np.concatenate([_plot_xy(meas) for meas in sd.measurements])
        clutter_xy = None
        if sd.clutter_t.size:
            from seatrack.geometry import polar_to_cart

            clutter_xy = (
                np.asarray(polar_to_cart(sd.clutter_range, sd.clutter_azimuth))
                + sd.clutter_sensor[:, :2]
            )
        fig = track_figure(
            {n: tr.pos for n, tr in zip(sc.target_names, sim.targets, strict=True)},
            estimates,
            plots=plots_xy,
            ownship=sim.ownship.pos,
            clutter=clutter_xy,
            title=f"{sc.name}: truth, {sensor.name} plots and tracks",
        )
        save(fig, pngs[0])
        for j, name in enumerate(sc.target_names):
            errs = {
                m: np.hypot(*(rr[j].pos[:, :2] - sd.truth[j].pos[:, :2]).T)
                for m, rr in res.items()
                if not rr[j].error
            }
            fig = error_figure(sd.t, errs, "position error (m)", title=f"{sc.name}: target {name}")
            save(fig, pngs[j + 1])

        # 3. Monte-Carlo comparison
        mc = compare_methods(
            sc, methods, n, sc.seed, sensor=sensor.name, processes=processes, progress=progress
        )
        crb = position_crb(sc, sensor.name)
        rows = summarize(mc, methods, dims=3 if "elevation" in sensor.components else 2, crb=crb)
        lo, hi = chi2_interval(1, n)
        title = f"{sc.name}: {n} Monte-Carlo runs, {len(sc.targets)} targets, sensor {sensor.name}"
        if console.is_terminal:
            console.print(rich_table(rows, SUMMARY_COLUMNS, title=title))
        else:
            typer.echo(f"{title}\n{format_table(rows, SUMMARY_COLUMNS)}")
        note = f"ANEES 95% bounds per step (1 dof, {n} runs): [{lo:.3f}, {hi:.3f}]"
        console.print(note)
        text = [title, format_table(rows, SUMMARY_COLUMNS), note, ""]

        # 4. TMA when available
        tma_lines = _tma_demo(out, typer.echo)
        if tma_lines:
            pngs.append(out / "tma.png")
        text += tma_lines
        with atomic_write(out / "results.txt") as fh:
            fh.write("\n".join(text) + "\n")
        console.print(f"wrote {', '.join(str(p) for p in pngs)} and {out / 'results.txt'}")
