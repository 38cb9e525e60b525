"""``seatrack simulate SCENARIO --out DIR``: simulated measurements and truth as CSV files."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import typer

from seatrack.commands.options import option_in
from seatrack.commands.options import prepare_outputs


def simulation_files(scenario: Any, out: Path) -> list[Path]:
    """The files :func:`write_simulation` writes for ``scenario`` into folder ``out``.

    ``plots_<sensor>.csv`` (PLOTS format, one track per target) for each active sensor,
    ``clutter_<sensor>.csv`` for each active sensor with a clutter density (possibly with
    no rows), ``bearings_<sensor>.csv`` for each passive sonar, ``truth.csv`` (all
    targets at the truth interval) and ``ownship.csv``.
    """
    files = []
    for s in scenario.sensors:
        if s.is_passive:
            files.append(out / f"bearings_{s.name}.csv")
        else:
            files.append(out / f"plots_{s.name}.csv")
            if s.clutter_density > 0:
                files.append(out / f"clutter_{s.name}.csv")
    return [*files, out / "truth.csv", out / "ownship.csv"]


def write_simulation(sim: Any, out: Path) -> list[tuple[Path, int]]:
    """Write one :class:`~seatrack.simulate.scenarios.SimulationResult` to ``out``.

    The files of :func:`simulation_files` are written together: if one fails, none of
    them replaces its previous version (:func:`seatrack.io.atomic.atomic_files`).
    Returns (path, rows) for each file.
    """
    from seatrack.io.atomic import atomic_files
    from seatrack.simulate.files import write_bearings
    from seatrack.simulate.files import write_clutter
    from seatrack.simulate.files import write_plots
    from seatrack.simulate.files import write_truth

    paths = simulation_files(sim.scenario, out)
    prepare_outputs(paths, [out])
    names = sim.scenario.target_names
    rows: list[int] = []
    with atomic_files(paths) as tmp:
        it = iter(tmp)
        for sd in sim.sensors:
            s = sd.sensor
            meas = zip(names, sd.measurements, strict=True)
            if s.is_passive:
                rows.append(write_bearings(next(it), meas, float(np.degrees(s.sigma[0]))))
                continue
            rows.append(write_plots(next(it), meas))
            if s.clutter_density > 0:
                args = (sd.clutter_t, sd.clutter_range, sd.clutter_azimuth, sd.clutter_sensor)
                rows.append(write_clutter(next(it), *args))
        rows.append(write_truth(next(it), list(zip(names, sim.targets, strict=True))))
        rows.append(write_truth(next(it), sim.ownship))
    return list(zip(paths, rows, strict=True))


def multitarget_files(scenario: Any, out: Path) -> list[Path]:
    """The files :func:`write_multitarget` writes for a ``[multitarget]`` scenario."""
    from seatrack.evaluate.tracking import tracking_sensor

    name = tracking_sensor(scenario).name
    return [out / f"plots_{name}.csv", out / f"plot_origin_{name}.csv", out / "truth.csv"]


def write_multitarget(scenario: Any, rng: np.random.Generator, out: Path) -> list[tuple[Path, int]]:
    """One run of a multi-target scenario, as its first active sensor sees it.

    ``plots_<sensor>.csv``: every plot (targets and clutter) WITHOUT a track column, in time
    order -- the input of the multi-target tracker; ``plot_origin_<sensor>.csv``: each plot
    with its line in that file and the target it came from (``clutter`` otherwise);
    ``truth.csv``: every live target at every scan (``time_s, target``, position and
    velocity). Written together (:func:`seatrack.io.atomic.atomic_files`).
    """
    import dataclasses

    from seatrack.evaluate.multitarget import simulate_scenario
    from seatrack.evaluate.tracking import tracking_sensor
    from seatrack.io.atomic import atomic_files
    from seatrack.io.multitarget import write_plot_labels
    from seatrack.io.multitarget import write_unlabelled_plots
    from seatrack.simulate.files import write_target_states

    paths = multitarget_files(scenario, out)
    prepare_outputs(paths, [out])
    sim = simulate_scenario(scenario, rng, tracking_sensor(scenario))
    order = np.argsort(sim.plots.t, kind="stable")
    plots = sim.plots.take(order)
    plots = dataclasses.replace(plots, line=np.arange(2, len(plots) + 2, dtype=np.int64))
    with atomic_files(paths) as (f_plots, f_origin, f_truth):
        rows = [
            write_unlabelled_plots(f_plots, plots),
            write_plot_labels(f_origin, plots, sim.origin[order]),
            write_target_states(f_truth, sim.truth_t, sim.truth_id, sim.truth_pos, sim.truth_vel),
        ]
    return list(zip(paths, rows, strict=True))


def seeded_rng(seed: int, run: int) -> np.random.Generator:
    """The generator of Monte-Carlo run ``run`` under master seed ``seed`` (as in evaluate)."""
    from seatrack.simulate.scenarios import MAX_RUNS

    option_in("--seed", seed, 0, 2**63 - 1)
    option_in("--run", run, 0, MAX_RUNS - 1)
    return np.random.default_rng(np.random.SeedSequence(seed).spawn(run + 1)[run])


def register(app: typer.Typer) -> None:
    @app.command("simulate")
    def simulate(
        scenario: str = typer.Argument(
            ...,
            help="Scenario TOML file, or the name of a bundled one (demo, linear_cv, tma_classic, "
            "coastal_multitarget).",
        ),
        out: Path = typer.Option(Path("seatrack-sim"), "--out", "-o", help="Output folder."),
        seed: int | None = typer.Option(
            None, "--seed", help="Master seed (default: the scenario's)."
        ),
        run: int = typer.Option(
            0,
            "--run",
            help="Monte-Carlo run index: reproduces run RUN of `seatrack evaluate`.",
        ),
    ) -> None:
        """Simulate a scenario once and write measurements and truth as CSV.

        Writes plots_<sensor>.csv (PLOTS format for `seatrack track`), bearings_<sensor>.csv
        for passive sonars (contact,time_s,bearing_deg,observer_x_m,observer_y_m,sigma_deg),
        clutter_<sensor>.csv, truth.csv and ownship.csv. A scenario with a [multitarget]
        table (e.g. coastal_multitarget) gives instead plots_<sensor>.csv without a track
        column (targets and clutter mixed, the multi-target tracker's input),
        plot_origin_<sensor>.csv (the target of each plot, or clutter) and truth.csv.
        """
        from seatrack.simulate.scenarios import load_scenario
        from seatrack.simulate.scenarios import resolve_scenario

        source = resolve_scenario(scenario)
        prepare_outputs({}, {"--out": out}, inputs=[source])
        sc = load_scenario(source)
        rng = seeded_rng(sc.seed if seed is None else seed, run)
        if sc.multitarget is not None:  # unlabelled plots for the multi-target tracker
            written = write_multitarget(sc, rng, out)
        else:
            prepare_outputs(simulation_files(sc, out), [out])
            written = write_simulation(sc.simulate(rng), out)
        for path, n in written:
            typer.echo(f"wrote {path} ({n} rows)")
