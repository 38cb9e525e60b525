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
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.models.measurement import bearing_jacobian
from seatrack.tma.legs import leg_index
from seatrack.tma.legs import leg_time_matrix
from seatrack.tma.measurements import SOUND_SPEED
from seatrack.tma.measurements import BowAngles
from seatrack.tma.measurements import Frequencies
from seatrack.tma.measurements import bow_angle_residuals
from seatrack.tma.measurements import frequency_residuals
from seatrack.tma.support import SupportValue
from seatrack.tma.support import support_residuals
from seatrack.tma.support import support_rows

FloatArray = NDArray[np.float64]

__all__ = ["Bearings", "Problem", "bearing_residuals", "decimate"]


def decimate(n: int, k: int) -> NDArray[np.int64] | None:
    """At most ``k`` evenly spaced indices of ``n`` (first and last kept); None if ``n <= k``."""
    if n <= k:
        return None
    return np.unique(np.round(np.linspace(0, n - 1, k)).astype(np.int64))


@dataclass(frozen=True)
class Bearings:
    """Bearings of one contact (SI units, radians).

    Parameters
    ----------
    t : (N,) s, strictly increasing.
    bearing : (N,) rad, true bearing clockwise from North (any wrap).
    observer : (N, 2) m, observer position (East, North) at each bearing.
    sigma : (N,) rad, optional per-bearing standard deviation (else the solver's ``sigma``).
    frequencies : optional tonal frequencies of the contact
        (:class:`~seatrack.tma.measurements.Frequencies`), none before ``t[0]``.
    bow_angles : optional angles on the bow (:class:`~seatrack.tma.measurements.BowAngles`),
        none before ``t[0]``.
    """

    t: FloatArray
    bearing: FloatArray
    observer: FloatArray
    sigma: FloatArray | None = None
    frequencies: Frequencies | None = None
    bow_angles: BowAngles | None = None

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
        for name, extra in (("frequency", self.frequencies), ("ATB", self.bow_angles)):
            if extra is not None and len(extra) and extra.t.min() < t[0]:
                raise ValueError(
                    f"a {name} measurement at {extra.t.min():g} s is before the first bearing "
                    f"({t[0]:g} s), the reference time of the solution"
                )

    @property
    def n_frequencies(self) -> int:
        """Number of frequency measurements."""
        return 0 if self.frequencies is None else len(self.frequencies)

    @property
    def n_bow_angles(self) -> int:
        """Number of ATB measurements."""
        return 0 if self.bow_angles is None else len(self.bow_angles)

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


def _leg_rows(t: FloatArray, starts: FloatArray) -> FloatArray:
    """One-hot rows ``(N, 1 + L)`` selecting the velocity of the leg each time falls in."""
    E = np.zeros((t.size, starts.size + 1))
    E[np.arange(t.size), 1 + leg_index(t, starts)] = 1.0
    return E


#: Problem fields per measurement axis: bearings (N), support (M), frequencies (F), ATB (A),
#: tonals (T); the others have no row axis. Weights pad with zeros, geometry with its last
#: row (finite, weight zero).
_AXES = {
    "C": "N", "obs": "N", "z": "N", "wb": "N",
    "sk": "M", "sA": "M", "soff": "M", "sval": "M", "sw": "M",
    "fC": "F", "fE": "F", "fobs": "F", "fvel": "F", "fz": "F", "fw": "F", "fO": "F",
    "f0fix": "T",
    "aC": "A", "aE": "A", "aobs": "A", "az": "A", "aw": "A",
}  # fmt: skip
_ZERO_PAD = {"wb", "sk", "sA", "soff", "sval", "sw", "fw", "fO", "aw", "f0fix"}
#: the fields of the frequency (with their tonals) and ATB rows
_FIELDS = {
    "F": ("fC", "fE", "fobs", "fvel", "fz", "fw", "fO", "f0fix"),
    "A": ("aC", "aE", "aobs", "az", "aw"),
}


@lru_cache(maxsize=64)
def _no_rows(L1: int, kind: str) -> dict[str, FloatArray]:
    """The fields of a measurement kind (``"F"`` or ``"A"``) without rows, for ``L1 - 1``
    legs: zero-size arrays (read-only, shared by every problem without that kind)."""
    shapes = {
        "F": [(0, L1), (0, L1), (0, 2), (0, 2), (0,), (0,), (0, 0), (0,)],
        "A": [(0, L1), (0, L1), (0, 2), (0,), (0,)],
    }[kind]
    out = {}
    for name, shape in zip(_FIELDS[kind], shapes, strict=True):
        a = np.zeros(shape)
        a.flags.writeable = False
        out[name] = a
    return out


def _repeat_rows(a: NDArray[Any], k: int) -> NDArray[Any]:
    """Each batch entry of ``a`` repeated ``k`` times (axis 0); a kind without rows
    (axis 1 empty) needs no copy, only the shape."""
    if a.shape[1] == 0:
        return np.empty((a.shape[0] * k,) + a.shape[1:], a.dtype)
    return np.repeat(a, k, axis=0)


