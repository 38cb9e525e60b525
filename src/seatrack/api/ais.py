"""``seatrack.ais``: clean and smooth the AIS tracks of many vessels, as ``seatrack ais``.

The reports go through the bounded-memory pipeline of the command
(:func:`seatrack.io.ais.pipeline.track_files`); the frame returned holds the values of the
command's TRACKS.csv (its fixed decimals).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from seatrack.api.inputs import Source
from seatrack.api.inputs import as_file
from seatrack.api.inputs import read_frame
from seatrack.io.table import InputError
from seatrack.io.table import check_input_file

__all__ = ["ais", "ais_config", "track_to_files", "TEXT_COLUMNS"]

#: TRACKS columns read as text
TEXT_COLUMNS = ("time_utc", "outlier_reason", "reject_reason", "source")


def ais_config(
    sigma_pos_m: float = 5.0,
    max_gap_s: float = 600.0,
    max_speed_kn: float = 50.0,
    max_accel_mps2: float = 2.0,
    smooth: bool = True,
    names: Sequence[str] = ("sigma_pos_m", "max_gap_s", "max_speed_kn", "max_accel_mps2"),
) -> Any:
    """The AIS tracker configuration of the options, each checked and named as ``names``
    (the command line passes its option names).

    Raises
    ------
    InputError
        A value that is not finite and positive, above its limit (1e4 m, 1e9 s, 1e4 kn,
        1e3 m/s^2), or a position sigma below the tracker's floor.
    """
    from seatrack.api.options import option_positive
    from seatrack.filters.ais import AisTrackerConfig

    option_positive(names[0], sigma_pos_m, 1e4)
    option_positive(names[1], max_gap_s, 1e9)
    option_positive(names[2], max_speed_kn, 1e4)
    option_positive(names[3], max_accel_mps2, 1e3)
    floor = AisTrackerConfig.sigma_pos_min_m
    if sigma_pos_m < floor:
        raise InputError(f"{names[0]}: must be at least {floor} m, got {sigma_pos_m}")
    return AisTrackerConfig(
        sigma_pos_m=sigma_pos_m,
        max_gap_s=max_gap_s,
        max_speed_kn=max_speed_kn,
        max_accel_mps2=max_accel_mps2,
        smooth=smooth,
    )


def track_to_files(
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
    """Track the AIS files ``inputs`` into TRACKS ``out`` (CSV or Parquet) and the map files
    (GeoJSON, offline HTML); returns the summary lines. Every file is written atomically.
    Reports that look like SOG in m/s or swapped latitude and longitude are warned about
    (:class:`seatrack.io.suspect.AisUnitCheck`) after the outputs are written."""
    from seatrack.io.suspect import AisUnitCheck
    from seatrack.io.suspect import warn

    want_map = geojson is not None or html is not None
    maps: list[Any] = []
    units = AisUnitCheck()

    def collect(r: Any, tr: Any) -> None:
        units.add(r)
        if want_map:
            from seatrack.report.html import map_tracks

            maps.extend(map_tracks(r, tr))

    if use_dask:
        if want_map:
            raise InputError("--geojson and --html are not available with --dask")
        from seatrack.io.ais.cluster import track_files_dask

        summary = track_files_dask(inputs, out, cfg, scheduler=scheduler)
    else:
        from seatrack.io.ais.pipeline import ais_progress
        from seatrack.io.ais.pipeline import track_files

        bar = ais_progress(inputs)
        summary = track_files(
            inputs, out, cfg, memory_limit=memory_limit, on_group=collect, progress=bar
        )
    lines = summary.lines()
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


def ais(
    reports: Source | Sequence[str | os.PathLike[str]],
    *,
    sigma_pos_m: float = 5.0,
    max_gap_s: float = 600.0,
    max_speed_kn: float = 50.0,
    max_accel_mps2: float = 2.0,
    smooth: bool = True,
    memory_limit: int | None = None,
) -> Any:
    """Clean and smooth the AIS tracks of every vessel, as ``seatrack ais``.

    Parameters
    ----------
    reports : path, list of paths, pandas.DataFrame, pyarrow.Table or dict of arrays
        AIS CSV exports (common, DMA or NOAA columns; ``.gz``/``.zst``/``.bz2``), Parquet
        files or NMEA logs; or a table with the common columns ``mmsi``, ``time_utc``,
        ``lat``, ``lon`` (degrees), optional ``sog_kn``, ``cog_deg``, ``heading_deg``. A
        vessel seen in several files is one track.
    sigma_pos_m : float
        Largest AIS position sigma, m (the tracker estimates each vessel's own).
    max_gap_s : float
        Tracks are split at gaps longer than this, s.
    max_speed_kn, max_accel_mps2 : float
        Largest plausible speed (kn) and acceleration (m/s^2).
    smooth : bool
        Fixed-interval (RTS) smoothing; False: the forward filter only.
    memory_limit : int, optional
        Peak memory to stay near, bytes (default: that of ``seatrack ais``, 2 GiB).

    Returns
    -------
    pandas.DataFrame
        The TRACKS columns: one row per input line that can hold a report (vessels in
        order of first appearance, input order within a vessel): ``mmsi``, ``time_utc``
        (ISO 8601 text), ``lat``, ``lon``, ``course_deg``, ``speed_kn``, ``turn_rate_dps``
        and their standard deviations, ``x_m``, ``y_m``, ``time_offset_s``, ``outlier``,
        ``outlier_reason``, ``segment``, ``raw_lat``, ``raw_lon``, ``reject_reason``,
        ``source``, ``line``. Rejected rows keep their place with ``reject_reason`` set.

    Examples
    --------
    >>> import seatrack
    >>> from seatrack.data import ais_sample
    >>> out = seatrack.ais(ais_sample("dk_gothenburg_20170705_cpa.csv"))
    >>> list(out.columns[:6])
    ['mmsi', 'time_utc', 'lat', 'lon', 'course_deg', 'speed_kn']
    >>> int(out["mmsi"].nunique()) > 1
    True
    """
    from seatrack.io.ais.pipeline import DEFAULT_MEMORY_LIMIT

    cfg = ais_config(sigma_pos_m, max_gap_s, max_speed_kn, max_accel_mps2, smooth)
    limit = DEFAULT_MEMORY_LIMIT if memory_limit is None else int(memory_limit)
    paths_given = isinstance(reports, (list, tuple)) and all(
        isinstance(p, (str, os.PathLike)) for p in reports
    )
    with contextlib.ExitStack() as stack:
        if paths_given:
            inputs = [check_input_file(Path(p), "an AIS file") for p in reports]
        else:
            inputs = [stack.enter_context(as_file(reports, "reports"))]
            if isinstance(reports, (str, os.PathLike)):
                check_input_file(inputs[0], "an AIS file")
        folder = stack.enter_context(tempfile.TemporaryDirectory(prefix="seatrack-"))
        out = Path(folder) / "tracks.csv"
        track_to_files(inputs, out, cfg, limit)
        return read_frame(out, TEXT_COLUMNS)
