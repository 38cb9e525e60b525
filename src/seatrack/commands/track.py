"""``seatrack track PLOTS.csv --method NAME [--config FILE] --out TRACK.csv``.

A shell over :func:`seatrack.api.track.run_track`: the options are checked, the plots
tracked, and TRACK.csv (with ``--plots-out`` and ``--plot`` for unlabelled plots) written
atomically (:mod:`seatrack.io.atomic`).
"""

from __future__ import annotations

from pathlib import Path

import typer

__all__ = ["register"]


def _list_methods(value: bool) -> None:
    """``--list-methods``: every registered method, grouped, then exit."""
    if value:
        from seatrack.filters.registry import list_methods

        typer.echo(list_methods())
        raise typer.Exit()


def register(app: typer.Typer) -> None:
    # the method list is not imported here: the registry loads the compiled filters, and
    # ``seatrack --help`` stays fast; an unknown method is an error listing them

    @app.command("track")
    def track(
        plots_csv: Path = typer.Argument(
            ...,
            help="PLOTS.csv: track, time_s, range_m, azimuth_deg, "
            "[elevation_deg], [range_rate_mps], [sensor_x_m, sensor_y_m, sensor_z_m]; or "
            "PLOTS.ast (ASTERIX CAT048)",
        ),
        method: str = typer.Option(
            "ekf",
            "--method",
            "-m",
            help="tracking method: ekf, imm, turning, robust, ... (--list-methods lists "
            "them all; docs/architecture.md describes each)",
        ),
        config: Path | None = typer.Option(
            None,
            "--config",
            help="TOML file: method keys, and the sensor keys flat or in a [sensor] table",
        ),
        out: Path = typer.Option(..., "--out", "-o", help="TRACK.csv to write (one row per plot)"),
        all_tracks: bool = typer.Option(
            False, "--all-tracks", help="unlabelled plots: also tentative tracks"
        ),
        plots_out: Path | None = typer.Option(
            None, "--plots-out", help="unlabelled plots: each plot with its track or clutter"
        ),
        plot: Path | None = typer.Option(
            None, "--plot", help="unlabelled plots: PNG of plots and tracks"
        ),
        association: str | None = typer.Option(
            None, "--association", help="unlabelled plots: gnn or jpda"
        ),
        list_methods: bool = typer.Option(
            False,
            "--list-methods",
            callback=_list_methods,
            is_eager=True,
            help="list the methods (grouped, with when to use each) and exit",
        ),  # fmt: skip
    ) -> None:
        """Run a tracking filter over recorded radar/sonar plots (without a track column:
        the multi-target tracker, see docs/tracking.md)."""
        import numpy as np

        from seatrack.api.track import check_method
        from seatrack.api.track import config_table
        from seatrack.api.track import run_track
        from seatrack.api.track import write_track_csv
        from seatrack.commands.options import prepare_outputs
        from seatrack.io.multitarget import write_outputs

        check_method(method)  # unknown method: fail before any work
        outputs = {"--out": out, "--plots-out": plots_out, "--plot": plot}
        prepare_outputs(outputs, inputs=[plots_csv, config], images=["--plot"])
        table, source = config_table(config)
        res = run_track(plots_csv, method, table, source, association, all_tracks)
        if not res.labelled:
            write_outputs(res.tracker, out, plots_out, plot, f"{plots_csv.name}: {method}")
            typer.echo(res.tracker.summary(method, out))
            return
        plots, cols = res.plots, res.columns
        assert plots.track is not None and cols is not None
        n = write_track_csv(out, plots.track, plots.t, cols)
        n_tracks = len(set(plots.track.tolist()))
        rejected = int(np.count_nonzero(cols["status"] == "rejected"))
        note = f", {rejected} plot(s) rejected (status column)" if rejected else ""
        typer.echo(f"{method}: {n_tracks} track(s), {n} rows written to {out}{note}")
