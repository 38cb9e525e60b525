"""Whole-second timestamp offsets of AIS reports, estimated from a smoothed track."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit
from numba import prange
from numpy.typing import NDArray

from seatrack.filters.ais.config import NX
from seatrack.filters.ais.config import AisTrackerConfig

FloatArray = NDArray[np.float64]

__all__ = [
    "MIN_OFFSET_REPORTS",
    "OffsetInputs",
    "OffsetScores",
    "apply_offsets",
    "estimate_prior",
    "offset_scores",
    "prior_counts",
    "std_offset_scores",
    "timestamp_offsets",
]

#: fewest reports with an identifiable offset (speed x 1 s > 3 sigma_pos) for the prior
MIN_OFFSET_REPORTS = 100


@njit(cache=True, error_model="numpy", inline="always")
def _score_row(
    ex, ey, vx, vy, d_old, a00, a01, a10, a11, sp, st, st_fine, cand, loo, q
):  # pragma: no cover - compiled
    """``q[k] = r_d^T C^-1 r_d`` of :func:`timestamp_offsets` for one row (residual ``e``
    of ``d = 0``, velocity ``v``, smoothed position covariance ``A``) and every candidate
    offset ``cand[k]`` (2x2 algebra written out; a degenerate row scores 0 at ``d = 0``)."""
    s2 = sp * sp
    c00 = s2 + st_fine * st_fine * vx * vx
    c01 = st_fine * st_fine * vx * vy
    c11 = s2 + st_fine * st_fine * vy * vy
    if loo:
        # R of the run, its inverse; X = I - A R^-1; B = X^-1; e = B r; M = B A
        t2 = st * st
        r00 = s2 + t2 * vx * vx
        r01 = t2 * vx * vy
        r11 = s2 + t2 * vy * vy
        dr = r00 * r11 - r01 * r01
        i00, i01, i11 = r11 / dr, -r01 / dr, r00 / dr
        x00 = 1.0 - (a00 * i00 + a01 * i01)
        x01 = -(a00 * i01 + a01 * i11)
        x10 = -(a10 * i00 + a11 * i01)
        x11 = 1.0 - (a10 * i01 + a11 * i11)
        dx = x00 * x11 - x01 * x10
        b00, b01, b10, b11 = x11 / dx, -x01 / dx, -x10 / dx, x00 / dx
        rx = ex + vx * d_old
        ry = ey + vy * d_old
        ex = b00 * rx + b01 * ry - vx * d_old
        ey = b10 * rx + b11 * ry - vy * d_old
        m00 = b00 * a00 + b01 * a10
        m01 = 0.5 * ((b00 * a01 + b01 * a11) + (b10 * a00 + b11 * a10))
        m11 = b10 * a01 + b11 * a11
        c00 += m00
        c01 += m01
        c11 += m11
    dc = c00 * c11 - c01 * c01
    j00, j01, j11 = c11 / dc, -c01 / dc, c00 / dc
    # (e + v d)^T C^-1 (e + v d) = a + 2 b d + c d^2
    qa = j00 * ex * ex + 2.0 * j01 * ex * ey + j11 * ey * ey
    qb = j00 * ex * vx + j01 * (ex * vy + ey * vx) + j11 * ey * vy
    qc = j00 * vx * vx + 2.0 * j01 * vx * vy + j11 * vy * vy
    for k in range(cand.shape[0]):
        d = cand[k]
        qk = qa + 2.0 * qb * d + qc * d * d
        # a degenerate row (not finite): d = 0
        q[k] = qk if math.isfinite(qk) else (0.0 if d == 0.0 else np.inf)


@njit(cache=True, inline="always")
def _cov(c00, c01, c10, c11, squared, i):  # pragma: no cover - compiled
    """Position covariance of row ``i``: the four entries, or (``squared``) from the
    kernel's std output: sigma x, the x-y covariance twice, sigma y."""
    if squared:
        return c00[i] * c00[i], c01[i], c10[i], c11[i] * c11[i]
    return c00[i], c01[i], c10[i], c11[i]


