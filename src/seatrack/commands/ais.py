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

import numpy as np
import typer

from seatrack.io.budget import parse_size
from seatrack.io.table import InputError
from seatrack.io.table import check_input_file


def tracker_config(
    sigma_pos: float, max_gap: float, max_speed: float, max_accel: float, smooth: bool
) -> Any:
    """The tracker configuration of the command's options (each checked, by name)."""
    from seatrack.commands.options import option_positive
    from seatrack.filters.ais import AisTrackerConfig

    option_positive("--sigma-pos", sigma_pos, 1e4)
    option_positive("--max-gap", max_gap, 1e9)
    option_positive("--max-speed", max_speed, 1e4)
    option_positive("--max-accel", max_accel, 1e3)
    if sigma_pos < AisTrackerConfig.sigma_pos_min_m:
        raise InputError(
            f"--sigma-pos: must be at least {AisTrackerConfig.sigma_pos_min_m} m, got {sigma_pos}"
        )
    return AisTrackerConfig(
        sigma_pos_m=sigma_pos,
        max_gap_s=max_gap,
        max_speed_kn=max_speed,
        max_accel_mps2=max_accel,
        smooth=smooth,
    )


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


def run(
    inputs: Sequence[Path],
    out: Path,
    cfg: Any,
    memory_limit: int,
    geojson: Path | None = None,
    html: Path | None = None,
    tile_url: str | None = None,
    use_dask: bool = False,
    scheduler: str | None = None,
) -> list[str]:
    """Track ``inputs`` into ``out`` (and the map files); returns the summary lines."""
    from seatrack.io.suspect import AisUnitCheck
    from seatrack.io.suspect import warn

    want_map = geojson is not None or html is not None
    maps: list[Any] = []
    units = AisUnitCheck()  # SOG in m/s, lat/lon swapped: warned about after the run

    def collect(r: Any, tr: Any) -> None:
        from seatrack.report.html import map_tracks

        units.add(r)
        if want_map:
            maps.extend(map_tracks(r, tr))

    if use_dask:
        if want_map:
            raise InputError("--geojson and --html are not available with --dask")
        from seatrack.io.ais.cluster import track_files_dask

        summary = track_files_dask(inputs, out, cfg, scheduler=scheduler)
    else:
        from seatrack.io.ais.pipeline import track_files

        summary = track_files(inputs, out, cfg, memory_limit=memory_limit, on_group=collect)
    lines = summary.lines()
    # the map files through io.atomic whatever the report module does with a path
    from seatrack.io.atomic import atomic_path

    if geojson is not None:
        from seatrack.report.html import write_geojson

        with atomic_path(geojson) as tmp:
            write_geojson(tmp, maps)
    if html is not None:
        from seatrack.report.html import write_html

        with atomic_path(html) as tmp:
            write_html(
                tmp,
                maps,
                title=f"AIS tracks: {', '.join(p.name for p in inputs)}",
                summary="; ".join(lines),
                tile_url=tile_url,
            )
    warn(units.warnings(", ".join(map(str, inputs))))  # after every output: a run, no error
    lines.append(f"wrote {out} ({summary.rows} rows)")
    lines += [f"wrote {p}" for p in (geojson, html) if p is not None]
    return lines


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
    from seatrack.io.ais.pipeline import DEFAULT_MEMORY_LIMIT

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
        memory_limit: str = typer.Option(
            f"{DEFAULT_MEMORY_LIMIT >> 30}G",
            "--memory-limit",
            help="peak memory to stay near (e.g. 1G, 800M): vessels are tracked in groups",
        ),
        use_dask: bool = typer.Option(
            False, "--dask", help="track on a Dask cluster (all files shuffled by MMSI)"
        ),
        scheduler: str | None = typer.Option(
            None, "--scheduler", help="Dask scheduler address (default: a local cluster)"
        ),
    ) -> None:
        """Track vessels in AIS logs: smoothed position, course, speed, turn rate, outliers."""
        from seatrack.io.budget import set_budget

        cfg = tracker_config(sigma_pos, max_gap, max_speed, max_accel, not no_smooth)
        limit = parse_size(memory_limit)
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
        for ln in run(inputs, out, cfg, limit, geojson, html, tile_url, use_dask, scheduler):
            typer.echo(ln)


def track_columns(tracks: Any) -> dict[str, np.ndarray]:
    """TRACKS value columns from :class:`~seatrack.filters.ais.AisTracks` (see
    :func:`seatrack.io.ais.output.track_columns`)."""
    from seatrack.io.ais.output import track_columns as columns

    return columns(tracks)