@dataclass(frozen=True)
class Problem:
    """Arrays of one (or a padded batch of) least-squares problem(s).

    Leading dimension ``K`` (batch) is optional; bearing arrays ``(K, N, ...)``, support
    arrays ``(K, M, ...)``, frequency arrays ``(K, F, ...)``, ATB arrays ``(K, A, ...)``;
    padded rows have zero weight.

    Attributes
    ----------
    C : (K, N, 1 + L) coefficient rows of the bearings; obs : (K, N, 2) m; z : (K, N) rad;
    wb : (K, N) bearing weights ``1/sigma^2``; sk, sA, soff, sval, sw : support rows
    (:class:`~seatrack.tma.support.SupportRows`); square : squared support residuals;
    c_last : (K, 1 + L) coefficient row of the last bearing time (convergence test);
    fC, fE : (K, F, 1 + L) position / leg-velocity rows of the frequencies; fobs, fvel :
    (K, F, 2) own-ship position (m) and velocity (m/s); fz : (K, F) Hz; fw : (K, F) Hz^-2;
    fO : (K, F, T) tonal membership; f0fix : (K, T) known base frequency (Hz), NaN where
    estimated; aC, aE, aobs, az, aw : the same for the ATB rows (rad); sound_speed : m/s.
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
    fC: FloatArray
    fE: FloatArray
    fobs: FloatArray
    fvel: FloatArray
    fz: FloatArray
    fw: FloatArray
    fO: FloatArray
    f0fix: FloatArray
    aC: FloatArray
    aE: FloatArray
    aobs: FloatArray
    az: FloatArray
    aw: FloatArray
    sound_speed: float = SOUND_SPEED

    @staticmethod
    def build(
        bearings: Bearings,
        support: Sequence[SupportValue],
        starts: FloatArray,
        sigma: float,
        square: bool = False,
        index: NDArray[np.int64] | None = None,
        sound_speed: float = SOUND_SPEED,
    ) -> Problem:
        """Unbatched problem for one contact.

        ``sigma`` (rad) applies where ``bearings.sigma`` is None; ``index`` selects bearings
        (the start search uses a subset; the frequency and ATB rows are then thinned to at
        most as many, evenly spaced); ``square`` selects the patent's squared support
        residuals; ``sound_speed`` in m/s.
        """
        sig = bearings.sigma if bearings.sigma is not None else np.full(len(bearings), sigma)
        t, z, obs = bearings.t, bearings.bearing, bearings.observer
        if index is not None:
            t, z, obs, sig = t[index], z[index], obs[index], sig[index]
        rows = support_rows(support, starts, square)
        L1 = starts.size + 1
        fr, ab = bearings.frequencies, bearings.bow_angles
        if index is not None:
            fi = None if fr is None else decimate(len(fr), index.size)
            fr = fr if fr is None or fi is None else fr.subset(fi)
            ai = None if ab is None else decimate(len(ab), index.size)
            ab = ab if ab is None or ai is None else ab.subset(ai)
        extra: dict[str, FloatArray] = {}
        if fr is None or not len(fr):
            extra.update(_no_rows(L1, "F"))
        else:
            tonals = fr.tonals
            assert fr.tonal is not None
            fO = (fr.tonal[:, None] == np.asarray(tonals, dtype=str)[None, :]).astype(float)
            f0fix = np.array([fr.base_frequency.get(k, np.nan) for k in tonals], dtype=float)
            vals = (
                leg_time_matrix(fr.t, starts), _leg_rows(fr.t, starts), fr.observer,
                fr.observer_velocity, fr.frequency, 1.0 / fr.sigma**2, fO, f0fix,
            )  # fmt: skip
            extra.update(zip(_FIELDS["F"], vals, strict=True))
        if ab is None or not len(ab):
            extra.update(_no_rows(L1, "A"))
        else:
            avals = (
                leg_time_matrix(ab.t, starts), _leg_rows(ab.t, starts), ab.observer, ab.angle,
                1.0 / ab.sigma**2,
            )  # fmt: skip
            extra.update(zip(_FIELDS["A"], avals, strict=True))
        return Problem(
            C=leg_time_matrix(t, starts), obs=np.asarray(obs, dtype=float),
            z=np.asarray(z, dtype=float), wb=1.0 / sig**2, sk=rows.kind, sA=rows.A,
            soff=rows.offset, sval=rows.value, sw=rows.weight, square=rows.square,
            c_last=leg_time_matrix(bearings.t[-1:], starts)[0], sound_speed=float(sound_speed),
            **extra,
        )  # fmt: skip

    @staticmethod
    def stack(problems: Sequence[Problem]) -> Problem:
        """Pad and stack unbatched problems of equal state size into a batch."""
        size = {
            ax: max(getattr(p, name).shape[0] for p in problems)
            for name, ax in (("z", "N"), ("sk", "M"), ("fz", "F"), ("az", "A"), ("f0fix", "T"))
        }

        def padb(a: NDArray[Any], n: int, zero: bool, axis: int = 0) -> NDArray[Any]:
            if a.shape[axis] == n:
                return a
            if zero or a.shape[axis] == 0:
                shape = list(a.shape)
                shape[axis] = n - a.shape[axis]
                fill = np.zeros(shape, a.dtype)
            else:  # repeat the last real row (finite geometry), weight set to zero
                fill = np.repeat(a[-1:], n - a.shape[0], axis=0)
            return np.concatenate([a, fill], axis=axis)

        def col(name: str) -> NDArray[Any]:
            n = size[_AXES[name]]
            if n == 0:  # no problem has rows of this kind
                a = getattr(problems[0], name)
                return np.zeros((len(problems), 0) + a.shape[1:], a.dtype)
            arrs = [padb(getattr(p, name), n, name in _ZERO_PAD) for p in problems]
            if name == "fO":  # tonal columns too
                arrs = [padb(a, size["T"], True, axis=1) for a in arrs]
            if len(arrs) == 1:  # one problem: a batch of one (np.stack's checks cost more)
                return arrs[0][None].copy()
            return np.stack(arrs)

        cols = {name: col(name) for name in _AXES}
        return Problem(
            square=problems[0].square, c_last=np.stack([p.c_last for p in problems]),
            sound_speed=problems[0].sound_speed, **cols,
        )  # fmt: skip

    def repeat(self, k: int) -> Problem:
        """Each batch entry repeated ``k`` times (for multi-start), batch ``K * k``."""
        cols = {name: _repeat_rows(getattr(self, name), k) for name in _AXES}
        return Problem(
            square=self.square, c_last=np.repeat(self.c_last, k, axis=0),
            sound_speed=self.sound_speed, **cols,
        )  # fmt: skip

    @property
    def weights(self) -> FloatArray:
        """Row weights ``(..., N + M + F + A)``: bearings, support values, frequencies, ATB."""
        return np.concatenate([self.wb, self.sw, self.fw, self.aw], axis=-1)

    def evaluate(self, beta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Stacked residuals ``(..., N + M + F + A)`` and Jacobian ``(..., N + M + F + A, n)``
        (frequency rows with the unknown base frequencies eliminated, see
        :func:`~seatrack.tma.measurements.frequency_residuals`)."""
        b = np.asarray(beta, dtype=float)
        r, J = bearing_residuals(b, self.C, self.obs, self.z)
        rs_, Js_ = [r], [J]
        if self.sk.shape[-1]:
            B = b.reshape(b.shape[:-1] + (-1, 2))
            rs, Js = support_residuals(B, self.sk, self.sA, self.soff, self.sval, self.square)
            rs_.append(rs)
            Js_.append(Js)
        if self.fz.shape[-1]:
            rf, Jf, _, _ = self._frequency(b)
            rs_.append(rf)
            Js_.append(Jf)
        if self.az.shape[-1]:
            ra, Ja = bow_angle_residuals(b, self.aC, self.aE, self.aobs, self.az)
            rs_.append(ra)
            Js_.append(Ja)
        if len(rs_) == 1:
            return r, J
        return np.concatenate(rs_, -1), np.concatenate(Js_, -2)

    def _frequency(self, b: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        return frequency_residuals(
            b, self.fC, self.fE, self.fobs, self.fvel, self.fz, self.fw, self.fO, self.f0fix,
            self.sound_speed,
        )  # fmt: skip

    @property
    def estimated_tonals(self) -> NDArray[np.bool_]:
        """(T,) True for the tonals whose base frequency is estimated (unbatched problem)."""
        return np.asarray(np.isnan(self.f0fix))

    def augmented(self, beta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Base frequencies ``(T,)`` (Hz) at ``beta`` and the Jacobian ``(R, n + T_est)`` of
        every row w.r.t. ``beta`` and the estimated base frequencies (unbatched problem;
        rows as in :meth:`evaluate`). Its Fisher information is that of the joint
        parameter vector, so its inverse gives the covariance of the base frequencies."""
        b = np.asarray(beta, dtype=float)
        _, J = self.evaluate(b)
        if not self.fz.shape[-1]:
            return np.zeros(0), J
        _, _, f0, g = self._frequency(b)
        est = self.estimated_tonals
        n0 = J.shape[0] - self.fz.shape[-1] - self.az.shape[-1]
        # the unprojected frequency Jacobian: f0 * dg/dbeta
        fixed = np.where(est, 0.0, self.f0fix)
        plain = frequency_residuals(
            b, self.fC, self.fE, self.fobs, self.fvel, self.fz, self.fw, self.fO,
            np.where(est, f0, fixed), self.sound_speed,
        )[1]  # fmt: skip
        J = J.copy()
        J[n0 : n0 + plain.shape[0]] = plain
        G = np.zeros((J.shape[0], int(est.sum())))
        G[n0 : n0 + plain.shape[0]] = g[:, None] * self.fO[:, est]
        return f0, np.concatenate([J, G], axis=1)
