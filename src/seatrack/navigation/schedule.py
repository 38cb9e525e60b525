"""Landmark scheduling: one echo trap, one landmark at a time, JUMP counters.

Spec ``landmark_nav.md``, "Scheduling". After a landmark is processed the bearings of the
others are computed; the next one is the first the antenna will reach (smallest bearing
gap in the direction of rotation, clockwise) that leaves time to prepare the echo trap.

Landmarks nearly in line (gap smaller than the gate width plus the preparation margin,
e.g. 11 deg) cannot both be served on one revolution. The patent's per-landmark JUMP
counter (0..3) handles them: when the nearest follower ``c`` of the just-processed
landmark ``j`` is too close, ``JUMP[j] += 1`` and ``JUMP[c] -= 1`` (if positive); the next
landmark is then chosen in increasing gap among those at least ``min_gap`` away. A landmark
with a positive counter is skipped (and its counter decremented) when the antenna passes
it, so two landmarks in line are served on alternate revolutions.

Worked example from the patent (boat at B1, FIRST = 7): the landmark of index 1 (R8) has
just been processed at 110 deg; index 0 (R7) is at 115 deg, a gap of 5 deg < 11 deg, so
JUMP1 = 1 and the next landmark is index 3 (R10), 75 deg > 11 deg further on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import TWO_PI

__all__ = ["ScheduleConfig", "Choice", "next_landmark"]


@dataclass(frozen=True)
class ScheduleConfig:
    """Scheduler parameters.

    Attributes
    ----------
    min_gap : rad
        Gate width plus preparation margin (spec example 11 deg): followers closer than this
        to the processed landmark cannot be served on the same revolution.
    start_margin : rad
        Gate half-width plus safety margin added to the antenna bearing when nothing has
        been processed yet (the patent's ``s``).
    max_jump : int
        Largest JUMP counter value (3 in the patent).
    """

    min_gap: float = float(np.radians(11.0))
    start_margin: float = float(np.radians(11.0))
    max_jump: int = 3


@dataclass(frozen=True)
class Choice:
    """Scheduler decision.

    Attributes
    ----------
    index : int
        Position (in the arrays passed in) of the next landmark, or -1 if none is eligible.
    gap : float
        Antenna rotation (rad, >= 0, may exceed 2 pi when a revolution is skipped) from the
        reference bearing to the next landmark's bearing.
    jump : (N,) int
        Updated JUMP counters.
    """

    index: int
    gap: float
    jump: NDArray[np.int64]


def next_landmark(
    bearings: ArrayLike,
    eligible: ArrayLike,
    jump: ArrayLike,
    processed: int | None = None,
    antenna_bearing: float = 0.0,
    config: ScheduleConfig | None = None,
) -> Choice:
    """Choose the next landmark to serve (spec "Scheduling").

    Parameters
    ----------
    bearings : (N,) rad
        Predicted true bearings (clockwise from North) of the landmarks.
    eligible : (N,) bool
        Landmarks that may be chosen (in the active window and in range).
    jump : (N,) int
        JUMP counters (not modified; the updated copy is returned).
    processed : int, optional
        Index of the landmark just processed; its bearing is the reference. If None,
        the reference is ``antenna_bearing + config.start_margin`` and no gap is enforced.
    antenna_bearing : rad
        Current true bearing of the antenna (used only when ``processed`` is None).
    config : ScheduleConfig

    Returns
    -------
    Choice
    """
    cfg = config or ScheduleConfig()
    th = np.asarray(bearings, float)
    ok = np.asarray(eligible, bool).copy()
    jp = np.array(jump, dtype=np.int64)
    if processed is None:
        ref = antenna_bearing + cfg.start_margin
        min_gap = 0.0
    else:
        ref = float(th[processed])
        min_gap = cfg.min_gap
        ok[processed] = False
    idx = np.flatnonzero(ok)
    gaps = np.mod(th[idx] - ref, TWO_PI)
    # candidates over two revolutions (the processed landmark itself one turn later)
    cand_i = np.concatenate([idx, idx])
    cand_g = np.concatenate([gaps, gaps + TWO_PI])
    if processed is not None and bool(np.asarray(eligible, bool)[processed]):
        cand_i = np.append(cand_i, processed)
        cand_g = np.append(cand_g, TWO_PI)
    if cand_i.size == 0:
        return Choice(-1, 0.0, jp)
    order = np.argsort(cand_g, kind="stable")
    cand_i, cand_g = cand_i[order], cand_g[order]
    if processed is not None and idx.size:
        c = int(idx[np.argmin(gaps)])
        if gaps.min() < min_gap:
            jp[processed] = min(jp[processed] + 1, cfg.max_jump)
            if jp[c] > 0:
                jp[c] -= 1
    for i, g in zip(cand_i.tolist(), cand_g.tolist(), strict=True):
        if g < min_gap:
            continue
        if jp[i] > 0:
            jp[i] -= 1  # skipped on this pass of the antenna
            continue
        return Choice(int(i), float(g), jp)
    # every candidate is jumped: take the first far enough, ignoring the counters
    far = cand_g >= min_gap
    if not far.any():
        return Choice(-1, 0.0, jp)
    k = int(np.argmax(far))
    return Choice(int(cand_i[k]), float(cand_g[k]), jp)
