"""``seatrack.track``: a tracking filter over radar / sonar plots, as ``seatrack track``.

Labelled plots (a ``track`` column) run one method over every track at once
(:func:`seatrack.filters.registry.run`); unlabelled plots run the multi-target tracker
with the method as its per-track filter and the automatic noise levels of
:mod:`seatrack.tracking.auto` (:func:`seatrack.io.multitarget.run_unlabelled`). The
frame returned holds exactly the values of the command's ``TRACK.csv`` (6 decimals).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.api.inputs import Source
from seatrack.api.inputs import as_file
from seatrack.api.sensor import Sensor
from seatrack.io.table import InputError

__all__ = [
    "track",
    "TrackRun",
    "run_track",
    "check_method",
    "config_table",
    "track_table",
    "write_track_csv",
]

#: decimals of the TRACK.csv numbers
DECIMALS = 6


def _column(v: NDArray[Any]) -> Any:
    """A pyarrow array: floats rounded to 6 decimals with NaN written empty."""
    import pyarrow as pa

    a = np.asarray(v)
    if a.dtype.kind == "f":
        return pa.array(np.round(a, DECIMALS), mask=~np.isfinite(a))
    if a.dtype.kind in "US":
        return pa.array(a.astype(str))
    return pa.array(a)


def track_table(labels: NDArray[Any], t: NDArray[Any], cols: Mapping[str, NDArray[Any]]) -> Any:
    """The TRACK.csv table of labelled plots (pyarrow): ``track, time_s`` then the method's
    columns, rows grouped by track (order of first appearance, time order within a track),
    numbers rounded to 6 decimals."""
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
    """Write TRACK.csv of labelled plots atomically; returns the number of rows.

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


def check_method(method: str) -> None:
    """Fail with a :class:`~seatrack.config.ConfigError` listing the registered methods when
    ``method`` is not one of them."""
    from seatrack.config import ConfigError
    from seatrack.filters.registry import METHODS

    if method not in METHODS:
        raise ConfigError(f"unknown method {method!r}; choose one of {', '.join(sorted(METHODS))}")


def config_table(
    config: Mapping[str, Any] | str | os.PathLike[str] | None,
    sensor: Sensor | None = None,
    target: str | None = None,
) -> tuple[dict[str, Any], str]:
    """``(table, source)``: the configuration (a mapping, or a TOML file) with the sensor
    and target class added; ``source`` names it in messages.

    Raises
    ------
    ConfigError
        The sensor or the target given both here and in ``config``.
    """
    from seatrack.config import ConfigError
    from seatrack.config import load_toml
    from seatrack.filters.registry import SENSOR_KEYS
    from seatrack.filters.registry import TARGET_KEY

    if config is None:
        table: dict[str, Any] = {}
        source = "config"
    elif isinstance(config, Mapping):
        table, source = dict(config), "config"
    else:
        table, source = load_toml(Path(config)), str(config)
    if sensor is not None:
        if not isinstance(sensor, Sensor):
            raise ConfigError(f"sensor: expected a seatrack.Sensor, got {type(sensor).__name__}")
        if "sensor" in table or any(k in table for k in SENSOR_KEYS):
            raise ConfigError(f"{source}: the sensor is given both in the config and as sensor=")
        table["sensor"] = sensor.table()
    if target is not None:
        if TARGET_KEY in table:
            raise ConfigError(f"{source}: the target is given both in the config and as target=")
        table[TARGET_KEY] = target
    return table, source


@dataclasses.dataclass(frozen=True)
class TrackRun:
    """What :func:`run_track` did: ``labelled`` plots give ``plots`` (with labels) and the
    method's ``columns``; unlabelled ones the :class:`seatrack.io.multitarget.UnlabelledRun`
    in ``tracker``."""

    method: str
    plots: Any
    columns: dict[str, NDArray[Any]] | None = None
    tracker: Any = None

    @property
    def labelled(self) -> bool:
        """Whether the plots carried track labels (one filter per label)."""
        return self.tracker is None

    def frame(self) -> Any:
        """The TRACK.csv columns as a pandas DataFrame (the values of the file)."""
        if self.labelled:
            assert self.columns is not None and self.plots.track is not None
            out = track_table(self.plots.track, self.plots.t, self.columns).to_pandas()
            out["track"] = out["track"].astype(object)
            return out
        import pandas as pd

        from seatrack.io.multitarget import tracks_text

        header, cols = tracks_text(self.tracker.run, self.tracker.plots)
        data: dict[str, Any] = {}
        for name, col in zip(header, cols, strict=True):
            data[name] = col.astype(object) if name in ("track", "status") else _numbers(col)
        frame = pd.DataFrame(data, columns=header)
        frame["plot_line"] = frame["plot_line"].astype("Int64")
        return frame


def _numbers(cells: NDArray[Any]) -> NDArray[np.float64]:
    """Text cells as float64 (empty: NaN)."""
    out = np.full(cells.shape, np.nan)
    given = cells != ""
    out[given] = cells[given].astype(float)
    return out


