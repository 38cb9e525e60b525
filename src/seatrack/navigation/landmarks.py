"""Landmark map: point reflectors and contour elements, numbered along the channel.

Spec ``landmark_nav.md``, "Inputs and state" and "Map preparation". A map is an ordered
list (the order number is the position along the channel, used by the active window) of

* **point reflectors** (pylons, chimneys): a position ``(X_R, Y_R)``;
* **contour elements** (bank or quay edges): a reference point plus ``orientation``, the
  direction of the contour line itself, clockwise from North, in ``[0, pi)``. Its normal
  ``beta = orientation + pi/2`` is what the measurement uses.

File formats (CSV and the binary records) are in :mod:`seatrack.io.landmarks`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

__all__ = ["LandmarkMap"]


@dataclass(frozen=True)
class LandmarkMap:
    """Landmarks in channel order.

    Attributes
    ----------
    ids : (N,) str
    is_contour : (N,) bool
        False for point reflectors, True for contour elements.
    xy : (N, 2) m
        East, North of the reflector / the contour reference point.
    orientation : (N,) rad
        Direction of the contour line, clockwise from North, in ``[0, pi)``
        (0 for point reflectors).
    """

    ids: NDArray[np.str_]
    is_contour: NDArray[np.bool_]
    xy: FloatArray
    orientation: FloatArray

    def __post_init__(self) -> None:
        n = len(self.ids)
        if (
            self.xy.shape != (n, 2)
            or self.is_contour.shape != (n,)
            or self.orientation.shape != (n,)
        ):
            raise ValueError("LandmarkMap arrays must have matching lengths (xy of shape (N, 2))")
        if len(set(self.ids.tolist())) != n:
            raise ValueError("LandmarkMap ids must be unique")

    @classmethod
    def from_arrays(
        cls,
        xy: ArrayLike,
        is_contour: ArrayLike | None = None,
        orientation: ArrayLike | None = None,
        ids: Sequence[str] | None = None,
    ) -> LandmarkMap:
        """Build a map; ``orientation`` (rad) is wrapped to ``[0, pi)``."""
        p = np.asarray(xy, dtype=float).reshape(-1, 2)
        n = p.shape[0]
        c = np.zeros(n, bool) if is_contour is None else np.asarray(is_contour, bool)
        o = np.zeros(n) if orientation is None else np.asarray(orientation, float)
        o = np.where(c, np.mod(o, np.pi), 0.0)
        i = np.array([str(k) for k in range(n)] if ids is None else list(ids), dtype=str)
        return cls(i, c, p, o)

    def __len__(self) -> int:
        return int(self.ids.size)

    @property
    def normal(self) -> FloatArray:
        """Normal direction ``beta = orientation + pi/2`` (rad) of each contour element."""
        return self.orientation + 0.5 * np.pi

    def with_xy(self, xy: ArrayLike) -> LandmarkMap:
        """Same landmarks with new positions (used by the survey and the simulator)."""
        return LandmarkMap(
            self.ids, self.is_contour, np.asarray(xy, float).reshape(-1, 2), self.orientation
        )

    def subset(self, keep: ArrayLike) -> LandmarkMap:
        """Landmarks where ``keep`` is true (channel order kept)."""
        k = np.asarray(keep)
        return LandmarkMap(self.ids[k], self.is_contour[k], self.xy[k], self.orientation[k])