@njit(cache=True, nogil=True, parallel=True)
def _scorable(state, c00, c01, c10, c11, squared, usable, ok):  # pragma: no cover - compiled
    """Rows with a finite state (first four) and position covariance, and usable."""
    for i in prange(ok.size):
        a00, a01, a10, a11 = _cov(c00, c01, c10, c11, squared, i)
        fin = (
            math.isfinite(state[i, 0])
            and math.isfinite(state[i, 1])
            and math.isfinite(state[i, 2])
            and math.isfinite(state[i, 3])
        )
        fin = fin and math.isfinite(a00) and math.isfinite(a01)
        ok[i] = usable[i] and fin and math.isfinite(a10) and math.isfinite(a11)


@njit(cache=True, nogil=True, parallel=True, error_model="numpy")
def _score_rows(
    idx, xy, state, c00, c01, c10, c11, squared, sig, d_old, st_fine, cand, loo, q, ident
):  # pragma: no cover - compiled
    """Scores ``q`` and identifiability of the rows ``idx`` (see :func:`offset_scores`)."""
    for k in prange(idx.size):
        i = idx[k]
        a00, a01, a10, a11 = _cov(c00, c01, c10, c11, squared, i)
        vx, vy = state[i, 2], state[i, 3]
        ex, ey = xy[i, 0] - state[i, 0], xy[i, 1] - state[i, 1]
        sp = sig[i, 0]
        _score_row(
            ex, ey, vx, vy, d_old[i], a00, a01, a10, a11, sp, sig[i, 1], st_fine, cand, loo, q[k]
        )
        ident[k] = vx * vx + vy * vy > 9.0 * (sp * sp)


class OffsetInputs(NamedTuple):
    """The reports and the smoothed track that the offsets are scored against (``N`` rows,
    one vessel's or many vessels'):

    ``xy`` (N, 2) reported positions (m); ``state`` (N, >= 4) smoothed states at the logged
    times (m, m/s; NaN = none); ``sig`` (N, 2) report noise ``(sigma_pos m, sigma_time s)``
    of the run that made the track (:func:`position_noise`); ``used_offset`` (N,) offsets
    (s) of that run; ``usable`` (N,) bool, the reports to score (used by that run)."""

    xy: FloatArray
    state: FloatArray
    sig: FloatArray
    used_offset: FloatArray
    usable: NDArray[np.bool_]


