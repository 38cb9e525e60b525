"""Per-vessel measurement noise of AIS positions, estimated from the vessel's own reports."""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba import prange
from numpy.typing import NDArray

from seatrack.filters.ais.config import CHI2_1_MEDIAN
from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.config import trim_scale
from seatrack.filters.ais.kernel import largest_vessel
from seatrack.filters.ais.kernel import vessel_rows

FloatArray = NDArray[np.float64]

__all__ = ["position_noise"]


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

    Compiled, one vessel at a time on all threads (:func:`_noise_vessel`): each vessel's
    values are sorted and summed in ascending order, the arithmetic of the vectorised
    formulas above term by term.
    """
    n = t.size
    out = np.empty((n, 2))
    if n == 0:
        return out
    _noise_kernel(*vessel_rows(vessel, t, xy, use), _noise_params(config), out)
    return out


def _noise_params(cfg: AisTrackerConfig) -> tuple[float, ...]:
    """The constants of :func:`_noise_vessel` (computed here as the formulas do)."""
    return (
        float(cfg.noise_max_dt_s),
        float(cfg.noise_min_reports),
        float(cfg.noise_trim),
        float(trim_scale(cfg.noise_trim)),
        float(cfg.sigma_pos_m**2),
        float(cfg.sigma_pos_min_m),
        float(cfg.sigma_pos_m),
        float(cfg.sigma_time_min_s),
        float(cfg.noise_max_time_s),
        float(cfg.noise_min_speed_mps),
        float(CHI2_1_MEDIAN),
    )


@njit(cache=True, inline="always")
def _clip(x, lo, hi):  # pragma: no cover - compiled
    """``np.clip`` of a scalar (NaN stays NaN)."""
    if x != x:
        return x
    return min(max(x, lo), hi)


@njit(cache=True, inline="always")
def _median_sorted(x, n):  # pragma: no cover - compiled
    return 0.5 * (x[(n - 1) // 2] + x[n // 2])


@njit(cache=True, nogil=True)
def _noise_vessel(a, b, t, xy, use, par, xc, xa, xi, out):  # pragma: no cover - compiled
    """:func:`position_noise` of the vessel on rows ``a..b-1`` (``par``: :func:`_noise_params`;
    ``xc``, ``xa``, ``xi`` scratch of at least ``b - a`` values)."""
    lim, min_reports, keep, scale, sig2_default, s_min, s_max = par[:7]
    tau_floor, tau_max, min_speed, chi2_median = par[7:]
    n_all = 0
    n_mv = 0
    p = -1  # the used reports p, i, j: the residual of i against the chord p-j
    i = -1
    for j in range(a, b):
        if not use[j]:
            continue
        if p >= 0:
            dtp = t[i] - t[p]
            dtn = t[j] - t[i]
            if dtp > 0 and dtn > 0 and dtp <= lim and dtn <= lim:
                span = dtp + dtn
                w = dtp / span
                c = 1.0 + w * w + (1.0 - w) * (1.0 - w)
                chx = xy[j, 0] - xy[p, 0]
                chy = xy[j, 1] - xy[p, 1]
                rx = xy[i, 0] - (xy[p, 0] + w * chx)
                ry = xy[i, 1] - (xy[p, 1] + w * chy)
                length = math.hypot(chx, chy)
                ux, uy = (chx / length, chy / length) if length > 0 else (1.0, 0.0)
                r_along = rx * ux + ry * uy
                r_cross = -rx * uy + ry * ux
                speed = length / span
                xc[n_all] = r_cross * r_cross / c
                n_all += 1
                if speed >= min_speed:
                    sp2 = speed * speed
                    xa[n_mv] = r_along * r_along / (c * sp2)
                    xi[n_mv] = 1.0 / sp2
                    n_mv += 1
        p = i
        i = j
    s_pos, s_tau = s_max, tau_floor
    if n_all > 0:
        xc[:n_all].sort()
        n_keep = max(math.ceil(keep * n_all), 1)
        tot = 0.0
        for k in range(n_keep):
            tot += xc[k]
        s_pos2 = tot / n_keep / scale if n_all >= min_reports else sig2_default
        s_pos = _clip(math.sqrt(s_pos2), s_min, s_max)
        tau2 = 0.0
        if n_mv >= min_reports:
            tau2 = np.nan
            if n_mv > 0:
                xa[:n_mv].sort()
                xi[:n_mv].sort()
                tau2 = _median_sorted(xa, n_mv) / chi2_median
                tau2 -= s_pos * s_pos * _median_sorted(xi, n_mv)
        s_tau = _clip(math.sqrt(tau2 if not tau2 < 0.0 else 0.0), tau_floor, tau_max)
    for r in range(a, b):
        out[r, 0] = s_pos
        out[r, 1] = s_tau


@njit(cache=True, nogil=True, parallel=True)
def _noise_kernel(starts, chunks, t, xy, use, par, out):  # pragma: no cover - compiled
    """:func:`_noise_vessel` of every vessel, chunk by chunk on all threads."""
    for c in prange(chunks.size - 1):
        size = largest_vessel(starts, chunks, c)
        xc, xa, xi = np.empty(size), np.empty(size), np.empty(size)
        for v in range(chunks[c], chunks[c + 1]):
            _noise_vessel(starts[v], starts[v + 1], t, xy, use, par, xc, xa, xi, out)
