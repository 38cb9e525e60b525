"""Track existence: the probability that a track follows a real target (track quality).

Every track carries the log-odds ``s = log(r / (1 - r))`` of its existence probability
``r`` -- the integrated PDA of Musicki, Evans & Stankovic (1994), in the joint form of
Musicki & Evans (JIPDA, 2004) -- updated from the same likelihood ratios the association
uses, so that confirmation adapts to the clutter density and deletion to the detection
probability:

* **survival** between scans: ``r <- p_s r``, ``p_s = exp(-dt / mean_life)``;
* **a scan with the track's plot(s)** (IPDA): ``odds <- odds (1 - Pd Pg + sum_j Pd g_j /
  lambda)`` over the plots associated with the track (GNN: the assigned one; none: a miss,
  ``odds <- odds (1 - Pd Pg)``), ``g_j`` the innovation density and ``lambda`` the clutter
  density in the same measurement space;
* **JIPDA** with the joint association probabilities ``beta_ij`` (which weigh each track's
  detection by ``r Pd``): ``r <- sum_j beta_ij + beta_i0 r (1 - Pd Pg) / (1 - r Pd Pg)``;
* **birth**: a plot no track explains is a target not detected before with prior odds
  ``Pd D_u / n_c`` -- ``D_u`` the expected number of undetected targets, ``n_c`` the
  expected clutter plots per scan (both uniform over the surveillance region, as in the
  Poisson part of a PMBM filter; Williams 2015); ``D_u <- p_s (1 - Pd) D_u + n_b`` per
  scan, ``n_b`` the expected new targets per scan. Before the first scan nothing is known:
  the share ``f`` of the first scan's plots that are targets is estimated at the second
  scan by expectation-maximisation over the pairs they formed (:func:`first_scan_share`),
  which sets their prior odds ``f / (1 - f)`` and ``D_u = f N_1 / Pd``.

A track is reported (confirmed) while ``r`` is at least the confirmation threshold and
deleted when ``r`` falls below the deletion threshold. With ``c`` the GOSPA cut-off, a
track of existence ``r`` and position error ``d`` costs ``r d^2 + (1 - r) c^2/2`` when
reported and ``r c^2/2`` when not: reporting pays when ``r > 1/2`` for accurate tracks --
the expected-GOSPA-optimal report (Garcia-Fernandez et al. 2020) that the confirmation
threshold approximates.

All functions work on arrays of log-odds and never form ``1 - r`` by subtraction.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray
from scipy.special import expit

FloatArray = NDArray[np.float64]

__all__ = [
    "logit",
    "probability",
    "survive",
    "ipda_update",
    "jipda_update",
    "UndetectedTargets",
    "first_scan_share",
]


def logit(r: ArrayLike) -> FloatArray:
    """``log(r / (1 - r))`` (``r`` in [0, 1]; 0 and 1 give -inf and inf)."""
    rr = np.asarray(r, dtype=float)
    with np.errstate(divide="ignore"):
        return np.asarray(np.log(rr) - np.log1p(-rr))


def probability(s: ArrayLike) -> FloatArray:
    """Existence probability from log-odds ``s`` (the logistic function)."""
    return np.asarray(expit(np.asarray(s, dtype=float)))


def _log_sigmoid(s: FloatArray) -> FloatArray:
    """``log(1 / (1 + exp(-s)))`` without overflow."""
    return np.asarray(-np.logaddexp(0.0, -s))


def survive(s: ArrayLike, log_ps: ArrayLike) -> FloatArray:
    """Log-odds after survival ``r <- p_s r`` (``log_ps = log p_s <= 0``, per track or one).

    ``logit(p_s r) = log p_s + log r - log(1 - p_s r)``, with
    ``1 - p_s r = (1 - r) + (1 - p_s) r``.
    """
    ss = np.asarray(s, dtype=float)
    lp = np.asarray(log_ps, dtype=float)
    log_r = _log_sigmoid(ss)
    log_1mr = _log_sigmoid(-ss)
    with np.errstate(divide="ignore"):
        log_1mps = np.log(-np.expm1(np.minimum(lp, 0.0)))
    return np.asarray(lp + log_r - np.logaddexp(log_1mr, log_1mps + log_r))


def ipda_update(s: ArrayLike, log_miss: float, log_lr: ArrayLike) -> FloatArray:
    """IPDA existence update with the plots associated with each track.

    Parameters
    ----------
    s : (B,) predicted log-odds
    log_miss : ``log(1 - Pd Pg)``
    log_lr : (B,) ``log(sum_j Pd g_j / lambda)`` over each track's plots; ``-inf`` for a
        track without plot (a miss)
    """
    return np.asarray(np.asarray(s, dtype=float) + np.logaddexp(log_miss, log_lr))


def jipda_update(
    s: ArrayLike, log_pdpg: float, beta_plot: ArrayLike, beta0: ArrayLike
) -> FloatArray:
    """JIPDA existence update from the joint association probabilities.

    Parameters
    ----------
    s : (B,) predicted log-odds
    log_pdpg : ``log(Pd Pg)``
    beta_plot : (B,) ``sum_j beta_ij``: probability that one of the plots is the track's
    beta0 : (B,) ``beta_i0`` (the two add up to one)

    ``1 - r+ = beta0 (1 - r) / (1 - r Pd Pg)``, ``r+ = sum_j beta_ij + beta0 r (1 - Pd Pg) /
    (1 - r Pd Pg)``; both parts are formed in log space.
    """
    ss = np.asarray(s, dtype=float)
    b = np.asarray(beta_plot, dtype=float)
    b0 = np.asarray(beta0, dtype=float)
    log_r, log_1mr = _log_sigmoid(ss), _log_sigmoid(-ss)
    # 1 - r Pd Pg = (1 - r) + r (1 - Pd Pg)
    log_1mpg = math.log(-math.expm1(log_pdpg)) if log_pdpg < 0 else -math.inf
    log_den = np.logaddexp(log_1mr, log_r + log_1mpg)
    with np.errstate(divide="ignore"):
        log_b, log_b0 = np.log(b), np.log(b0)
    log_dead = log_b0 + log_1mr - log_den
    log_alive = np.logaddexp(log_b, log_b0 + log_r + log_1mpg - log_den)
    return np.asarray(log_alive - log_dead)


def first_scan_share(log_lr: ArrayLike, n_plots: int, pd: float, iters: int = 200) -> float:
    """Share ``f`` of the first scan's ``n_plots`` plots that are targets (EM estimate).

    Each plot is a target with prior ``f`` or clutter. A plot that started a pair at the
    second scan brings the log likelihood ratio ``log_lr`` (target against clutter) of
    that pair; a plot without a pair ``log(1 - Pd)`` (its target was not detected again).
    The EM step for a mixing share -- ``f`` <- the mean posterior -- is iterated to its
    fixed point from ``f = 1/2``.
    """
    lr = np.asarray(log_lr, dtype=float)
    n_none = max(n_plots - lr.size, 0)
    if n_plots <= 0:
        return 0.5
    f = 0.5
    miss = math.log1p(-min(pd, 1.0 - 1e-12))
    for _ in range(iters):
        lo = math.log(f) - math.log1p(-f)
        post = float(expit(lo + lr).sum()) + n_none * float(expit(lo + miss))
        new = min(max(post / n_plots, 1e-6), 1.0 - 1e-6)
        if abs(new - f) < 1e-9:
            return new
        f = new
    return f


class UndetectedTargets:
    """Expected number ``D_u`` of targets in the region not yet detected: the prior of a
    new track (see the module docstring).

    Parameters
    ----------
    births_per_scan : expected new targets per scan over the region (``n_b``)
    """

    def __init__(self, births_per_scan: float) -> None:
        self.births = float(births_per_scan)
        self.expected: float | None = None  # D_u; None before the first scan
        self.first_plots = 0  # plots of the first scan
        self.first_share: float | None = None  # share of them that are targets (estimated)

    def log_prior_odds(self, pd: float, clutter_per_scan: float, n_plots: int) -> float:
        """Log prior odds ``log(Pd D_u / n_c)`` of a plot of this scan being a new target.

        At the first scan nothing is known: its plots have prior odds 1 (``D_u`` = half of
        them over ``Pd``) until :meth:`first_scan` sets their share.
        """
        if self.expected is None:
            self.expected = 0.5 * n_plots / pd
            self.first_plots = n_plots
            return 0.0
        return math.log(max(pd * self.expected, 1e-300)) - math.log(max(clutter_per_scan, 1e-300))

    def first_scan(self, share: float, pd: float, survival: float) -> float:
        """The first scan's target share is now known (one scan later): ``D_u`` follows;
        returns the log prior odds of the first scan's plots."""
        self.first_share = share
        self.expected = survival * (1.0 - pd) * share * self.first_plots / pd + self.births
        return math.log(share) - math.log1p(-share)

    def advance(self, pd: float, survival: float) -> None:
        """One scan later: the undetected survive and stay undetected, new ones are born."""
        if self.expected is not None:
            self.expected = survival * (1.0 - pd) * self.expected + self.births
