"""Plot of TMA solutions: geography (own ship, bearing lines, estimated target tracks with
95 % ellipses) and bearing residuals over time. Degrees and kilometres at this edge only."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from seatrack.io.atomic import atomic_path
from seatrack.tma.bounds import ellipse
from seatrack.tma.problem import Bearings
from seatrack.tma.result import TMASolution

__all__ = ["plot_solutions"]


def plot_solutions(
    contacts: Mapping[str, Bearings],
    solutions: Mapping[str, TMASolution],
    path: str | Path,
    n_ellipses: int = 5,
    max_lines: int = 40,
) -> None:
    """Write a PNG (or any matplotlib format by suffix) with two panels.

    Left: own-ship track, bearing lines (at most ``max_lines`` per contact, drawn to
    1.3 x the estimated range, or 20 km when unobservable), the estimated target track and
    ``n_ellipses`` 95 % position ellipses along it (observable and converged solutions
    only). Right: bearing residuals (deg) against time. Written atomically
    (:func:`seatrack.io.atomic.atomic_path`).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Ellipse

    fig, (ax, axr) = plt.subplots(1, 2, figsize=(13, 6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (cid, b) in enumerate(contacts.items()):
        col = colors[k % len(colors)]
        sol = solutions[cid]
        ax.plot(
            b.observer[:, 0] / 1e3,
            b.observer[:, 1] / 1e3,
            "k-",
            lw=1,
            label="own ship" if k == 0 else None,
        )
        idx = np.unique(np.round(np.linspace(0, len(b) - 1, min(max_lines, len(b)))).astype(int))
        if sol.valid:
            est = sol.position_at(b.t)
            length = 1.3 * np.hypot(*(est - b.observer).T)
        else:
            est = None
            length = np.full(len(b), 20_000.0)
        for i in idx:
            e = b.observer[i] + length[i] * np.array([np.sin(b.bearing[i]), np.cos(b.bearing[i])])
            ax.plot(
                [b.observer[i, 0] / 1e3, e[0] / 1e3],
                [b.observer[i, 1] / 1e3, e[1] / 1e3],
                color=col,
                lw=0.4,
                alpha=0.4,
            )
        if est is not None:
            ax.plot(est[:, 0] / 1e3, est[:, 1] / 1e3, "-", color=col, lw=2, label=f"contact {cid}")
            for tt in np.linspace(b.t[0], b.t[-1], n_ellipses):
                a, c, o = ellipse(sol.position_covariance_at(float(tt)), 0.95)
                p = sol.position_at(np.array([tt]))[0]
                xy = (p[0] / 1e3, p[1] / 1e3)
                ang = 90 - np.degrees(o)  # matplotlib: counter-clockwise from East
                ax.add_patch(
                    Ellipse(xy, 2 * a / 1e3, 2 * c / 1e3, angle=ang, fill=False, color=col)
                )
        else:
            why = "not observable" if not sol.observable else "not converged"
            ax.plot([], [], color=col, label=f"contact {cid} ({why})")
        axr.plot(b.t, np.degrees(sol.residuals), ".-", color=col, lw=0.6, label=f"contact {cid}")
        for m in sol.manoeuvres:
            axr.axvline(m, color=col, ls="--", lw=0.8)
    ax.set_xlabel("East (km)")
    ax.set_ylabel("North (km)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("TMA solution (95 % ellipses)")
    ax.legend(loc="best", fontsize=8)
    axr.axhline(0.0, color="k", lw=0.5)
    axr.set_xlabel("time (s)")
    axr.set_ylabel("bearing residual (deg)")
    axr.set_title("bearing residuals (dashed: leg changes)")
    fig.tight_layout()
    try:
        with atomic_path(path) as tmp:
            fig.savefig(str(tmp), dpi=110)
    finally:
        plt.close(fig)
