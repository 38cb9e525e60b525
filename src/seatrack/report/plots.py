"""Shared plotting helpers (matplotlib, no GUI: figures are built with the Agg canvas).

Plots show x East / y North in kilometres, times in seconds; inputs are SI arrays.
Functions return :class:`matplotlib.figure.Figure` objects (not pyplot state), so they are
safe in worker processes and tests; :func:`save` writes one to a PNG file.
"""

from __future__ import annotations

from collections.abc import Mapping
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["track_figure", "error_figure", "situation_figure", "ais_figure", "save"]


def _figure(size: tuple[float, float]) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _finish(fig: Any, ax: Any, title: str) -> Any:
    """Grid, legend and title (when given) of a one-panel figure; returns ``fig``."""
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    return fig


def _xy(a: ArrayLike) -> np.ndarray:
    v = np.asarray(a, dtype=float)
    return v[..., :2] / 1000.0


def track_figure(
    truth: Mapping[str, ArrayLike],
    estimates: Mapping[str, ArrayLike | Sequence[ArrayLike]] | None = None,
    plots: ArrayLike | None = None,
    ownship: ArrayLike | None = None,
    clutter: ArrayLike | None = None,
    title: str = "",
) -> Any:
    """Plan view of truth, estimates and measurements.

    Parameters
    ----------
    truth : name -> (N, 2+) positions, m
    estimates : label -> (M, 2+) estimated positions, m (NaN rows are gaps), or a list of
        such arrays (one per target; drawn in one colour under one label)
    plots : (K, 2+) measured positions (polar plots converted to x/y), m
    ownship : (L, 2+) own-ship track, m
    clutter : (C, 2+) false plots, m
    title : str

    The view is zoomed on the truth and own-ship tracks (clutter outside is cut off).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = _figure((7.5, 7.0))
    ax = fig.add_subplot(1, 1, 1)
    if clutter is not None and np.size(clutter):
        c = _xy(clutter)
        ax.plot(c[:, 0], c[:, 1], ".", color="0.75", ms=2, label="clutter")
    if plots is not None and np.size(plots):
        p = _xy(plots)
        ax.plot(p[:, 0], p[:, 1], "+", color="0.45", ms=4, label="measurements")
    if ownship is not None:
        o = _xy(ownship)
        ax.plot(o[:, 0], o[:, 1], "-", color="tab:blue", lw=2, label="own-ship")
        ax.plot(o[0, 0], o[0, 1], "o", color="tab:blue")
    for i, (name, tr) in enumerate(truth.items()):
        t = _xy(tr)
        ax.plot(t[:, 0], t[:, 1], "k-", lw=2, label="truth" if i == 0 else None)
        ax.plot(t[0, 0], t[0, 1], "ko", ms=4)
        ax.annotate(name, (t[0, 0], t[0, 1]), textcoords="offset points", xytext=(4, 4))
    colours = iter(
        [
            "tab:orange",
            "tab:green",
            "tab:red",
            "tab:purple",
            "tab:brown",
            "tab:pink",
            "tab:olive",
            "tab:cyan",
            "tab:gray",
        ]
        * 4
    )
    for label, est in (estimates or {}).items():
        tracks: list[Any] = [est] if isinstance(est, np.ndarray) else list(est)  # type: ignore[arg-type]
        colour = next(colours)
        for i, tr in enumerate(tracks):
            e = _xy(tr)
            ax.plot(e[:, 0], e[:, 1], "-", lw=1.2, color=colour, label=label if i == 0 else None)
    pts = [_xy(tr).reshape(-1, 2) for tr in truth.values()]
    if ownship is not None:
        pts.append(_xy(ownship).reshape(-1, 2))
    allp = np.concatenate(pts)
    lo, hi = np.nanmin(allp, axis=0), np.nanmax(allp, axis=0)
    pad = 0.1 * max(float(np.max(hi - lo)), 0.5)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_xlabel("East (km)")
    ax.set_ylabel("North (km)")
    ax.set_aspect("equal", adjustable="box")
    return _finish(fig, ax, title)


def error_figure(
    t: ArrayLike | Mapping[str, ArrayLike],
    errors: Mapping[str, ArrayLike],
    ylabel: str,
    title: str = "",
    bounds: Mapping[str, ArrayLike] | None = None,
    hlines: Mapping[str, float] | None = None,
    logy: bool = False,
) -> Any:
    """Error (or any statistic) against time, one line per method.

    Parameters
    ----------
    t : (N,) s, or label -> (N,) times per line
    errors : label -> (N,) values (NaN = gap)
    ylabel, title : str
    bounds : label -> (N,) reference curves drawn dashed (e.g. the PCRB)
    hlines : label -> value, horizontal reference lines (e.g. chi-square bounds)
    logy : logarithmic y axis

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = _figure((8.0, 4.0))
    ax = fig.add_subplot(1, 1, 1)

    def times(label: str) -> np.ndarray:
        if isinstance(t, Mapping):
            return np.asarray(t[label], dtype=float)
        return np.asarray(t, dtype=float)

    for label, e in errors.items():
        ax.plot(times(label), np.asarray(e, dtype=float), lw=1.2, label=label)
    for label, b in (bounds or {}).items():
        ax.plot(
            times(label) if isinstance(t, Mapping) and label in t else times(next(iter(errors))),
            np.asarray(b, dtype=float),
            "k--",
            lw=1.0,
            label=label,
        )
    for label, v in (hlines or {}).items():
        ax.axhline(v, color="0.4", ls=":", lw=1.0, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    if logy:
        from matplotlib.ticker import FuncFormatter

        def minor(v: float, _: Any) -> str:
            m = v / 10 ** np.floor(np.log10(v))
            return f"{v:g}" if np.isclose(m, 2) or np.isclose(m, 5) else ""

        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(FuncFormatter(minor))
    return _finish(fig, ax, title)


def situation_figure(
    truth: ArrayLike,
    estimates: Mapping[str, ArrayLike],
    plots: ArrayLike | None,
    t: ArrayLike,
    title: str = "",
    plots_label: str = "plots",
) -> Any:
    """Two panels: the plan view (truth, plots, estimates; km) and each estimate's position
    error against time (m; moving RMS over about 1/60 of the run).

    Parameters
    ----------
    truth : (N, 2+) true positions at the times ``t`` (N,), m
    estimates : label -> (N, 2+) estimated positions at the same times, m
    plots : (K, 2+) plot positions (or landmarks), m
    """
    fig = _figure((11.0, 4.6))
    ax, ae = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    tr = np.asarray(truth, dtype=float)[:, :2]
    if plots is not None and np.size(plots):
        p = _xy(plots)
        ax.plot(p[:, 0], p[:, 1], "+", color="0.6", ms=3, label=plots_label)
    ax.plot(tr[:, 0] / 1e3, tr[:, 1] / 1e3, "k-", lw=2, label="truth")
    tt = np.asarray(t, dtype=float)
    w = max(1, tt.size // 60)  # moving RMS over about 1/60 of the run
    kernel = np.ones(w) / w
    for label, est in estimates.items():
        e = np.asarray(est, dtype=float)[:, :2]
        (line,) = ax.plot(e[:, 0] / 1e3, e[:, 1] / 1e3, lw=1.2, label=label)
        err2 = np.convolve(np.sum((e - tr) ** 2, -1), kernel, mode="same")
        ae.plot(tt, np.sqrt(err2), lw=1.2, color=line.get_color(), label=label)
    ax.set_xlabel("East (km)")
    ax.set_ylabel("North (km)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best", fontsize=8)
    ae.set_xlabel("time (s)")
    ae.set_ylabel("position error, moving RMS (m)")
    ae.set_yscale("log")
    for a in (ax, ae):
        a.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig


def ais_figure(reports: Any, tracks: Any, title: str = "") -> Any:
    """Plan view (longitude, latitude) of AIS reports (grey), the smoothed tracks (one
    colour per vessel) and the reports flagged as outliers (red crosses).

    ``reports`` / ``tracks``: :class:`~seatrack.io.ais.AisReports` and the tracker's
    :class:`~seatrack.filters.ais.AisTracks` (one entry per report row).
    """
    fig = _figure((8.0, 6.0))
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(reports.lon, reports.lat, ".", color="0.7", ms=3, label="reports")
    for k, m in enumerate(np.unique(reports.mmsi[reports.mmsi >= 0])):
        sel = reports.mmsi == m
        ax.plot(
            tracks.lon[sel], tracks.lat[sel], lw=1.2, label="smoothed tracks" if k == 0 else None
        )
    out = np.asarray(tracks.outlier, dtype=bool)
    ax.plot(reports.lon[out], reports.lat[out], "x", color="red", ms=8, mew=2,
            label=f"outliers ({int(out.sum())})")  # fmt: skip
    ax.set_xlabel("longitude (deg)")
    ax.set_ylabel("latitude (deg)")
    return _finish(fig, ax, title)


def save(fig: Any, path: str | Path, dpi: int = 110) -> Path:
    """Write ``fig`` to ``path`` (format by extension, PNG by default) and return the path.

    The file is written atomically (:func:`seatrack.io.atomic.atomic_path`): a failed
    write leaves the previous file intact and no temporary behind. The folder is created
    when missing; a bad path raises :class:`~seatrack.io.atomic.OutputError`.
    """
    from seatrack.io.atomic import atomic_path

    p = Path(path)
    fmt = p.suffix[1:].lower() or "png"
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt)
    return p
