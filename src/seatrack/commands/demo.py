"""``seatrack demo``: every method of seatrack in the situation it is made for.

Writes to ``--out`` (default ``seatrack-demo``):

* ``report.html`` -- one self-contained page: the situations, the comparisons with one
  sentence per method on when to use it, and the plots (:mod:`seatrack.report.demo_page`);
* ``results.txt`` -- the comparison as printed;
* one PNG per situation (:data:`seatrack.report.demo.SECTIONS`);
* ``data/`` -- input files to try the commands on: the bundled ``demo`` scenario simulated
  once (``plots_radar.csv``, ``truth.csv``, ...; ``seatrack track data/plots_radar.csv``),
  the unlabelled plots of the multi-target situation and what the trackers made of them.

Every output path is checked before any work; all outputs are replaced together at the end
(one :func:`seatrack.io.atomic.output_transaction`, the sections' worker processes
included): a failure or an interrupt leaves every previous output as it was and no
temporary file.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer

#: Monte-Carlo runs of each tracking situation by default
DEFAULT_RUNS = 10
#: the most runs a demo may ask for
MAX_DEMO_RUNS = 1000
#: files the sections write besides their PNGs (under ``--out``)
SECTION_FILES = ("data/ais_tracks.csv", "data/plots_unlabelled.csv", "data/tracks_unlabelled.csv")


def _outputs(out: Path) -> list[Path]:
    """Every file the demo writes (checked before any work)."""
    from seatrack.api.simulate import simulation_files
    from seatrack.report.demo import SECTIONS
    from seatrack.simulate.scenarios import bundled_scenario
    from seatrack.simulate.scenarios import load_scenario

    data = simulation_files(load_scenario(bundled_scenario("demo")), out / "data")
    pngs = [out / f"{k}.png" for k in SECTIONS]
    return [
        *data,
        *(out / f for f in SECTION_FILES),
        *pngs,
        out / "results.txt",
        out / "report.html",
    ]


def _write_data(out: Path) -> None:
    """The bundled demo scenario, simulated once, as input files for the commands."""
    import numpy as np

    from seatrack.api.simulate import write_simulation
    from seatrack.simulate.scenarios import bundled_scenario
    from seatrack.simulate.scenarios import load_scenario

    sc = load_scenario(bundled_scenario("demo"))
    write_simulation(sc.simulate(np.random.default_rng(sc.seed)), out / "data")


def run_demo(out: Path, runs: int | None, processes: int) -> str:
    """Run every section, write the outputs; returns the text of the comparison."""
    from seatrack.api.evaluate import MAX_PROCESSES
    from seatrack.api.options import option_in
    from seatrack.api.options import prepare_outputs
    from seatrack.io.atomic import atomic_write
    from seatrack.report.demo import run_sections
    from seatrack.report.demo_page import demo_text
    from seatrack.report.demo_page import write_demo_page

    n = DEFAULT_RUNS if runs is None else runs
    option_in("--runs", n, 1, MAX_DEMO_RUNS)
    option_in("--processes", processes, 1, MAX_PROCESSES)
    prepare_outputs(_outputs(out), [out, out / "data"])
    t0 = time.perf_counter()
    _write_data(out)
    sections = run_sections(out, n, processes)
    seconds = time.perf_counter() - t0
    text = demo_text(sections, seconds)
    with atomic_write(out / "results.txt") as fh:
        fh.write(text)
    write_demo_page(out / "report.html", sections, seconds, n)
    return text


def _live_demo(http: str, speed: float) -> None:
    """``seatrack demo --live``: :mod:`seatrack.live.demo` into a live process."""
    import asyncio
    import threading

    from seatrack.commands.live import run_live
    from seatrack.commands.options import option_positive
    from seatrack.live.demo import radar_setup
    from seatrack.live.demo import start_replay
    from seatrack.live.process import LiveOptions
    from seatrack.live.sources import Source
    from seatrack.live.sources import parse_hostport

    option_positive("--speed", speed, 1e6)
    udp = Source("udp", "127.0.0.1", 0)
    opts = LiveOptions(ais=[udp], plots=[udp], radar=radar_setup(),
                       http=parse_hostport(http, "--http"))  # fmt: skip
    stop = threading.Event()

    def started(proc: object) -> None:
        a, p = proc.udp_ports  # type: ignore[attr-defined]
        start_replay({"ais": ("127.0.0.1", a), "plots": ("127.0.0.1", p)}, speed, stop)

    try:
        interrupted = asyncio.run(run_live(opts, typer.echo, on_start=started))
    finally:
        stop.set()
    if interrupted:
        raise typer.Abort()


def register(app: typer.Typer) -> None:
    @app.command("demo")
    def demo(
        out: Path = typer.Option(
            Path("seatrack-demo"), "--out", "-o", help="Folder for the report, plots and data."
        ),
        runs: int | None = typer.Option(
            None, "--runs", "-n", help=f"Runs of each tracking situation (default {DEFAULT_RUNS})."
        ),
        processes: int = typer.Option(
            2, "--processes", "-p", help="Situations run in parallel (results do not depend on it)."
        ),
        live: bool = typer.Option(
            False,
            "--live",
            help="replay a real AIS sample and a simulated radar into "
            "seatrack live and serve its map (until Ctrl-C)",
        ),
        http: str = typer.Option(
            "127.0.0.1:8080", "--http", help="--live: the map's HOST:PORT (port 0: any free)"
        ),
        speed: float = typer.Option(5.0, "--speed", help="--live: times real time"),
    ) -> None:
        """Show every method in the situation it is made for and write a one-page report.

        Turns (turning, IMM), range rate (multiple models), outliers (robust filters),
        bearings only (TMA), a landmark passage (navigation), AIS cleaning of a bundled
        sample and unlabelled plots (multi-target tracking): an honest comparison with one
        sentence per method on when to use it, printed and written to --out with the plots
        (report.html, one self-contained page). With --live: the live tracker on a replayed
        real AIS sample and a simulated radar, with its map (docs/live.md).
        """
        if live:
            _live_demo(http, speed)
            return
        # every output in the command's transaction: replaced together at the end
        typer.echo(run_demo(out, runs, processes), nl=False)
        typer.echo(
            f"open {out / 'report.html'}; try: seatrack track "
            f"{out / 'data' / 'plots_radar.csv'} --method turning --out tracks.csv"
        )
