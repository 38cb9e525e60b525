"""``seatrack ais``: clean and smooth real AIS tracks of many vessels at once.

``seatrack ais INPUT... --out TRACKS.csv|TRACKS.parquet [--geojson FILE] [--html FILE]``

INPUT files are AIS CSV exports (common / DMA / NOAA MarineCadastre columns, detected by
header; plain or ``.gz``/``.zst``/``.bz2``), Parquet files with those columns, or
timestamped NMEA ``!AIVDM`` logs (detected by content). A vessel seen in several files is one
track. By default the files are tracked in this process within ``--memory-limit``
(:mod:`seatrack.io.ais.pipeline`: vessels in groups, all cores); with ``--dask`` all reports
are shuffled by MMSI over a Dask cluster (:mod:`seatrack.io.ais.cluster`; a local cluster,
or ``--scheduler ADDRESS``), with the same output.

TRACKS has one row per input line that can hold a report, vessels in order of first
appearance and input order within each vessel; rejected rows keep their place with
``reject_reason`` set. All output paths are checked before any work, and every file is
written atomically.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import typer

from seatrack.errors import InputError


def tracker_config(
    sigma_pos: float, max_gap: float, max_speed: float, max_accel: float, smooth: bool
) -> Any:
    """The tracker configuration of the command's options (each checked, by name)."""
    from seatrack.api.ais import ais_config

    names = ("--sigma-pos", "--max-gap", "--max-speed", "--max-accel")
    return ais_config(sigma_pos, max_gap, max_speed, max_accel, smooth, names)


def _check_outputs(
    out: Path, extra: Sequence[Path | None], use_dask: bool, inputs: Sequence[Path] = ()
) -> None:
    """Check every output path before any work (a bad one fails fast): none is an input
    or another output."""
    from seatrack.commands.options import prepare_outputs

    if use_dask and out.suffix.lower() not in (".parquet", ".pq", ".csv"):
        raise InputError(f"--out: with --dask, give a .csv file or a .parquet folder, got {out}")
    geojson, html = (list(extra) + [None, None])[:2]
    prepare_outputs({"--out": out, "--geojson": geojson, "--html": html}, inputs=inputs)


def track_files(paths: Sequence[str | Path], config: Any = None) -> tuple[Any, Any]:
    """Read and track AIS files in memory (a vessel seen in several files is one track);
    returns ``(AisReports, AisTracks)`` row-aligned. For files of any size use
    :func:`seatrack.io.ais.track_files` (bounded memory, writes TRACKS)."""
    from seatrack.filters.ais import AisTrackerConfig
    from seatrack.filters.ais import track_reports
    from seatrack.io.ais import read_ais

    reports = read_ais(list(paths))
    return reports, track_reports(reports, config or AisTrackerConfig())


def not_utf8(paths: Sequence[Path]) -> Exception:
    """The error for an input that is not UTF-8: the first such file, its line and byte."""
    from seatrack.io.table import InputError

    for p in paths:
        data = p.read_bytes()
        try:
            data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            line = data[: exc.start].count(b"\n") + 1
            return InputError(f"{p}, line {line}: not UTF-8 text (byte 0x{data[exc.start]:02x})")
    return InputError(f"{', '.join(map(str, paths))}: not UTF-8 text")


def register(app: typer.Typer) -> None:
    """Add the ``ais`` sub-command to ``app``."""

    @app.command("ais")
    def ais(
        inputs: list[Path] = typer.Argument(
            ...,
            help="AIS CSV files (common/DMA/NOAA columns; .gz/.zst allowed), Parquet files "
            "or timestamped NMEA logs",
        ),
        out: Path = typer.Option(
            ..., "--out", "-o", help="TRACKS file to write: .csv, or .parquet"
        ),
        geojson: Path | None = typer.Option(None, "--geojson", help="GeoJSON file to write"),
        html: Path | None = typer.Option(None, "--html", help="offline HTML map to write"),
        sigma_pos: float = typer.Option(
            5.0,
            "--sigma-pos",
            help="largest AIS position sigma, m (outlier noise allowance; the tracker "
            "estimates each vessel's own, at most this)",
        ),
        max_gap: float = typer.Option(
            600.0, "--max-gap", help="split tracks at gaps longer than this, s"
        ),
        max_speed: float = typer.Option(50.0, "--max-speed", help="largest plausible speed, kn"),
        max_accel: float = typer.Option(
            2.0, "--max-accel", help="largest plausible acceleration, m/s^2"
        ),
        no_smooth: bool = typer.Option(False, "--no-smooth", help="forward filter only (no RTS)"),
        tile_url: str | None = typer.Option(
            None,
            "--tile-url",
            help="background tiles for the HTML map, e.g. https://.../{z}/{x}/{y}.png",
        ),
        memory_limit: str | None = typer.Option(
            None,
            "--memory-limit",
            help="peak memory to stay near (e.g. 1G, 800M; default 2G): vessels are tracked "
            "in groups",
        ),
        use_dask: bool = typer.Option(
            False, "--dask", help="track on a Dask cluster (all files shuffled by MMSI)"
        ),
        scheduler: str | None = typer.Option(
            None, "--scheduler", help="Dask scheduler address (default: a local cluster)"
        ),
    ) -> None:
        """Track vessels in AIS logs: smoothed position, course, speed, turn rate, outliers."""
        from seatrack.io.budget import parse_size
        from seatrack.io.budget import set_budget
        from seatrack.io.table import check_input_file

        cfg = tracker_config(sigma_pos, max_gap, max_speed, max_accel, not no_smooth)
        from seatrack.io.ais.pipeline import DEFAULT_MEMORY_LIMIT

        limit = DEFAULT_MEMORY_LIMIT if memory_limit is None else parse_size(memory_limit)
        set_budget(memory_bytes=limit)  # the one budget of the run (see seatrack.io.budget)
        if scheduler is not None and not use_dask:
            raise InputError("--scheduler needs --dask")
        if use_dask and (geojson is not None or html is not None):
            raise InputError("--geojson and --html are not available with --dask")
        if tile_url is not None and "{z}" not in tile_url:
            raise InputError(f"--tile-url: needs {{z}}, {{x}} and {{y}}, got {tile_url!r}")
        _check_outputs(out, [geojson, html], use_dask, inputs)
        for p in inputs:
            check_input_file(p, "an AIS file")
        from seatrack.api.ais import track_to_files

        args = (geojson, html, tile_url, use_dask, scheduler)
        for ln in track_to_files(inputs, out, cfg, limit, *args):
            typer.echo(ln)


def track_columns(tracks: Any) -> dict[str, Any]:
    """TRACKS value columns from :class:`~seatrack.filters.ais.AisTracks` (see
    :func:`seatrack.io.ais.output.track_columns`)."""
    from seatrack.io.ais.output import track_columns as columns

    return columns(tracks)
