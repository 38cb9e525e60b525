"""Per-vessel measurement noise of AIS positions, estimated from the vessel's own reports."""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from seatrack.filters.ais.config import CHI2_1_MEDIAN, AisTrackerConfig, trim_scale
from seatrack.filters.ais.plausibility import neighbours

FloatArray = NDArray[np.float64]

__all__ = ["position_noise", "group_median", "group_trimmed_mean", "sorted_by_group"]


def position_noise(
    vessel: NDArray[np.int64],
    t: FloatArray,
    xy: FloatArray,
    use: NDArray[np.bool_],
    config: AisTrackerConfig,
) -> FloatArray:
    """Per-vessel measurement noise of the reported positions, estimated from the vessel's own
    reports: ``(sigma_pos, sigma_time)`` per row (m, s).

    Model: ``z = p(t + tau) + e ~ p(t) + v tau + e`` with white position noise ``e``
    (``sigma_pos`` per axis) and a timestamp error ``tau`` (``sigma_time``: the one-second
    resolution and the reception latency of the logged time), i.e. the report covariance
    ``R = sigma_pos^2 I + sigma_time^2 v v^T`` used by the tracker.

    Estimate: rows sorted by (vessel, time); for every used report ``i`` with used
    neighbours ``p``, ``n`` of the same vessel (both intervals positive and at most
    ``noise_max_dt_s``), the chord residual ``r = z_i - ((1 - w) z_p + w z_n)``,
    ``w = (t_i - t_p) / (t_n - t_p)``, is split into its components across and along the
    chord direction; the chord speed is ``s = |z_n - z_p| / (t_n - t_p)``. On a locally
    straight, uniform track each component has variance ``c sigma^2`` with
    ``c = 1 + w^2 + (1 - w)^2`` (white errors of the three reports), where ``sigma^2`` is
    ``sigma_pos^2`` across and ``sigma_pos^2 + sigma_time^2 s^2`` along. Robust scales
    per vessel:

    * ``sigma_pos^2``: trimmed mean of ``x = r_cross^2 / c`` over all rows (at rest the
      chord direction is arbitrary: East when the chord is zero), keeping the smallest
      fraction ``noise_trim`` and dividing by ``E[chi2_1 | below its noise_trim
      quantile]``; clipped to ``[sigma_pos_min_m, sigma_pos_m]``. (A trimmed mean rather
      than the median: on grid-rounded feeds most residuals of a slow vessel are exactly
      zero and the median would be zero while the grid steps are not.)
    * ``sigma_time^2``: ``median(r_along^2 / (c s^2)) / median(chi2_1)`` over rows with
      ``s >= noise_min_speed_mps``, less ``sigma_pos^2 median(1 / s^2)``, clipped to
      ``[sigma_time_min_s, noise_max_time_s]``. The median ignores up to half the
      residuals (timestamps off by whole seconds, glitches, manoeuvres).

    Vessels with fewer than ``noise_min_reports`` residuals (moving residuals for
    ``sigma_time``) get ``sigma_pos_m`` and ``sigma_time_min_s``. Withheld reports
    (``use`` False) are not used. Measured on the real files (North Sea, chord residuals
    at 1-3 s spacing): cross-track 0.1-0.6 m, along-track growing with speed
    (``sigma_time`` ~0.4-0.6 s), the along-track errors being mostly whole-second
    timestamp offsets of single reports.
    """
    n = t.size
    tau_floor = config.sigma_time_min_s
    out = np.empty((n, 2))
    out[:, 0] = config.sigma_pos_m
    out[:, 1] = tau_floor
    if n == 0:
        return out
    ip, inn, has_p, has_n = neighbours(vessel, use)
    dtp = t - t[ip]
    dtn = t[inn] - t
    lim = config.noise_max_dt_s
    ok = use & has_p & has_n & (dtp > 0) & (dtn > 0) & (dtp <= lim) & (dtn <= lim)
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return out
    span = dtp[idx] + dtn[idx]
    w = dtp[idx] / span
    c = 1.0 + w**2 + (1.0 - w) ** 2
    chord = xy[inn[idx]] - xy[ip[idx]]
    r = xy[idx] - (xy[ip[idx]] + w[:, None] * chord)
    length = np.hypot(chord[:, 0], chord[:, 1])
    ux = np.where(length > 0, chord[:, 0] / np.where(length > 0, length, 1.0), 1.0)
    uy = np.where(length > 0, chord[:, 1] / np.where(length > 0, length, 1.0), 0.0)
    r_along = r[:, 0] * ux + r[:, 1] * uy
    r_cross = -r[:, 0] * uy + r[:, 1] * ux
    speed = length / span
    vid = vessel[idx]
    uv, inv = np.unique(vid, return_inverse=True)
    s_pos2 = group_trimmed_mean(inv, uv.size, r_cross**2 / c, config.noise_trim)
    n_all = np.bincount(inv, minlength=uv.size)
    s_pos2 = np.where(n_all >= config.noise_min_reports, s_pos2, config.sigma_pos_m**2)
    s_pos = np.clip(np.sqrt(s_pos2), config.sigma_pos_min_m, config.sigma_pos_m)
    mv = speed >= config.noise_min_speed_mps
    sp2 = np.where(mv, speed, 1.0) ** 2
    g = np.where(mv, inv, uv.size)  # parked rows go to an extra group
    tau2 = group_median(g, uv.size + 1, r_along**2 / (c * sp2))[:-1] / CHI2_1_MEDIAN
    tau2 -= s_pos**2 * group_median(g, uv.size + 1, 1.0 / sp2)[:-1]
    n_mv = np.bincount(g, minlength=uv.size + 1)[:-1]
    tau2 = np.where(n_mv >= config.noise_min_reports, tau2, 0.0)
    s_tau = np.clip(np.sqrt(np.maximum(tau2, 0.0)), tau_floor, config.noise_max_time_s)
    vi = np.minimum(np.searchsorted(uv, vessel), uv.size - 1)
    known = uv[vi] == vessel
    out[known, 0] = s_pos[vi[known]]
    out[known, 1] = s_tau[vi[known]]
    return out


