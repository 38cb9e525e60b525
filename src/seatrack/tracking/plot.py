"""Picture of a multi-target run: plots, tracks, and GOSPA over time when truth is known.

Plan view in kilometres (x East, y North): every plot as a dot -- grey when no confirmed
track took it (clutter), in its track's colour otherwise -- confirmed tracks as coloured
lines outlined in black (coasting scans circled), tentative tracks as thin dashed lines,
truth (when given) as thin black dashed lines. With a GOSPA series a second panel shows
GOSPA and its localisation / missed / false parts against time.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

__all__ = ["tracks_figure"]


def _figure(size: tuple[float, float]) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _colour(track_id: int) -> Any:
    from matplotlib import colormaps

    return colormaps["tab20"]((int(track_id) * 7) % 20)


def tracks_figure(
    plot_pos: ArrayLike,
    plot_track: ArrayLike,
    t: ArrayLike,
    track: ArrayLike,
    status: ArrayLike,
    pos: ArrayLike,
    truth: Mapping[Any, ArrayLike] | None = None,
    gospa: Mapping[str, ArrayLike] | None = None,
    title: str = "",
) -> Any:
    """The figure (a :class:`matplotlib.figure.Figure`, not yet saved).

    Parameters
    ----------
    plot_pos : (N, 2) m -- Cartesian position of every plot
    plot_track : (N,) int -- track id of each plot, -1 for clutter
    t, track, status, pos : the track rows (time s, id, status 0 tentative / 1 confirmed /
        2 coasting, position ``(R, 2)`` m)
    truth : target id -> (K, 2) m positions (optional)
    gospa : series with ``t``, ``gospa``, ``localisation``, ``missed``, ``false`` (the
        parts as their ``p``-th roots), optional
    title : str
    """
    pp = np.asarray(plot_pos, dtype=float).reshape(-1, 2) / 1e3
    lab = np.asarray(plot_track)
    tt, tid = np.asarray(t, dtype=float), np.asarray(track)
    st, xy = np.asarray(status), np.asarray(pos, dtype=float).reshape(-1, 2) / 1e3
    fig = _figure((13.0, 6.5) if gospa is not None else (8.0, 7.5))
    if gospa is not None:
        ax, axg = fig.subplots(1, 2, width_ratios=[1.15, 1.0])
    else:
        ax, axg = fig.subplots(1, 1), None
    clutter = lab < 0
    ax.scatter(pp[clutter, 0], pp[clutter, 1], s=3, c="0.65", lw=0, label="clutter / unused plots")
    if (~clutter).any():
        cols = [_colour(k) for k in lab[~clutter]]
        ax.scatter(pp[~clutter, 0], pp[~clutter, 1], s=4, c=cols, lw=0, alpha=0.45,
                   label="plots of confirmed tracks")  # fmt: skip
    _draw_tracks(ax, tt, tid, st, xy)
    if truth:
        for k, (_, tp) in enumerate(truth.items()):
            a = np.asarray(tp, dtype=float).reshape(-1, 2) / 1e3
            ax.plot(a[:, 0], a[:, 1], "--", color="k", lw=0.6, zorder=4,
                    label="truth" if k == 0 else None)  # fmt: skip
    ax.set_xlabel("East (km)")
    ax.set_ylabel("North (km)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or "plots and tracks")
    if axg is not None and gospa is not None:
        _draw_gospa(axg, gospa)
    return fig


def _draw_tracks(
    ax: Any, t: NDArray[Any], track: NDArray[Any], status: NDArray[Any], xy: NDArray[Any]
) -> None:
    from matplotlib.patheffects import Normal
    from matplotlib.patheffects import Stroke

    order = np.lexsort((t, track))
    ids, starts = np.unique(track[order], return_index=True)
    bounds = np.append(starts, order.size)
    first_conf = first_tent = True
    for k, i in enumerate(ids):
        rows = order[bounds[k] : bounds[k + 1]]
        s, p = status[rows], xy[rows]
        col = _colour(int(i))
        tent = s == 0
        if tent.any():
            ax.plot(p[tent, 0], p[tent, 1], "--", color=col, lw=0.7,
                    label="tentative track" if first_tent else None)  # fmt: skip
            first_tent = False
        conf = ~tent
        if conf.any():
            ax.plot(p[conf, 0], p[conf, 1], "-", color=col, lw=2.0, zorder=3,
                    path_effects=[Stroke(linewidth=3.2, foreground="k"), Normal()],
                    label="confirmed track" if first_conf else None)  # fmt: skip
            first_conf = False
            coast = s == 2
            ax.plot(p[coast, 0], p[coast, 1], "o", mfc="none", color="k", ms=3, mew=0.6,
                    zorder=3)  # fmt: skip
            end = p[conf][-1]
            ax.annotate(str(i), end, fontsize=6, color=col, xytext=(2, 2),
                        textcoords="offset points")  # fmt: skip


def _draw_gospa(ax: Any, g: Mapping[str, ArrayLike]) -> None:
    t = np.asarray(g["t"], dtype=float)
    ax.plot(t, np.asarray(g["gospa"]), "k-", lw=1.5, label="GOSPA")
    for key, style in (("localisation", "C0-"), ("missed", "C3--"), ("false", "C1:")):
        if key in g:
            ax.plot(t, np.asarray(g[key]), style, lw=1.0, label=key)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("GOSPA and its parts (m)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("GOSPA over time")