def run_track(
    plots: Source,
    method: str = "ekf",
    table: Mapping[str, Any] | None = None,
    source: str = "config",
    association: str | None = None,
    all_tracks: bool = False,
    associator: Any = None,
) -> TrackRun:
    """Read ``plots`` and run ``method`` on them as ``seatrack track`` does (labelled or
    unlabelled by the ``track`` column)."""
    from seatrack.filters.registry import check_range_rate
    from seatrack.filters.registry import run
    from seatrack.io.multitarget import has_track_column
    from seatrack.io.multitarget import track_unlabelled_file
    from seatrack.io.plots import read_plots
    from seatrack.progress import Progress

    check_method(method)  # unknown method: fail before any work
    tab = dict(table or {})
    with as_file(plots, "plots") as path:
        if not has_track_column(path):
            res = track_unlabelled_file(path, method, tab, source, association, all_tracks,
                                        associator)  # fmt: skip
            return TrackRun(method, res.plots, tracker=res)
        p = read_plots(path)
        check_range_rate(
            method,
            p.has_range_rate,
            str(plots) if isinstance(plots, (str, os.PathLike)) else "plots",
        )
    rate = LABELLED_SECONDS_PER_PLOT.get(method, DEFAULT_SECONDS_PER_PLOT)
    bar = Progress("seatrack track", len(p), "plots", len(p) * rate)
    return TrackRun(method, p, columns=run(method, p, tab, source=source, progress=bar))


#: seconds per plot of labelled tracking, reading and writing included (``seatrack track``
#: on 200 tracks x 1,000 plots on the 2-core development machine at load 2-5: ekf 2.8-3.8 s,
#: imm 4.2-4.5 s, robust-adaptive 13.4 s, turning 16.7 s for 200,000 plots)
LABELLED_SECONDS_PER_PLOT = {"turning": 8.5e-5, "robust-adaptive": 7e-5}
#: the same for every other method (the imm's figure, rounded up)
DEFAULT_SECONDS_PER_PLOT = 2.5e-5


def track(
    plots: Source,
    *,
    method: str = "ekf",
    sensor: Sensor | None = None,
    config: Mapping[str, Any] | str | os.PathLike[str] | None = None,
    target: str | None = None,
    association: Any = None,
    all_tracks: bool = False,
) -> Any:
    """Track radar or sonar plots with one method, exactly as ``seatrack track``.

    Parameters
    ----------
    plots : path, pandas.DataFrame, pyarrow.Table or dict of arrays
        The PLOTS columns: ``time_s``, ``range_m``, ``azimuth_deg`` (degrees clockwise
        from North, [0, 360)), optional ``elevation_deg``, ``range_rate_mps``,
        ``sensor_x_m``, ``sensor_y_m``, ``sensor_z_m`` (m, East / North / Up) and
        ``track``. With a ``track`` column each label is one target filtered on its
        own; without it the multi-target tracker finds the targets among clutter.
    method : str
        A method of :data:`seatrack.filters.registry.METHODS` (``ekf``, ``imm``, ...).
    sensor : Sensor, optional
        The sensor noise (default: the ``[sensor]`` keys of ``config``, else
        :class:`Sensor`'s defaults).
    config : mapping or path of a TOML file, optional
        The method's keys (and, for unlabelled plots, the ``[tracker]`` keys), as in the
        file of ``seatrack track --config``.
    target : str, optional
        Target class (``ship``, ``submarine``, ``aircraft``, ``fighter``) setting the
        method's process noise and manoeuvre parameters.
    association : {"gnn", "jpda"} or Associator, optional
        Unlabelled plots: the data association (default: the config's, else GNN), or an
        object with the :class:`seatrack.tracking.roles.Associator` protocol (a user's
        own associator; every other role stays the default). Labelled plots do not use it.
    all_tracks : bool
        Unlabelled plots: also the rows of tentative tracks.

    Returns
    -------
    pandas.DataFrame
        The columns of ``TRACK.csv`` with its values (6 decimals). Labelled plots: one row
        per plot, ``track, time_s``, the position, velocity and standard deviations
        (``x_m`` ... ``std_z_m``), ``status``, ``nis`` and the method's own columns.
        Unlabelled plots: one row per live track per scan, with ``status`` and
        ``plot_line`` (the input line of the plot that updated the track).

    Raises
    ------
    InputError, ConfigError
        (both ``ValueError``) a bad plot table, naming the file or table, the line or
        row and the problem; an unknown method or a bad configuration key.

    Examples
    --------
    One target seen by a radar at the origin, moving East at 10 m/s:

    >>> import numpy as np, seatrack
    >>> from seatrack.geometry import bearing, bearing_rad_to_deg
    >>> t = np.arange(0.0, 60.0, 2.0)
    >>> x, y = 1000.0 + 10.0 * t, np.full(t.size, 5000.0)
    >>> plots = {"track": ["A"] * t.size, "time_s": t, "range_m": np.hypot(x, y),
    ...          "azimuth_deg": bearing_rad_to_deg(bearing(x, y))}
    >>> out = seatrack.track(plots, method="ekf",
    ...                      sensor=seatrack.Sensor(sigma_range_m=5.0, sigma_azimuth_deg=0.1))
    >>> list(out.columns[:4]), len(out)
    (['track', 'time_s', 'x_m', 'y_m'], 30)
    >>> bool(abs(out["vx_mps"].iloc[-1] - 10.0) < 2.0)
    True
    """
    associator = None
    if association is not None and not isinstance(association, str):
        if not callable(getattr(association, "associate", None)):
            raise InputError(
                f"association: must be gnn, jpda or an Associator (with an associate method), "
                f"got {association!r}"
            )
        associator, association = association, None
    if association is not None and association not in ("gnn", "jpda"):
        raise InputError(f"association: must be gnn or jpda, got {association!r}")
    table, source = config_table(config, sensor, target)
    return run_track(plots, method, table, source, association, all_tracks, associator).frame()