def group_trimmed_mean(
    group: NDArray[np.int64], n_groups: int, x: FloatArray, keep: float
) -> FloatArray:
    """Per-group variance estimate from chi-square(1)-distributed ``x = r^2 / var``: the mean
    of the smallest fraction ``keep`` of each group's values, divided by its expectation
    ``E[X | X <= chi2_1(keep)] = F_3(chi2_1(keep)) / keep`` (``x f_1(x) = f_3(x)``)."""
    xs, count = sorted_by_group(group, x, n_groups)
    gs = np.repeat(np.arange(n_groups), count)
    first = np.r_[0, np.cumsum(count)[:-1]]
    n_keep = np.maximum(np.ceil(keep * count).astype(np.int64), 1)
    rank = np.arange(xs.size) - first[gs]
    kept = rank < n_keep[gs]
    tot = np.bincount(gs[kept], weights=xs[kept], minlength=n_groups)
    scale = trim_scale(keep)
    out = np.full(n_groups, np.nan)
    has = count > 0
    out[has] = tot[has] / n_keep[has] / scale
    return out


def group_median(group: NDArray[np.int64], n_groups: int, x: FloatArray) -> FloatArray:
    """Median of ``x`` per group ``0..n_groups-1`` (NaN for empty groups), vectorised."""
    xs, count = sorted_by_group(group, x, n_groups)
    first = np.r_[0, np.cumsum(count)[:-1]]
    out = np.full(n_groups, np.nan)
    has = count > 0
    lo = first[has] + (count[has] - 1) // 2
    hi = first[has] + count[has] // 2
    out[has] = 0.5 * (xs[lo] + xs[hi])
    return out


@njit(cache=True)
def _sorted_by_group(group, x, n_groups):  # pragma: no cover - compiled
    count = np.zeros(n_groups, dtype=np.int64)
    for g in group:
        count[g] += 1
    start = np.zeros(n_groups + 1, dtype=np.int64)
    for g in range(n_groups):
        start[g + 1] = start[g] + count[g]
    out = np.empty(x.size)
    pos = start[:-1].copy()
    for i in range(x.size):
        g = group[i]
        out[pos[g]] = x[i]
        pos[g] += 1
    for g in range(n_groups):
        out[start[g] : start[g + 1]].sort()
    return out, count


def sorted_by_group(
    group: NDArray[np.int64], x: FloatArray, n_groups: int
) -> tuple[FloatArray, NDArray[np.int64]]:
    """``x`` sorted by (group, value) -- ``x[np.lexsort((x, group))]`` by a counting sort of
    the groups and a sort within each -- and the count of each group ``0..n_groups-1``."""
    return _sorted_by_group(
        np.ascontiguousarray(group, dtype=np.int64),
        np.ascontiguousarray(x, dtype=np.float64),
        n_groups,
    )
