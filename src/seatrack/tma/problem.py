"""The TMA least-squares problem: bearings, residuals, Jacobians, batches of problems.

Spec: ``docs/tma.md`` (DE 3446658). The target moves with constant velocity on one or more
legs; the state ``beta = (X0, Y0, Vx0, Vy0, Vx1, Vy1, ...)`` is its position at the
reference time ``t0`` (the first bearing) and one velocity per leg (see
:mod:`seatrack.tma.legs`). A :class:`Problem` holds the arrays of one problem or of a padded
batch of problems (contacts x starts), so the solver evaluates residuals and Jacobians of a
whole batch in numpy; padded rows carry zero weight.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.models.measurement import bearing_jacobian
from seatrack.tma.legs import leg_time_matrix
from seatrack.tma.support import SupportValue
from seatrack.tma.support import support_residuals
from seatrack.tma.support import support_rows

FloatArray = NDArray[np.float64]

__all__ = ["Bearings", "Problem", "bearing_residuals"]


@dataclass(frozen=True)
class Bearings:
    """Bearings of one contact (SI units, radians).

    Parameters
    ----------
    t : (N,) s, strictly increasing.
    bearing : (N,) rad, true bearing clockwise from North (any wrap).
    observer : (N, 2) m, observer position (East, North) at each bearing.
    sigma : (N,) rad, optional per-bearing standard deviation (else the solver's ``sigma``).
    """

    t: FloatArray
    bearing: FloatArray
    observer: FloatArray
    sigma: FloatArray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).reshape(-1)
        b = np.asarray(self.bearing, dtype=float).reshape(-1)
        o = np.asarray(self.observer, dtype=float)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "bearing", b)
        if o.ndim != 2 or o.shape[1] < 2 or o.shape[0] != t.size:
            raise ValueError(f"observer must have shape (N, 2) with N = {t.size}, got {o.shape}")
        object.__setattr__(self, "observer", o[:, :2])
        if b.size != t.size:
            raise ValueError(f"{b.size} bearings for {t.size} times")
        if t.size < 2:
            raise ValueError(f"TMA needs at least 2 bearings, got {t.size}")
        for name, a in (("t", t), ("bearing", b), ("observer", o[:, :2])):
            bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(t.size, -1)), axis=1))
            if bad.size:
                raise ValueError(f"{name} is not finite at index {bad[0]}")
        dt = np.diff(t)
        if np.any(dt <= 0):
            i = int(np.flatnonzero(dt <= 0)[0]) + 1
            raise ValueError(
                f"times must be strictly increasing; index {i}: {t[i]:g} after {t[i - 1]:g}"
            )
        if self.sigma is not None:
            s = np.broadcast_to(np.asarray(self.sigma, dtype=float), t.shape).copy()
            if not np.all(np.isfinite(s) & (s > 0)):
                raise ValueError("bearing sigma must be finite and positive")
            object.__setattr__(self, "sigma", s)

    def __len__(self) -> int:
        return int(self.t.size)


def bearing_residuals(
    beta: ArrayLike, C: ArrayLike, observer: ArrayLike, z: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Bearing residuals ``wrap(z - h(beta))`` and Jacobian ``dh/dbeta`` (spec step 2).

    Parameters
    ----------
    beta : (..., n) states ``(X0, Y0, Vx0, Vy0, ...)``.
    C : (..., N, n/2) coefficient rows ``(1, T'_i0, T'_i1, ...)`` (:func:`leg_time_matrix`).
    observer : (..., N, 2) observer positions, m.
    z : (..., N) measured bearings, rad.

    Returns
    -------
    r : (..., N) rad in ``(-pi, pi]``.
    J : (..., N, n) rad per state unit; one leg: ``[R_y, -R_x, T R_y, -T R_x] / R^2``.
    """
    b = np.asarray(beta, dtype=float)
    CC = np.asarray(C, dtype=float)
    B = b.reshape(b.shape[:-1] + (-1, 2))
    d = CC @ B - np.asarray(observer, dtype=float)
    r = wrap_pi(np.asarray(z, dtype=float) - bearing(d[..., 0], d[..., 1]))
    g = bearing_jacobian(d)
    J = np.empty(d.shape[:-1] + (b.shape[-1],))
    for k in range(CC.shape[-1]):  # columns (2k, 2k + 1) = T'_ik * d(bearing)/d(position)
        J[..., 2 * k : 2 * k + 2] = CC[..., k, None] * g
    return np.asarray(r, dtype=float), J


@dataclass(frozen=True)
class Problem:
    """Arrays of one (or a padded batch of) least-squares problem(s).

    Leading dimension ``K`` (batch) is optional; bearing arrays ``(K, N, ...)``, support
    arrays ``(K, M, ...)``; padded rows have zero weight.

    Attributes
    ----------
    C : (K, N, 1 + L) coefficient rows of the bearings; obs : (K, N, 2) m; z : (K, N) rad;
    wb : (K, N) bearing weights ``1/sigma^2``; sk, sA, soff, sval, sw : support rows
    (:class:`~seatrack.tma.support.SupportRows`); square : squared support residuals;
    c_last : (K, 1 + L) coefficient row of the last bearing time (convergence test).
    """

    C: FloatArray
    obs: FloatArray
    z: FloatArray
    wb: FloatArray
    sk: NDArray[np.int64]
    sA: FloatArray
    soff: FloatArray
    sval: FloatArray
    sw: FloatArray
    square: bool
    c_last: FloatArray

    @staticmethod
    def build(
        bearings: Bearings,
        support: Sequence[SupportValue],
        starts: FloatArray,
        sigma: float,
        square: bool = False,
        index: NDArray[np.int64] | None = None,
    ) -> Problem:
        """Unbatched problem for one contact.

        ``sigma`` (rad) applies where ``bearings.sigma`` is None; ``index`` selects bearings
        (the start search uses a subset); ``square`` selects the patent's squared support
        residuals.
        """
        sig = bearings.sigma if bearings.sigma is not None else np.full(len(bearings), sigma)
        t, z, obs = bearings.t, bearings.bearing, bearings.observer
        if index is not None:
            t, z, obs, sig = t[index], z[index], obs[index], sig[index]
        rows = support_rows(support, starts, square)
        return Problem(
            leg_time_matrix(t, starts), np.asarray(obs, dtype=float), np.asarray(z, dtype=float),
            1.0 / sig**2, rows.kind, rows.A, rows.offset, rows.value, rows.weight, rows.square,
            leg_time_matrix(bearings.t[-1:], starts)[0],
        )  # fmt: skip

    @staticmethod
    def stack(problems: Sequence[Problem]) -> Problem:
        """Pad and stack unbatched problems of equal state size into a batch."""
        N = max(p.z.size for p in problems)
        M = max(p.sk.size for p in problems)

        def padb(a: NDArray[Any], n: int, zero: bool) -> NDArray[Any]:
            if a.shape[0] == n:
                return a
            if zero or a.shape[0] == 0:
                fill = np.zeros((n - a.shape[0],) + a.shape[1:], a.dtype)
            else:  # repeat the last real row (finite geometry), weight set to zero
                fill = np.repeat(a[-1:], n - a.shape[0], axis=0)
            return np.concatenate([a, fill], axis=0)

        def col(name: str, n: int, zero: bool) -> NDArray[Any]:
            return np.stack([padb(getattr(p, name), n, zero) for p in problems])

        return Problem(
            col("C", N, False), col("obs", N, False), col("z", N, False), col("wb", N, True),
            col("sk", M, True), col("sA", M, True), col("soff", M, True), col("sval", M, True),
            col("sw", M, True), problems[0].square, np.stack([p.c_last for p in problems]),
        )  # fmt: skip

    def repeat(self, k: int) -> Problem:
        """Each batch entry repeated ``k`` times (for multi-start), batch ``K * k``."""

        def rep(a: NDArray[Any]) -> NDArray[Any]:
            return np.repeat(a, k, axis=0)

        return Problem(
            rep(self.C), rep(self.obs), rep(self.z), rep(self.wb), rep(self.sk), rep(self.sA),
            rep(self.soff), rep(self.sval), rep(self.sw), self.square, rep(self.c_last),
        )  # fmt: skip

    @property
    def weights(self) -> FloatArray:
        """Row weights ``(..., N + M)``: bearings, then support values."""
        return np.concatenate([self.wb, self.sw], axis=-1)

    def evaluate(self, beta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Stacked residuals ``(..., N + M)`` and Jacobian ``(..., N + M, n)``."""
        b = np.asarray(beta, dtype=float)
        r, J = bearing_residuals(b, self.C, self.obs, self.z)
        if self.sk.shape[-1] == 0:
            return r, J
        B = b.reshape(b.shape[:-1] + (-1, 2))
        rs, Js = support_residuals(B, self.sk, self.sA, self.soff, self.sval, self.square)
        return np.concatenate([r, rs], -1), np.concatenate([J, Js], -2)
