"""Solve a group of TMA problems of equal state size as one batch: start, refine, finalise.

A problem is ``(bearings, support, leg starts, initial)``; ``initial = None`` asks for the
automatic start (:mod:`seatrack.tma.start`). Iteration accounting (RESULT.json
``iterations`` / ``iterations_total``): a problem started from a given value counts the LM
trials of the refinement; one started automatically adds the trials spent on the chosen
start (``iterations``) or on all starts (``iterations_total``). Callers that chose the
initial value by an earlier search (leg detection) pass those counts in ``prior``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.tma.config import TMAConfig
from seatrack.tma.lm import levenberg_marquardt
from seatrack.tma.problem import Bearings
from seatrack.tma.problem import Problem
from seatrack.tma.result import Fit
from seatrack.tma.result import TMASolution
from seatrack.tma.result import finalise
from seatrack.tma.start import auto_start
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = ["Item", "solve_group"]


@dataclass(frozen=True)
class Item:
    """One problem of a group.

    Attributes
    ----------
    bearings, support : the data.
    starts : (L,) leg start times, s.
    initial : (n,) start value, or None for the automatic start.
    prior_iterations, prior_total : LM trials already spent on reaching ``initial`` (on the
        chosen path, and in all) -- added to the solution's counts.
    detected : the leg start times were found from the data.
    """

    bearings: Bearings
    support: Sequence[SupportValue]
    starts: FloatArray
    initial: FloatArray | None = None
    prior_iterations: int = 0
    prior_total: int = 0
    detected: bool = False


def _real_rows(stacked: Problem, p: Problem) -> NDArray[np.int64] | slice:
    """Rows of ``p`` in the padded batch ``stacked`` (blocks bearings, support, frequency,
    ATB): a slice when ``p`` has bearings only, else their indices."""
    if not (p.sk.shape[-1] or p.fz.shape[-1] or p.az.shape[-1]):
        return slice(0, p.z.shape[-1])
    out, off = [], 0
    for name in ("z", "sk", "fz", "az"):
        out.append(off + np.arange(getattr(p, name).shape[-1]))
        off += getattr(stacked, name).shape[-1]
    return np.concatenate(out).astype(np.int64)


def solve_group(items: Sequence[Item], cfg: TMAConfig, sigma: float) -> list[TMASolution]:
    """Solve problems with equal state size together (``sigma``: default bearing sigma, rad)."""
    n = 2 + 2 * items[0].starts.size
    square = cfg.support_residual == "square"
    beta0 = np.zeros((len(items), n))
    its = np.array([it.prior_iterations for it in items], dtype=np.int64)
    tot = np.array([it.prior_total for it in items], dtype=np.int64)
    need = [i for i, it in enumerate(items) if it.initial is None]
    for i, it in enumerate(items):
        if it.initial is not None:
            beta0[i] = it.initial
    if need:
        found = auto_start(
            [(items[i].bearings, items[i].support, items[i].starts) for i in need], cfg, sigma
        )
        beta0[need] = found.beta
        its[need] += found.iterations
        tot[need] += found.iterations_total
    probs = [
        Problem.build(it.bearings, it.support, it.starts, sigma, square, None, cfg.sound_speed)
        for it in items
    ]
    stacked = Problem.stack(probs)
    res = levenberg_marquardt(stacked, beta0, cfg, cfg.max_iterations)
    W = stacked.weights
    out = []
    for i, it in enumerate(items):
        keep = _real_rows(stacked, probs[i])
        # a copy of the residuals (the solution keeps them; the batch is not kept alive)
        r, J, f0 = np.array(res.r[i][keep]), res.J[i][keep], np.zeros(0)
        if probs[i].fz.size:  # joint Jacobian of the state and the base frequencies
            f0, J = probs[i].augmented(res.beta[i])
        fit = Fit(
            res.beta[i], float(res.cost[i]), r, J, W[i][keep],
            int(its[i] + res.iterations[i]), int(tot[i] + res.iterations[i]),
            bool(res.converged[i]), f0,
        )  # fmt: skip
        out.append(finalise(it.bearings, it.support, it.starts, fit, cfg, it.detected))
    return out
