"""``fuse``: radar plots and AIS reports fused into one identified picture (docs/fusion.md).

>>> tables = fuse("ais.csv", "plots.csv", "radar.toml")   # doctest: +SKIP
>>> tables["radar_tracks"].query("`class` == 'dark'")     # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.api.inputs import Source
from seatrack.api.inputs import as_file
from seatrack.fusion.associate import FusionConfig
from seatrack.fusion.picture import CLASSES
from seatrack.fusion.picture import Picture
from seatrack.fusion.picture import fuse_picture
from seatrack.fusion.picture import load_fusion_config
from seatrack.fusion.picture import parse_fusion_config
from seatrack.fusion.picture import with_association
from seatrack.io.ais import read_ais
from seatrack.io.multitarget import read_unlabelled_plots
from seatrack.io.radar import RadarSetup

__all__ = ["fuse", "picture_tables", "TABLES"]

#: the tables of a picture, in the order ``seatrack fuse`` writes them
TABLES = ("radar_tracks", "ais_vessels", "ais_reports")


def _text(ids: Any, names: Any) -> Any:
    ids = np.asarray(ids)
    return (
        np.where(ids >= 0, np.asarray(names, dtype=object)[np.maximum(ids, 0)], "")
        if np.size(names)
        else np.full(ids.size, "", dtype=object)
    )


def picture_tables(pic: Picture) -> dict[str, Any]:
    """The three :data:`TABLES` of a :class:`~seatrack.fusion.picture.Picture` as pandas
    DataFrames (columns in docs/fusion.md; degrees at the edge, ``time_s`` Unix time)."""
    import pandas as pd

    r, a = pic.radar, pic.ais
    lat, lon = pic.geodetic(r.pos)
    mmsi_text = np.array([str(m) for m in a.vessel_mmsi], dtype=object)
    radar = pd.DataFrame({
        "track": r.track, "time_s": r.t, "x_m": r.pos[:, 0], "y_m": r.pos[:, 1],
        "lat_deg": lat, "lon_deg": lon, "status": r.status,
        "mmsi": _text(pic.radar_vessel, mmsi_text), "vessel": _text(pic.radar_vessel,
                                                                    a.vessel_name),
        "identity_prob": pic.identity_prob, "class": np.asarray(CLASSES)[pic.klass],
        "covered": pic.radar_covered,
    })  # fmt: skip
    vlat, vlon = pic.geodetic(pic.v_pos)
    vessels = pd.DataFrame({
        "vessel": _text(pic.v_vessel, a.vessel_name), "mmsi": _text(pic.v_vessel, mmsi_text),
        "time_s": pic.v_time, "x_m": pic.v_pos[:, 0], "y_m": pic.v_pos[:, 1],
        "lat_deg": vlat, "lon_deg": vlon, "covered": pic.v_covered,
        "track": pd.array(np.where(pic.v_track >= 0, pic.v_track, -1), dtype="Int64"),
        "not_seen": pic.v_not_seen,
    })  # fmt: skip
    vessels.loc[vessels["track"] < 0, "track"] = pd.NA
    rep = pic.reports
    rows = a.rows
    reports = pd.DataFrame({
        "line": rep.line[rows], "mmsi": rep.mmsi[rows], "vessel": _text(a.vessel, a.vessel_name),
        "time_s": rep.t[rows], "lat_deg": rep.lat[rows], "lon_deg": rep.lon[rows],
        "gap": a.gap, "jump": a.jump, "identity_conflict": a.conflict,
    })  # fmt: skip
    if len(rep.sources) > 1:
        reports.insert(0, "source", np.asarray(rep.sources, dtype=object)[rep.source[rows]])
    return {"radar_tracks": radar, "ais_vessels": vessels, "ais_reports": reports}


def fuse(
    ais: Source | list[str | Path],
    plots: Source,
    config: str | Path | Mapping[str, Any] | tuple[RadarSetup, FusionConfig],
    association: str | None = None,
) -> dict[str, Any]:
    """Fuse AIS reports with radar plots: ``{table name: pandas.DataFrame}`` (:data:`TABLES`).

    Parameters
    ----------
    ais : AIS file(s) in any format ``seatrack ais`` reads (reports or its TRACKS output), or
        a table (DataFrame, pyarrow Table, dict of arrays) with the AIS CSV columns.
    plots : unlabelled plots (``time_s`` Unix time, ``range_m``, ``azimuth_deg``): a CSV
        path or a table with those columns.
    config : ``radar.toml`` path, its parsed table, or ``(RadarSetup, FusionConfig)``.
    association : ``"track"`` (AIS tracks associated with the radar tracks) or
        ``"measurement"`` (AIS reports update the radar tracks); default: the ``[fusion]``
        table's ``association`` (itself ``"track"`` by default). docs/fusion.md compares
        the two.

    Raises
    ------
    InputError, ConfigError
        Bad files or keys, naming the file, line or key.
    """
    if isinstance(config, tuple):
        setup, cfg = config
        source = "radar config"
    elif isinstance(config, Mapping):
        setup, cfg = parse_fusion_config(config)
        source = "radar config"
    else:
        setup, cfg = load_fusion_config(config)
        source = str(config)
    if association is not None:
        cfg = with_association(cfg, association)
    with as_file(plots, "plots") as ppath:
        p = read_unlabelled_plots(ppath)
    if isinstance(ais, (list, tuple)) and all(isinstance(x, (str, os.PathLike)) for x in ais):
        reports = read_ais(list(ais))
    else:
        with as_file(ais, "ais") as apath:  # type: ignore[arg-type]
            reports = read_ais([apath])
    return picture_tables(fuse_picture(reports, p, setup, cfg, source))
