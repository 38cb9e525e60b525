"""``seatrack simulate SCENARIO --out DIR``: simulated measurements and truth as CSV files."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import typer


def write_simulation(sim: Any, out: Path) -> list[tuple[Path, int]]:
    """Write one :class:`~seatrack.simulate.scenarios.SimulationResult` to ``out``.

    Files: ``plots_<sensor>.csv`` (PLOTS format, one track per target) for each active
    sensor, ``clutter_<sensor>.csv`` when it has false plots, ``bearings_<sensor>.csv``
    for each passive sonar, ``truth.csv`` (all targets at the truth interval) and
    ``ownship.csv``. Returns (path, rows) for each file.
    """
    from seatrack.io.measurements_csv import write_bearings, write_clutter, write_plots, write_truth

    out.mkdir(parents=True, exist_ok=True)
    names = sim.scenario.target_names
    written: list[tuple[Path, int]] = []
    for sd in sim.sensors:
        s = sd.sensor
        if s.is_passive:
            p = out / f"bearings_{s.name}.csv"
            sigma_deg = float(np.degrees(s.sigma[0]))
            written.append(
                (p, write_bearings(p, zip(names, sd.measurements, strict=True), sigma_deg))
            )
        else:
            p = out / f"plots_{s.name}.csv"
            written.append((p, write_plots(p, zip(names, sd.measurements, strict=True))))
            if sd.clutter_t.size:
                p = out / f"clutter_{s.name}.csv"
                n = write_clutter(
                    p, sd.clutter_t, sd.clutter_range, sd.clutter_azimuth, sd.clutter_sensor
                )
                written.append((p, n))
    p = out / "truth.csv"
    written.append((p, write_truth(p, list(zip(names, sim.targets, strict=True)))))
    p = out / "ownship.csv"
    written.append((p, write_truth(p, sim.ownship)))
    return written


def register(app: typer.Typer) -> None:
    @app.command("simulate")
    def simulate(
        scenario: str = typer.Argument(
            ...,
            help="Scenario TOML file, or the name of a bundled one (demo, linear_cv, tma_classic).",
        ),
        out: Path = typer.Option(Path("seatrack-sim"), "--out", "-o", help="Output folder."),
        seed: int | None = typer.Option(
            None, "--seed", help="Master seed (default: the scenario's)."
        ),
        run: int = typer.Option(
            0,
            "--run",
            min=0,
            help="Monte-Carlo run index: reproduces run RUN of `seatrack evaluate`.",
        ),
    ) -> None:
        """Simulate a scenario once and write measurements and truth as CSV.

        Writes plots_<sensor>.csv (PLOTS format for `seatrack track`), bearings_<sensor>.csv
        for passive sonars (contact,time_s,bearing_deg,observer_x_m,observer_y_m,sigma_deg),
        clutter_<sensor>.csv, truth.csv and ownship.csv.
        """
        from seatrack.simulate.scenarios import load_scenario, resolve_scenario

        sc = load_scenario(resolve_scenario(scenario))
        s = sc.seed if seed is None else seed
        rng = np.random.default_rng(np.random.SeedSequence(s).spawn(run + 1)[run])
        sim = sc.simulate(rng)
        for path, n in write_simulation(sim, out):
            typer.echo(f"wrote {path} ({n} rows)")