def timestamp_offsets(
    inputs: OffsetInputs,
    pos_cov: FloatArray,
    config: AisTrackerConfig,
    leave_one_out: bool = True,
) -> FloatArray:
    """Most probable whole-second timestamp error of each report, given a smoothed track.

    The logged time of an AIS report is often off by whole seconds (on the Danish files
    ~20 % of the reports by one second and ~2 % by two, against precise positions): a
    report stamped ``d`` seconds late shows the position at ``t - d``, ``p(t) - v d``.

    Each candidate ``d`` in ``-max_time_offset_s .. max_time_offset_s`` scores

    ``0.5 r_d^T C^-1 r_d - log pi_d``,  ``r_d = e + v (d - used_offset)``,
    ``C = M + sigma_pos^2 I + sigma_time_fine_s^2 v v^T``

    where ``e`` is the report's residual (under the offset ``used_offset`` of the run that
    made the track) and ``M`` its prediction covariance. With ``leave_one_out`` (default)
    these are against the track of all *other* reports -- the smoothed track has used the
    report, which pulls it towards a glitch. With ``A`` the smoothed position covariance,
    ``R`` the report's noise covariance in that run (``sig``, the velocity ``v``) and ``r``
    the smoothed residual, Gaussian conditioning (``A = M (M + R)^-1 R``) gives

    ``e = B r``,  ``M = B A``,  ``B = (I - A R^-1)^-1``

    (the velocity uncertainty over the offset is neglected). Without it, ``e = r`` and
    ``M = 0``: the smoothed residual, shrunk towards the track, scored as if the track
    were exact -- the refinement pass uses this only for its first estimate, from the
    coarse first track, whose large ``M`` would hide every offset.

    and the smallest score wins (MAP). The prior ``pi`` is estimated from the reports
    themselves (all vessels together): starting from ``pi_0 = 0.6``, it is re-estimated
    from the counts of the winning offsets (plus one each) over the reports on which the
    offset is identifiable (``|v| * 1 s > 3 sigma_pos``), three times. Slow vessels keep
    ``d = 0`` through the prior. If the estimated share of non-zero offsets is below
    ``min_offset_share`` the data show no whole-second offsets (noise alone makes a few
    winners) and all offsets are 0; so they are with fewer than 100 identifiable reports.

    Parameters
    ----------
    inputs : the reports and the smoothed track (:class:`OffsetInputs`).
    pos_cov : (N, 2, 2) the position covariance of the smoothed states (m^2).
    config : the tracker's configuration; leave_one_out : bool.

    Returns
    -------
    ndarray (N,)
        Offsets (s, whole numbers; 0 for reports not scored).

    Notes
    -----
    The same computation in three steps, for tables split into vessel groups whose prior
    must be estimated from all groups together (the result is then the same as for one
    table; the counts are integers): :func:`offset_scores` per group,
    :func:`estimate_prior` with a function summing :func:`prior_counts` over the groups,
    :func:`apply_offsets` per group.
    """
    scores = offset_scores(inputs, pos_cov, config, leave_one_out)
    prior = estimate_prior(
        lambda p: prior_counts(scores, p), int(np.count_nonzero(scores.ident)), config
    )
    return apply_offsets(scores, prior, config)


class OffsetScores(NamedTuple):
    """Scores of the candidate offsets of the scored reports: ``rows`` (M,) their indices,
    ``q`` (M, K) ``r_d^T C^-1 r_d`` per candidate ``-k_max..k_max``, ``ident`` (M,) whether
    the offset is identifiable (``|v| * 1 s > 3 sigma_pos``); ``n`` rows in the table."""

    rows: NDArray[np.int64]
    q: FloatArray
    ident: NDArray[np.bool_]
    n: int


def offset_scores(
    inputs: OffsetInputs,
    pos_cov: FloatArray,
    config: AisTrackerConfig,
    leave_one_out: bool = True,
) -> OffsetScores:
    """The scores of :func:`timestamp_offsets` (same parameters) before the prior."""
    cov = (pos_cov[:, 0, 0], pos_cov[:, 0, 1], pos_cov[:, 1, 0], pos_cov[:, 1, 1])
    return _scores(inputs, cov, False, config, leave_one_out)


def std_offset_scores(
    inputs: OffsetInputs,
    std: FloatArray,
    config: AisTrackerConfig,
    leave_one_out: bool = True,
) -> OffsetScores:
    """:func:`offset_scores` with the position covariance given by the kernel's std output
    ``(N, 6)`` (sigma x, sigma y in the first two columns, the x-y covariance in the
    last), without building the ``(N, 2, 2)`` array."""
    cov = (std[:, 0], std[:, NX], std[:, NX], std[:, 1])
    return _scores(inputs, cov, True, config, leave_one_out)


