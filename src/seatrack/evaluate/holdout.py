"""Hold-out evaluation of AIS tracks: withhold every k-th report, predict it from the track.

The criterion of real-data tracking without ground truth: every ``every``-th report of each
vessel (the one at position ``phase`` within each group, counted in time order from the
vessel's first usable report) is withheld from the tracker; the smoothed track at the
report's logged time is its prediction. The anchor is linear interpolation between the
nearest non-withheld reports of the same vessel before and after. Errors are horizontal
distances (m) in the vessel's local East-North plane. Withheld reports without a neighbour on
both sides, or without a track estimate (a new segment after a long gap), are left out of
both methods.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["HoldoutResult", "ais_holdout"]


@dataclass(frozen=True)
class HoldoutResult:
    """Per withheld report: ``row`` (index into the reports), ``track`` and ``interp``
    errors (m)."""

    row: NDArray[np.int64]
    track: NDArray[np.float64]
    interp: NDArray[np.float64]

    def summary(self) -> dict[str, float]:
        """Median and 95th percentile of both errors (m) and the number of reports."""
        return {
            "n": float(self.row.size),
            "track_median": float(np.median(self.track)),
            "interp_median": float(np.median(self.interp)),
            "track_p95": float(np.percentile(self.track, 95)),
            "interp_p95": float(np.percentile(self.interp, 95)),
        }


def ais_holdout(reports: Any, config: Any = None, every: int = 5, phase: int = 4) -> HoldoutResult:
    """Withhold every ``every``-th report of each vessel (position ``phase`` in each group)
    and compare the track's prediction with linear interpolation (see the module docstring).

    Parameters
    ----------
    reports : AisReports
    config : AisTrackerConfig, optional
    every, phase : int
        Group size and the withheld position in each group (``0 <= phase < every``).
    """
    from seatrack.filters.ais import track_reports
    from seatrack.geometry import local_frames

    if not 0 <= phase < every:
        raise ValueError(f"need 0 <= phase < every, got phase={phase}, every={every}")
    ok = np.flatnonzero(reports.valid)
    o = ok[np.lexsort((reports.t[ok], reports.mmsi[ok]))]
    m = reports.mmsi[o]
    first = np.r_[True, m[1:] != m[:-1]]
    start = np.maximum.accumulate(np.where(first, np.arange(o.size), 0))
    held = (np.arange(o.size) - start) % every == phase
    use = np.ones(len(reports), dtype=bool)
    use[o[held]] = False
    tr = track_reports(reports, config, use=use)
    E = local_frames(reports.mmsi, reports.lat, reports.lon, reports.valid).enu[:, :2]
    pos = np.arange(o.size)
    prev = np.maximum.accumulate(np.where(~held, pos, -1))
    nxt = np.minimum.accumulate(np.where(~held, pos, o.size)[::-1])[::-1]
    ii = np.flatnonzero(held & (prev >= 0) & (nxt < o.size))
    ii = ii[(m[prev[ii]] == m[ii]) & (m[nxt[ii]] == m[ii])]  # neighbours on both sides
    rows, rp, rn = o[ii], o[prev[ii]], o[nxt[ii]]
    span = reports.t[rn] - reports.t[rp]
    w = np.where(span > 0, (reports.t[rows] - reports.t[rp]) / np.where(span > 0, span, 1.0), 0.5)
    lerp = E[rp] + w[:, None] * (E[rn] - E[rp])
    e_lin = np.hypot(*(lerp - E[rows]).T)
    e_trk = np.hypot(tr.x_m[rows] - E[rows, 0], tr.y_m[rows] - E[rows, 1])
    has = np.isfinite(e_trk)
    return HoldoutResult(rows[has], e_trk[has], e_lin[has])
