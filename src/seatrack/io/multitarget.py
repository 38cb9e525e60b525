"""Unlabelled plot files in, TRACKS.csv (and the plot labels) out: ``seatrack track`` on
plots without a ``track`` column.

Input (``PLOTS.csv``, header names exact, extra columns ignored): ``time_s``, ``range_m``,
``azimuth_deg`` (clockwise from North, [0, 360)), optional ``elevation_deg``,
``range_rate_mps`` and ``sensor_x_m``, ``sensor_y_m``, ``sensor_z_m``. All plots of a scan
share one time; rows are in time order (non-decreasing). The sensor velocity, for the
range rate, is the finite difference of the sensor positions of successive scans.

Outputs, all written atomically (:mod:`seatrack.io.atomic`):

* ``TRACKS.csv`` -- one row per confirmed track per scan while it lives: ``track``,
  ``time_s``, the common columns (``x_m`` ... ``std_z_m``), ``status`` (``confirmed`` or
  ``coasting``; ``tentative`` rows too with ``all_tracks``), ``plot_line`` (input line of
  the plot that updated the track, empty when coasting), then the filter's own columns;
* ``--plots-out`` -- every input plot, in input order, with its input ``line`` and the
  ``track`` it went to or ``clutter``;
* ``--plot`` -- a PNG of plots and tracks (:func:`seatrack.tracking.plot.tracks_figure`).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.config import ConfigError
from seatrack.config import config_keys
from seatrack.config import parse_config
from seatrack.filters import registry
from seatrack.filters.base import COMMON_COLUMNS
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.io.atomic import atomic_path
from seatrack.io.atomic import atomic_write
from seatrack.io.compressed import open_input
from seatrack.io.plots import LIMITS as PLOT_LIMITS
from seatrack.io.plots import unit_warnings
from seatrack.io.table import InputError
from seatrack.io.table import Table
from seatrack.io.table import check_input_file
from seatrack.io.table import check_times
from seatrack.io.table import decode_text
from seatrack.io.table import read_csv_table
from seatrack.progress import Progress
from seatrack.tracking import Tracker
from seatrack.tracking import TrackerConfig
from seatrack.tracking import TrackerRun
from seatrack.tracking import TrackStatus
from seatrack.tracking.auto import per_track_filter
from seatrack.tracking.auto import scan_period
from seatrack.tracking.roles import Associator

FloatArray = NDArray[np.float64]

__all__ = [
    "has_track_column",
    "read_unlabelled_plots",
    "make_filter",
    "sensor_noise",
    "split_config",
    "save_picture",
    "write_tracks",
    "write_plot_labels",
    "write_unlabelled_plots",
    "track_unlabelled_file",
    "run_unlabelled",
    "tracker_setup",
    "TrackerSetup",
    "tracks_text",
    "write_outputs",
    "UnlabelledRun",
]

REQUIRED = ("time_s", "range_m", "azimuth_deg")
OPTIONAL = ("elevation_deg", "range_rate_mps", "sensor_x_m", "sensor_y_m", "sensor_z_m")


def has_track_column(path: str | Path) -> bool:
    """Whether the CSV header of ``path`` has a ``track`` column (a labelled plot file)."""
    p = check_input_file(path, "a CSV file")
    if p.suffix.lower() == ".ast":  # ASTERIX CAT048: plots without track labels
        return False
    with open_input(p) as fh:  # decompressed when gzip, zstd or bzip2
        head = fh.read(1 << 16).splitlines()  # LF, CRLF or the old CR alone
    first = head[0] if head else b""
    text, _ = decode_text(first)  # UTF-8 (BOM dropped), else Latin-1, as every reader
    try:
        header = next(csv.reader([text]), [])
    except csv.Error as exc:
        raise InputError(f"{p}, line 1: not valid CSV ({exc})") from None
    return "track" in [h.strip() for h in header]


def _check_values(tab: Table) -> None:
    def bad(mask: NDArray[np.bool_], what: str) -> None:
        if mask.any():
            i = int(np.argmax(mask))
            raise InputError(f"{tab.path}, line {tab.lines[i]}: {what}")

    for c in OPTIONAL:
        if c in tab:
            nan = np.isnan(tab[c])
            bad(nan & ~nan.all(), f"column {c} is empty here but filled on other rows")
    rng, t = tab["range_m"], tab["time_s"]
    bad(rng <= 0, "range_m must be > 0")
    lo, hi = PLOT_LIMITS["min_range_m"], PLOT_LIMITS["range_m"]
    bad(rng < lo, f"range_m = {rng[np.argmax(rng < lo)]:g} is implausible (< {lo:g} m)")
    bad(rng > hi, f"range_m = {rng[np.argmax(rng > hi)]:g} is implausible (> {hi:g} m)")
    far = np.abs(t) > PLOT_LIMITS["time_s"]
    bad(far, f"time_s = {t[np.argmax(far)]:g} is implausible (|t| > {PLOT_LIMITS['time_s']:.4g} s)")
    gap = np.zeros(t.size, dtype=bool)
    gap[1:] = np.diff(t) > PLOT_LIMITS["gap_s"]  # in time order (checked after reading)
    bad(gap, f"time gap of more than {PLOT_LIMITS['gap_s']:g} s since the previous plot")
    az = tab["azimuth_deg"]
    bad((az < 0) | (az >= 360), "azimuth_deg must be in [0, 360)")
    if "elevation_deg" in tab:
        bad(np.abs(tab["elevation_deg"]) > 90, "elevation_deg must be in [-90, 90]")


def read_unlabelled_plots(path: str | Path) -> Plots:
    """Read an unlabelled plot file into :class:`~seatrack.filters.base.Plots` (SI units,
    radians; ``line`` holds each plot's input line).

    Raises
    ------
    InputError
        Naming the file, line and problem: missing columns, empty or non-numeric values,
        range <= 0, azimuth outside [0, 360), elevation outside [-90, 90], times out of
        order, a column filled on some rows only.

    A ``.ast`` file is read as ASTERIX CAT048 (:func:`seatrack.io.asterix.cat048_plots`:
    time of day, range, azimuth; ``line`` = record number).
    """
    if Path(path).suffix.lower() == ".ast":
        from seatrack.io.asterix import cat048_plots
        from seatrack.io.asterix import read_cat048

        return cat048_plots(read_cat048(path), str(path))
    tab = read_csv_table(path, REQUIRED, OPTIONAL)
    check_times(tab, "time_s", strict=False)
    _check_values(tab)
    unit_warnings(tab)
    t = tab["time_s"]
    sensor = np.zeros((t.size, 3))
    for k, c in enumerate(("sensor_x_m", "sensor_y_m", "sensor_z_m")):
        if c in tab and not np.isnan(tab[c]).all():
            sensor[:, k] = tab[c]
    times, first, scan = np.unique(t, return_index=True, return_inverse=True)
    vel = np.zeros((times.size, 3))
    if times.size > 1:
        vel = np.stack([np.gradient(sensor[first, k], times) for k in range(3)], -1)

    def opt(c: str, f: Any = None) -> FloatArray | None:
        if c not in tab or np.isnan(tab[c]).all():
            return None
        return np.asarray(f(tab[c]) if f else tab[c])

    return Plots(
        t,
        tab["range_m"],
        np.radians(tab["azimuth_deg"]),
        opt("elevation_deg", np.radians),
        opt("range_rate_mps"),
        sensor,
        vel[scan.ravel()],
        tab.lines.astype(np.int64),
    )


# ---------------------------------------------------------------------------
# Configuration and the per-track filter
# ---------------------------------------------------------------------------
def split_config(table: Mapping[str, Any], source: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """``(tracker keys, method table)``: the tracker's keys (top level or a ``[tracker]``
    table) and the rest -- the method's keys and the sensor keys (flat or in ``[sensor]``),
    as :func:`seatrack.filters.registry.build` takes them."""
    tracker_keys = config_keys(TrackerConfig)
    tracker: dict[str, Any] = {}
    rest: dict[str, Any] = {}
    for k, v in table.items():
        if k == "tracker":
            if not isinstance(v, Mapping):
                raise ConfigError(f"{source}: [tracker] must be a table")
            tracker.update(v)
        elif k in tracker_keys:
            tracker[k] = v
        else:
            rest[k] = v
    return tracker, rest


def sensor_noise(table: Mapping[str, Any], source: str = "config") -> SensorNoise:
    """The sensor section of a method table (flat keys or ``[sensor]``)."""
    sensor_tab, _ = registry.split_config(table, source)
    return parse_config(SensorNoise, sensor_tab, source=source)


def make_filter(
    method: str,
    table: Mapping[str, Any],
    plots: Plots,
    source: str = "config",
    tracker: TrackerConfig | None = None,
) -> tuple[registry.Method, str]:
    """The per-track filter: registered method ``method`` configured from ``table`` (its
    keys and the sensor keys) for these plots, with the automatic process noise of
    :mod:`seatrack.tracking.auto` when ``table`` sets none (with the turn models of
    ``tracker.turn_rate``); and the noise rule applied."""
    turn = (tracker or TrackerConfig()).turn_rate
    return per_track_filter(
        method, table, plots.d, plots.has_range_rate, scan_period(plots.t), source,
        turn_rate=turn,
    )  # fmt: skip


# ---------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------
def _text(a: NDArray[Any]) -> NDArray[Any]:
    if a.dtype.kind == "f":
        out = np.char.mod("%.6f", np.where(np.isfinite(a), a, 0.0))
        return np.where(np.isfinite(a), out, "")
    return a.astype(str)


def tracks_text(run: TrackerRun, plots: Plots) -> tuple[list[str], list[NDArray[Any]]]:
    """TRACKS.csv as text: the header and one column of cells per name (6 decimals, NaN
    and a coasting track's ``plot_line`` empty)."""
    extra = [c for c in run.columns if c not in COMMON_COLUMNS]
    n = run.t.size
    labels = np.array([s.label for s in TrackStatus])
    line = np.where(run.plot >= 0, plots.line[np.maximum(run.plot, 0)], -1) if n else run.plot
    cols = [
        run.track.astype(str),
        np.char.mod("%.6f", run.t) if n else np.zeros(0, str),
        # no confirmed track at all (clutter only, a short file): the header and no rows
        *(_text(np.asarray(run.columns.get(c, np.zeros(0)))) for c in COMMON_COLUMNS),
        labels[run.status],
        np.where(line >= 0, line.astype(str), ""),
        *(_text(np.asarray(run.columns[c])) for c in extra),
    ]
    return ["track", "time_s", *COMMON_COLUMNS, "status", "plot_line", *extra], cols


def write_tracks(path: str | Path, run: TrackerRun, plots: Plots) -> int:
    """Write TRACKS.csv (see the module docstring); returns the number of rows."""
    header, cols = tracks_text(run, plots)
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(zip(*cols, strict=True))
    return int(run.t.size)


def write_unlabelled_plots(path: str | Path, plots: Plots) -> int:
    """Write plots as an unlabelled PLOTS.csv (time order; the sensor columns when the
    sensor is not at the origin): the input of the multi-target tracker."""
    order = np.argsort(plots.t, kind="stable")
    p = plots.take(order)
    head = ["time_s", "range_m", "azimuth_deg"]
    cols = [p.t, p.range, np.degrees(p.azimuth) % 360.0]
    if p.elevation is not None:
        head.append("elevation_deg")
        cols.append(np.degrees(p.elevation))
    if p.range_rate is not None:
        head.append("range_rate_mps")
        cols.append(p.range_rate)
    if np.any(p.sensor != 0):
        head += ["sensor_x_m", "sensor_y_m", "sensor_z_m"]
        cols += [p.sensor[:, 0], p.sensor[:, 1], p.sensor[:, 2]]
    text = [np.char.mod("%.6f", c) for c in cols]
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        w.writerows(zip(*text, strict=True))
    return len(p)


def write_plot_labels(path: str | Path, plots: Plots, labels: NDArray[np.int64]) -> int:
    """Write every plot with its input line and its track id (or ``clutter``)."""
    order = np.argsort(plots.line, kind="stable")
    num = lambda a: np.char.mod("%.6f", a)  # noqa: E731
    cols = [plots.line.astype(str), num(plots.t), num(plots.range), num(np.degrees(plots.azimuth))]
    head = ["line", "time_s", "range_m", "azimuth_deg"]
    if plots.elevation is not None:
        cols.append(np.char.mod("%.6f", np.degrees(plots.elevation)))
        head.append("elevation_deg")
    if plots.range_rate is not None:
        cols.append(np.char.mod("%.6f", plots.range_rate))
        head.append("range_rate_mps")
    cols.append(np.where(labels >= 0, labels.astype(str), "clutter"))
    head.append("track")
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        w.writerows(zip(*(c[order] for c in cols), strict=True))
    return len(plots)


# ---------------------------------------------------------------------------
# The command's entry point
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class UnlabelledRun:
    """What :func:`track_unlabelled_file` did."""

    plots: Plots
    run: TrackerRun
    tracker: Tracker
    rows: int
    noise: str = "given"  #: process-noise rule (:func:`seatrack.tracking.auto.per_track_filter`)

    def summary(self, method: str, out: Path) -> str:
        n_clutter = int((self.run.plot_track < 0).sum())
        noise = {
            "given": "as configured",
            "own": "the method's defaults",
            "levels": "automatic (two-level IMM)",
            "wrap": "the method's + manoeuvre level",
        }
        text = noise.get(self.noise, self.noise)
        w = self.tracker.config.turn_rate
        if self.noise in ("levels", "wrap") and w > 0:
            text += f", turn models +-{math.degrees(w):g} deg/s"
        return (
            f"{method} multi-target ({self.tracker.config.association}): "
            f"{self.run.scan_times.size} scans, {len(self.plots)} plots "
            f"({n_clutter} clutter or unconfirmed), {self.run.confirmed_ids.size} confirmed "
            f"tracks, {self.rows} rows written to {out}; clutter "
            f"{self.tracker.clutter.per_scan:.1f} plots/scan, Pd {self.tracker.detection.pd:.2f}"
            f"; process noise {text}"
        )  # fmt: skip


@dataclass(frozen=True)
class TrackerSetup:
    """A parsed configuration table of the multi-target tracker (:func:`tracker_setup`):
    the plots' noise, the tracker keys and the per-track method's table (method keys plus
    the sensor keys, as :func:`seatrack.filters.registry.build` takes it); ``source``
    names the table in error messages."""

    sensor: SensorNoise
    tracker: TrackerConfig
    method_table: dict[str, Any]
    source: str = "config"


def tracker_setup(
    table: Mapping[str, Any], source: str = "config", association: str | None = None
) -> TrackerSetup:
    """The :class:`TrackerSetup` of a configuration table (:func:`split_config`);
    ``association`` (``gnn`` or ``jpda``) overrides the table's."""
    t_tab, m_tab = split_config(table, source)
    if association is not None:
        if association not in ("gnn", "jpda"):
            raise InputError(f"--association: must be gnn or jpda, got {association!r}")
        t_tab = {**t_tab, "association": association}
    tcfg = parse_config(TrackerConfig, t_tab, source=source)
    return TrackerSetup(sensor_noise(m_tab, source), tcfg, m_tab, source)


def run_unlabelled(
    plots: Plots,
    method: str,
    setup: TrackerSetup,
    all_tracks: bool = False,
    associator: Associator | None = None,
    progress: Progress | None = None,
) -> UnlabelledRun:
    """The multi-target tracker of ``seatrack track`` on unlabelled plots: the per-track
    filter of :func:`make_filter` (automatic noise levels), the sensor noise and tracker
    keys of ``setup``; ``rows`` of the result is the number of TRACKS rows. ``associator``
    replaces the configured association role (:class:`seatrack.tracking.roles.Associator`);
    ``progress`` is told of the plots done after every scan."""
    tcfg = setup.tracker
    flt, noise = make_filter(method, setup.method_table, plots, setup.source, tcfg)
    tracker = Tracker(flt.filter, associator=associator, sensor=setup.sensor, config=tcfg)
    run = tracker.run(flt.prepare(plots), all_tracks=all_tracks, progress=progress)
    return UnlabelledRun(plots, run, tracker, int(run.t.size), noise)


def track_unlabelled_file(
    path: Path,
    method: str,
    table: Mapping[str, Any],
    source: str = "config",
    association: str | None = None,
    all_tracks: bool = False,
    associator: Associator | None = None,
) -> UnlabelledRun:
    """``seatrack track`` on a file without a ``track`` column: the configuration parsed
    (:func:`tracker_setup`) before the plots are read, then :func:`run_unlabelled` (with the
    estimate and progress of a long run, :mod:`seatrack.progress`); :func:`write_outputs`
    writes the result."""
    setup = tracker_setup(table, source, association)  # configuration errors first
    plots = read_unlabelled_plots(path)
    registry.check_range_rate(method, plots.has_range_rate, str(path))
    bar = Progress("seatrack track", len(plots), "plots", len(plots) * UNLABELLED_SECONDS_PER_PLOT)
    return run_unlabelled(plots, method, setup, all_tracks, associator, bar)


#: seconds per plot of the multi-target tracker, reading and writing included (ekf, GNN:
#: ``seatrack track`` on 1,000 scans of 100 targets and 100 clutter plots took 6.2-6.9 s on
#: the 2-core development machine at load 2-5)
UNLABELLED_SECONDS_PER_PLOT = 3.5e-5


def write_outputs(
    res: UnlabelledRun,
    out: Path,
    plots_out: Path | None = None,
    plot: Path | None = None,
    title: str = "",
) -> None:
    """TRACKS.csv, and the plot labels and the picture when asked for."""
    write_tracks(out, res.run, res.plots)
    if plots_out is not None:
        write_plot_labels(plots_out, res.plots, res.run.plot_track)
    if plot is not None:
        assoc = res.tracker.config.association.upper()
        save_picture(plot, res.plots, res.run, title=f"{title} + {assoc}")


def save_picture(
    path: Path,
    plots: Plots,
    run: TrackerRun,
    truth: Mapping[Any, Any] | None = None,
    gospa: Mapping[str, Any] | None = None,
    title: str = "",
) -> None:
    """Write the plots-and-tracks PNG (with GOSPA over time when given) atomically."""
    from seatrack.tracking.plot import tracks_figure

    xy = plots.positions()[:, :2]
    pos = np.stack([run.columns["x_m"], run.columns["y_m"]], -1) if run.t.size else np.zeros((0, 2))
    fig = tracks_figure(xy, run.plot_track, run.t, run.track, run.status, pos, truth, gospa, title)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
