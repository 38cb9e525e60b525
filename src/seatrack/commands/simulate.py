"""``seatrack simulate SCENARIO --out DIR``: simulated measurements and truth as CSV files."""

from __future__ import annotations

from pathlib import Path

import typer

__all__ = ["register"]


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
        from seatrack.api.options import prepare_outputs
        from seatrack.api.simulate import load
        from seatrack.api.simulate import simulate_to_folder
        from seatrack.simulate.scenarios import resolve_scenario

        source = resolve_scenario(scenario)
        prepare_outputs({}, {"--out": out}, inputs=[source])
        for path, n in simulate_to_folder(load(source), out, seed, run):
            typer.echo(f"wrote {path} ({n} rows)")
