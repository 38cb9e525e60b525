"""``seatrack track PLOTS.csv --method NAME [--config FILE] --out TRACK.csv``.

Reads the plots as columns, runs the method over all tracks of the file at once
(:func:`seatrack.filters.registry.run`) and writes the columns with pyarrow's CSV writer,
atomically (:mod:`seatrack.io.atomic`): no per-row Python loop on either side.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import typer
from numpy.typing import NDArray

__all__ = ["register", "write_track_csv", "track_table"]

_DECIMALS = 6


def _column(v: NDArray[Any]) -> Any:
    """A pyarrow array: floats rounded to 6 decimals with NaN written empty."""
    import pyarrow as pa

    a = np.asarray(v)
    if a.dtype.kind == "f":
        return pa.array(np.round(a, _DECIMALS), mask=~np.isfinite(a))
    if a.dtype.kind in "US":
        return pa.array(a.astype(str))
    return pa.array(a)


def track_table(labels: NDArray[Any], t: NDArray[Any], cols: Mapping[str, NDArray[Any]]) -> Any:
    """The TRACK.csv table: ``track, time_s`` then the method's columns, rows grouped by
    track (order of first appearance, time order within a track)."""
    import pyarrow as pa

    from seatrack.filters.registry import track_index

    ti, _ = track_index(labels)
    order = np.argsort(ti, kind="stable")
    names = ["track", "time_s", *cols]
    arrays = [_column(labels[order]), _column(t[order])]
    arrays += [_column(np.asarray(v)[order]) for v in cols.values()]
    return pa.table(arrays, names=names)


def write_track_csv(
    path: Path, labels: NDArray[Any], t: NDArray[Any], cols: Mapping[str, NDArray[Any]]
) -> int:
    """Write TRACK.csv atomically; returns the number of rows.

    Values are quoted only where needed (a track id holding a comma or a quote)."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    from seatrack.io.atomic import atomic_write

    table = track_table(labels, t, cols)
    with atomic_write(path, "wb") as fh:
        fh.write((",".join(table.column_names) + "\n").encode())
        try:
            pacsv.write_csv(
                table, fh, pacsv.WriteOptions(include_header=False, quoting_style="none")
            )
        except pa.ArrowInvalid:  # a value needs quoting: start the body again, quoted
            fh.seek(0)
            fh.truncate()
            pacsv.write_csv(table, fh, pacsv.WriteOptions(quoting_style="needed"))
    return int(table.num_rows)


def register(app: typer.Typer) -> None:
    from seatrack.filters.registry import METHODS

    names = ", ".join(f"{k} ({v[2]})" for k, v in METHODS.items())

    @app.command("track")
    def track(
        plots_csv: Path = typer.Argument(
            ...,
            help="PLOTS.csv: track, time_s, range_m, azimuth_deg, "
            "[elevation_deg], [range_rate_mps], [sensor_x_m, sensor_y_m, sensor_z_m]",
        ),
        method: str = typer.Option("ekf", "--method", "-m", help=f"filter: {names}"),
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
    ) -> None:
        """Run a tracking filter over recorded radar/sonar plots (without a track column:
        the multi-target tracker, see docs/tracking.md)."""
        from seatrack.commands.options import prepare_outputs
        from seatrack.config import load_toml
        from seatrack.filters.registry import method_class
        from seatrack.filters.registry import run
        from seatrack.io.multitarget import has_track_column
        from seatrack.io.multitarget import track_unlabelled
        from seatrack.io.plots import read_plots

        method_class(method)  # unknown method: fail before any work
        outputs = {"--out": out, "--plots-out": plots_out, "--plot": plot}
        prepare_outputs(outputs, inputs=[plots_csv, config], images=["--plot"])
        if not has_track_column(plots_csv):
            typer.echo(
                track_unlabelled(
                    plots_csv, out, method, config, all_tracks, plots_out, plot, association
                )
            )
            return
        prepare_outputs([out])
        table = load_toml(config) if config is not None else {}
        plots = read_plots(plots_csv)
        cols = run(method, plots, table, source=str(config) if config else "config")
        assert plots.track is not None
        n = write_track_csv(out, plots.track, plots.t, cols)
        n_tracks = len(set(plots.track.tolist()))
        rejected = int(np.count_nonzero(cols["status"] == "rejected"))
        note = f", {rejected} plot(s) rejected (status column)" if rejected else ""
        typer.echo(f"{method}: {n_tracks} track(s), {n} rows written to {out}{note}")
