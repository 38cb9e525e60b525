"""``seatrack ais``: clean and smooth real AIS tracks of many vessels at once.

``seatrack ais INPUT... --out TRACKS.csv [--geojson FILE] [--html FILE]``

INPUT files are AIS CSV exports (common / DMA / NOAA MarineCadastre columns, detected by
header) or timestamped NMEA ``!AIVDM`` logs (detected by content). By default all files
are read into one table (a vessel seen in several files is one track) and tracked in
process. With ``--dask`` each file is read and tracked as its own Dask task (vessels are
then *not* merged across files); Dask is imported only then (``pip install seatrack[dask]``).

TRACKS.csv has one row per input report, vessels in order of first appearance and input
order within each vessel; rejected rows keep their place with ``reject_reason`` set.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import typer


def _track_one(paths: Sequence[str], config: Any) -> tuple[Any, Any]:
    from seatrack.filters.ais_tracker import track_reports
    from seatrack.io.ais import read_ais

    reports = read_ais(list(paths))
    return reports, track_reports(reports, config)


def track_files(
    paths: Sequence[str | Path], config: Any = None, use_dask: bool = False
) -> tuple[Any, Any]:
    """Read and track AIS files; returns ``(AisReports, AisTracks)`` row-aligned.

    ``use_dask``: one Dask task per file (vessels not merged across files; the results are
    concatenated in file order). Dask is imported lazily.
    """
    from seatrack.filters.ais_tracker import AisTrackerConfig

    cfg = config or AisTrackerConfig()
    names = [str(p) for p in paths]
    if not use_dask or len(names) == 1:
        return _track_one(names, cfg)
    try:
        import dask
    except ImportError:
        raise ValueError("--dask needs the 'dask' package: pip install 'seatrack[dask]'") from None
    from seatrack.io.ais import concat_reports

    parts = dask.compute(*[dask.delayed(_track_one)([p], cfg) for p in names])
    reports = concat_reports([p[0] for p in parts])
    tr = [p[1] for p in parts]
    fields = type(tr[0]).__dataclass_fields__
    tracks = type(tr[0])(**{f: np.concatenate([getattr(x, f) for x in tr]) for f in fields})
    # segment ids are per file: make them unique
    offset = 0
    seg = tracks.segment
    start = 0
    for x in tr:
        n = x.segment.size
        s = seg[start : start + n]
        s[s >= 0] += offset
        offset = int(max(offset, s.max(initial=offset) + 1))
        start += n
    return reports, tracks


def track_columns(tracks: Any) -> dict[str, np.ndarray]:
    """TRACKS.csv value columns (degrees / knots) from :class:`AisTracks`."""
    from seatrack.filters.ais_tracker import OUTLIER_KINDS
    from seatrack.geometry import bearing_rad_to_deg, mps_to_knots

    course = np.asarray(tracks.course, float)
    course_deg = np.full(course.shape, np.nan)
    ok = np.isfinite(course)
    course_deg[ok] = bearing_rad_to_deg(course[ok])
    return {
        "lat": tracks.lat,
        "lon": tracks.lon,
        "course_deg": course_deg,
        "speed_kn": mps_to_knots(tracks.speed),
        "turn_rate_dps": np.degrees(tracks.turn_rate),
        "std_pos_m": tracks.std_pos_m,
        "std_course_deg": np.degrees(tracks.std_course),
        "std_speed_kn": mps_to_knots(tracks.std_speed),
        "std_turn_rate_dps": np.degrees(tracks.std_turn_rate),
        "x_m": tracks.x_m,
        "y_m": tracks.y_m,
        "time_offset_s": tracks.time_offset_s,
        "outlier": tracks.outlier,
        "outlier_reason": np.array(
            [OUTLIER_KINDS.get(int(k), "") for k in tracks.outlier_kind], dtype=object
        ),
        "segment": tracks.segment,
    }


def summary_lines(reports: Any, tracks: Any) -> list[str]:
    """Rows read / used / rejected by reason, outliers, vessels, segments, reports with a
    timestamp offset."""
    from seatrack.io.ais import rejection_counts

    n = len(reports)
    valid = reports.valid
    n_out = int(np.count_nonzero(tracks.outlier))
    used = int(np.count_nonzero(valid)) - n_out
    vessels = np.unique(reports.mmsi[valid]).size
    segs = np.unique(tracks.segment[tracks.segment >= 0]).size
    lines = [
        f"rows read: {n}",
        f"rows used: {used}",
        f"outliers (flagged, not used): {n_out}",
        f"rows rejected: {n - int(np.count_nonzero(valid))}",
    ]
    lines += [f"  {reason}: {k}" for reason, k in rejection_counts(reports).items()]
    if reports.skipped:
        lines.append(f"lines that are not position reports: {sum(reports.skipped.values())}")
        lines += [f"  {k}: {v}" for k, v in sorted(reports.skipped.items())]
    lines.append(f"vessels: {vessels}, track segments: {segs}")
    off = np.asarray(tracks.time_offset_s, float)
    n_off = int(np.count_nonzero(np.isfinite(off) & (off != 0)))
    if used:
        lines.append(
            f"reports with a whole-second timestamp offset: {n_off} ({100 * n_off / used:.1f} %)"
        )
    return lines


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
            ..., help="AIS CSV files (common/DMA/NOAA columns) or timestamped NMEA logs"
        ),
        out: Path = typer.Option(..., "--out", "-o", help="TRACKS.csv to write"),
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
        use_dask: bool = typer.Option(False, "--dask", help="one Dask task per input file"),
    ) -> None:
        """Track vessels in AIS logs: smoothed position, course, speed, turn rate, outliers."""
        from seatrack.commands.options import option_positive, prepare_outputs
        from seatrack.filters.ais_tracker import AisTrackerConfig
        from seatrack.io.ais import write_tracks_csv
        from seatrack.io.atomic import atomic_path

        option_positive("--sigma-pos", sigma_pos, 1e4)
        option_positive("--max-gap", max_gap, 1e9)
        option_positive("--max-speed", max_speed, 1e4)
        option_positive("--max-accel", max_accel, 1e3)
        cfg = AisTrackerConfig(
            sigma_pos_m=sigma_pos,
            max_gap_s=max_gap,
            max_speed_kn=max_speed,
            max_accel_mps2=max_accel,
            smooth=not no_smooth,
        )
        prepare_outputs([out, geojson, html])
        try:
            reports, tracks = track_files(inputs, cfg, use_dask=use_dask)
        except UnicodeDecodeError:
            raise not_utf8(inputs) from None
        with atomic_path(out) as tmp:
            n = write_tracks_csv(tmp, reports, track_columns(tracks))
        lines = summary_lines(reports, tracks)
        for ln in lines:
            typer.echo(ln)
        typer.echo(f"wrote {out} ({n} rows)")
        if geojson is not None or html is not None:
            from seatrack.report.html import map_tracks, write_geojson, write_html

            vt = map_tracks(reports, tracks)
            if geojson is not None:
                with atomic_path(geojson) as tmp:
                    write_geojson(tmp, vt)
                typer.echo(f"wrote {geojson}")
            if html is not None:
                with atomic_path(html) as tmp:
                    write_html(
                        tmp,
                        vt,
                        title=f"AIS tracks: {', '.join(p.name for p in inputs)}",
                        summary="; ".join(lines),
                        tile_url=tile_url,
                    )
                typer.echo(f"wrote {html}")
