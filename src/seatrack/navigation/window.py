"""Active window of the landmark list: the contiguous slice [FIRST, FIRST + NBR].

Spec ``landmark_nav.md``, "Active window". Landmarks are numbered along the channel and
only the slice ``FIRST .. FIRST + NBR`` (inclusive, so NBR is the number of landmarks
minus one) is used. When the processor has time the window is revised one step at each
end:

* lower end: if FIRST is within radar range, test FIRST - 1 and extend down if it is too;
  if FIRST is out of range, FIRST += 1;
* upper end: if the last (FIRST + NBR) is in range, test the next and extend NBR if it is
  too; if the last is out of range, NBR -= 1.

[reading] the upper end stays fixed when FIRST moves (NBR changes by the opposite amount),
as in the patent's example (boat at B1: FIRST = 7, NBR = 5; at B2: FIRST = 5, NBR = 5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

__all__ = ["Window", "in_range", "step_window", "settle_window"]


@dataclass(frozen=True)
class Window:
    """Active window: ``first`` (order number) and ``nbr`` (number of landmarks - 1).

    ``nbr = -1`` means an empty window (nothing in range).
    """

    first: int
    nbr: int

    @property
    def last(self) -> int:
        """Order number of the last landmark in the window."""
        return self.first + self.nbr

    def indices(self) -> NDArray[np.int64]:
        """Order numbers in the window (empty if ``nbr < 0``)."""
        return np.arange(self.first, self.first + self.nbr + 1)

    def index_of(self, number: int) -> int:
        """Window index of landmark ``number`` (the patent's index: FIRST + index = number)."""
        return number - self.first


def in_range(xy: ArrayLike, position: ArrayLike, range_limit: float) -> NDArray[np.bool_]:
    """Which landmarks (rows of ``xy``, m) lie within ``range_limit`` (m) of ``position``."""
    d = np.asarray(xy, float) - np.asarray(position, float)[:2]
    return np.asarray(np.hypot(d[:, 0], d[:, 1]) <= range_limit)


def step_window(w: Window, visible: ArrayLike) -> Window:
    """One revision of both ends of the window (spec "Active window").

    Parameters
    ----------
    w : current window.
    visible : (N,) bool
        Whether each landmark of the whole list is within radar range ("appropriate").

    Returns
    -------
    Window
        The revised window. An empty window (``nbr < 0``) is re-seeded on the first
        visible landmark at or after ``first`` (or before it, if none follows).
    """
    v = np.asarray(visible, bool)
    n = v.size
    if n == 0:
        return Window(0, -1)
    first, last = w.first, w.last
    if w.nbr < 0 or not (0 <= first < n):
        idx = np.flatnonzero(v)
        if idx.size == 0:
            return Window(min(max(first, 0), n - 1), -1)
        after = idx[idx >= first]
        k = int(after[0] if after.size else idx[-1])
        return Window(k, 0)
    # lower end
    if v[first]:
        if first - 1 >= 0 and v[first - 1]:
            first -= 1
    else:
        first += 1
    # upper end (independent of the lower end: [reading] upper end fixed when FIRST moves)
    if last < n and v[last]:
        if last + 1 < n and v[last + 1]:
            last += 1
    else:
        last -= 1
    return Window(first, max(last - first, -1))


def settle_window(w: Window, visible: ArrayLike, max_steps: int = 1000) -> Window:
    """Repeat :func:`step_window` until the window no longer changes."""
    for _ in range(max_steps):
        nw = step_window(w, visible)
        if nw == w:
            return w
        w = nw
    return w