def _scores(
    inputs: OffsetInputs,
    cov: tuple[FloatArray, ...],
    squared: bool,
    config: AisTrackerConfig,
    leave_one_out: bool,
) -> OffsetScores:
    xy, state, sig, used_offset, usable = inputs
    k_max = max(int(config.max_time_offset_s), 0)
    n = xy.shape[0]
    c = np.ascontiguousarray
    c00, c01, c10, c11 = (c(x, dtype=np.float64) for x in cov)
    ok = np.zeros(n, dtype=bool)
    state = c(state, dtype=np.float64)
    if k_max > 0 and n:
        _scorable(state, c00, c01, c10, c11, squared, c(usable, dtype=np.bool_), ok)
    idx = np.flatnonzero(ok)
    cand = np.arange(-k_max, k_max + 1, dtype=np.float64)
    q = np.empty((idx.size, cand.size))
    ident = np.empty(idx.size, dtype=bool)
    if idx.size:
        _score_rows(
            idx,
            c(xy, dtype=np.float64),
            state,
            c00,
            c01,
            c10,
            c11,
            squared,
            c(sig, dtype=np.float64),
            c(used_offset, dtype=np.float64),
            float(config.sigma_time_fine_s),
            cand,
            bool(leave_one_out),
            q,
            ident,
        )
    return OffsetScores(idx, q, ident, n)


@njit(cache=True, nogil=True, parallel=True)
def _argmin_rows(q, log_prior, out):  # pragma: no cover - compiled
    """``argmin(0.5 q - log_prior)`` of every row (the first of equal minima)."""
    for i in prange(q.shape[0]):
        best = 0
        vbest = 0.5 * q[i, 0] - log_prior[0]
        for k in range(1, q.shape[1]):
            vk = 0.5 * q[i, k] - log_prior[k]
            if vk < vbest:
                best, vbest = k, vk
        out[i] = best


def _winners(scores: OffsetScores, prior: FloatArray) -> NDArray[np.int64]:
    """Index of the MAP candidate of every scored report."""
    out = np.empty(scores.q.shape[0], dtype=np.int64)
    if out.size:
        _argmin_rows(scores.q, np.log(prior), out)
    return out


def prior_counts(scores: OffsetScores, prior: FloatArray) -> NDArray[np.int64]:
    """Counts of the MAP candidates under ``prior`` over the identifiable reports."""
    return np.bincount(_winners(scores, prior)[scores.ident], minlength=prior.size)


def estimate_prior(
    counts: Callable[[FloatArray], NDArray[np.int64]], n_ident: int, config: AisTrackerConfig
) -> FloatArray | None:
    """Prior of the offsets for :func:`apply_offsets`, or None where the data show no
    offsets (fewer than ``MIN_OFFSET_REPORTS`` identifiable reports, or an estimated
    share of non-zero offsets below ``min_offset_share``).

    ``counts(prior)`` returns the MAP counts under ``prior`` over all identifiable reports
    (:func:`prior_counts`, summed over vessel groups); ``n_ident`` is their number. From
    ``pi_0 = 0.6``, the prior is re-estimated from the counts (plus one each) three times;
    the offsets are the winners under the prior of the third round, and the share test
    uses the prior after it.
    """
    k_max = int(config.max_time_offset_s)
    if k_max <= 0 or n_ident < MIN_OFFSET_REPORTS:
        return None  # too few reports on which an offset shows to estimate its prior
    size = 2 * k_max + 1
    cand = np.arange(-k_max, k_max + 1)
    prior = np.where(cand == 0, 0.6, 0.4 / (size - 1))
    used = prior
    for _ in range(3):
        used = prior
        count = counts(used) + 1.0
        prior = count / count.sum()
    if 1.0 - prior[k_max] < config.min_offset_share:
        return None  # too few offsets to tell from noise: the data show none
    return np.asarray(used, dtype=np.float64)


def apply_offsets(
    scores: OffsetScores, prior: FloatArray | None, config: AisTrackerConfig
) -> FloatArray:
    """Offsets (s) of every row: the MAP candidate of the scored reports under ``prior``
    (:func:`estimate_prior`; None = no offsets), 0 elsewhere."""
    out = np.zeros(scores.n)
    if prior is None or scores.rows.size == 0:
        return out
    k_max = int(config.max_time_offset_s)
    cand = np.arange(-k_max, k_max + 1, dtype=np.float64)
    out[scores.rows] = cand[_winners(scores, prior)]
    return out
