"""Uncertainty of a TMA solution in operator terms, and the Cramér–Rao bound.

* :func:`operator_values` -- position, range, bearing, course and speed at a time, with
  their analytic Jacobian w.r.t. the state ``beta`` (spec "Output in operator terms");
  the covariance of those values is ``G P G^T`` (first-order propagation).
* :func:`crb` -- the Cramér–Rao bound of ``beta`` for a given true trajectory and
  measurement times: ``(J^T W J)^-1`` at the true state (spec "Beyond the patent": for
  Gaussian bearing noise this is the CRLB of the batch problem), inverted only after the
  explicit scaled rank test of :mod:`seatrack.information` (a singular geometry raises
  :class:`~seatrack.information.SingularMatrixError`, whatever the BLAS build).
* :func:`position_crb` -- that bound mapped to the target position at a time.
* :func:`ellipse` -- semi-axes and orientation of a confidence ellipse.

Conventions: x East, y North; bearings and courses in radians clockwise from North.
"""

from __future__ import annotations

from collections.abc import Mapping
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray
from scipy.stats import chi2

from seatrack.geometry import bearing
from seatrack.geometry import course_speed
from seatrack.information import invert_jacobian_information
from seatrack.models.measurement import bearing_jacobian
from seatrack.tma.legs import leg_index
from seatrack.tma.legs import leg_starts
from seatrack.tma.legs import leg_time_matrix
from seatrack.tma.legs import position_map
from seatrack.tma.measurements import SOUND_SPEED
from seatrack.tma.measurements import BowAngles
from seatrack.tma.measurements import Frequencies
from seatrack.tma.measurements import bow_angle
from seatrack.tma.measurements import doppler_ratio
from seatrack.tma.problem import Bearings
from seatrack.tma.problem import Problem
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = ["OPERATOR_NAMES", "operator_values", "crb", "position_crb", "ellipse"]

#: order of the values returned by :func:`operator_values`
OPERATOR_NAMES = ("x", "y", "range", "bearing", "course", "speed")


def operator_values(
    beta: ArrayLike, starts: ArrayLike, t: float, observer: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Target ``(x, y, range, bearing, course, speed)`` at time ``t`` and their Jacobian.

    Parameters
    ----------
    beta : (n,) state ``(X0, Y0, Vx0, Vy0, Vx1, Vy1, ...)`` (spec layout).
    starts : (L,) leg start times (s); ``starts[0]`` is the reference time ``t0``.
    t : float, s.
    observer : (2,) observer position (m) at ``t`` (for range and bearing).

    Returns
    -------
    values : (6,) -- m, m, m, rad [0, 2 pi), rad [0, 2 pi), m/s
    G : (6, n) -- d(values)/d(beta); angle rows are the derivatives of the unwrapped angle.
    """
    b = np.asarray(beta, dtype=float)
    s = np.asarray(starts, dtype=float)
    c = leg_time_matrix(np.array([t]), s)[0]
    M = position_map(c)
    B = b.reshape(-1, 2)
    p = c @ B
    d = p - np.asarray(observer, dtype=float)[:2]
    rng = float(np.hypot(d[0], d[1]))
    j = 1 + int(leg_index(t, s))
    v = B[j]
    crs, spd = course_speed(v[0], v[1])
    n = b.size
    G = np.zeros((6, n))
    G[0:2] = M
    G[2] = (d / rng) @ M
    G[3] = bearing_jacobian(d) @ M
    G[4, 2 * j : 2 * j + 2] = bearing_jacobian(v)
    G[5, 2 * j : 2 * j + 2] = v / spd
    values = np.array([p[0], p[1], rng, bearing(d[0], d[1]), crs, spd])
    return values, G


def crb(
    state: ArrayLike,
    times: ArrayLike,
    observer: ArrayLike,
    sigma: float | ArrayLike,
    manoeuvres: Sequence[float] | ArrayLike = (),
    support: Sequence[SupportValue] = (),
    support_residual: str = "linear",
    frequencies: Frequencies | None = None,
    base_frequency: Mapping[str, float] | None = None,
    bow_angles: BowAngles | None = None,
    sound_speed: float = SOUND_SPEED,
) -> FloatArray:
    """Cramér–Rao bound of the TMA state for a true trajectory and measurement times.

    Any mix of measurements: bearings at ``times``, support values, frequencies and ATB
    (their times, own-ship positions/velocities, tonals and sigmas are taken from
    ``frequencies`` / ``bow_angles``; the measured values are replaced by the noise-free
    ones of the true state). ``base_frequency`` gives the true ``f0`` (Hz) of every tonal;
    the tonals whose ``f0`` is not in ``frequencies.base_frequency`` are estimated, and the
    bound is then that of the joint vector (state, estimated ``f0`` in order of first
    appearance): shape ``(n + T_est, n + T_est)``; its state block is the bound with the
    base frequencies as nuisance parameters.

    Parameters
    ----------
    state : (n,) true ``beta`` (spec layout), reference time ``t0 = times[0]``.
    times : (N,) s, bearing times.
    observer : (N, 2) m, observer positions.
    sigma : float or (N,) rad, bearing standard deviation(s).
    manoeuvres : leg start times after ``t0`` (s).
    support : sequence of :class:`~seatrack.tma.support.SupportValue` (their information is
        included with the same weights as in the solver).
    support_residual : "linear" or "square" (the bound is the same to first order).

    Returns
    -------
    (n, n) bound ``(J^T W J)^-1`` at the true state (``(n + T_est, n + T_est)`` with
    estimated base frequencies, see above).

    Raises
    ------
    seatrack.information.SingularMatrixError
        (a :class:`numpy.linalg.LinAlgError`) if the whitened Jacobian is rank-deficient by
        the explicit scaled test (unobservable geometry, e.g. no own-ship manoeuvre and no
        support value).
    """
    if support_residual not in ("linear", "square"):
        raise ValueError(f"support_residual must be 'linear' or 'square', got {support_residual!r}")
    t = np.asarray(times, dtype=float)
    obs = np.asarray(observer, dtype=float)[:, :2]
    sig = np.broadcast_to(np.asarray(sigma, dtype=float), t.shape)
    b = np.asarray(state, dtype=float)
    starts = leg_starts(float(t[0]), manoeuvres)
    if b.size != 2 + 2 * starts.size:
        raise ValueError(
            f"state has {b.size} components; {starts.size} legs need {2 + 2 * starts.size}"
        )
    # noise-free bearings from the true state: the Jacobian does not depend on z
    C = leg_time_matrix(t, starts)
    p = C @ b.reshape(-1, 2)
    z = bearing(p[:, 0] - obs[:, 0], p[:, 1] - obs[:, 1])
    B = b.reshape(-1, 2)
    fr, ab = frequencies, bow_angles
    if fr is not None and len(fr):
        f0 = base_frequency or {}
        missing = [k for k in fr.tonals if k not in f0]
        if missing:
            raise ValueError(f"base_frequency needs the true f0 of tonal(s) {missing}")
        E = leg_time_matrix(fr.t, starts)
        j = 1 + leg_index(fr.t, starts)
        g, _, _ = doppler_ratio(E @ B - fr.observer, fr.observer_velocity, B[j], sound_speed)
        assert fr.tonal is not None
        true = np.array([f0[k] for k in fr.tonal.tolist()])
        fr = replace(fr, frequency=true * g)
    if ab is not None and len(ab):
        j = 1 + leg_index(ab.t, starts)
        ab = replace(ab, angle=bow_angle(leg_time_matrix(ab.t, starts) @ B - ab.observer, B[j]))
    bearings = Bearings(t, np.asarray(z), obs, np.array(sig), fr, ab)
    prob = Problem.build(
        bearings, list(support), starts, 1.0, support_residual == "square", None, sound_speed
    )
    _, J = prob.augmented(b)
    return invert_jacobian_information(J, prob.weights, "TMA Fisher information")


def position_crb(bound: ArrayLike, starts: ArrayLike, t: float) -> FloatArray:
    """Map a state covariance/bound ``(n, n)`` to the target position at time ``t`` (2, 2).

    Position is linear in ``beta`` (``p(t) = M(t) beta``), so the map is exact: ``M P M^T``.
    No inverse is involved; a bound that is not finite (the NaN covariance of a singular
    geometry) or not square of at least the state size is a :class:`ValueError`; of a
    joint bound (state, base frequencies) the leading state block is used.
    """
    s = np.asarray(starts, dtype=float)
    P = np.asarray(bound, dtype=float)
    n = 2 + 2 * s.size
    if P.ndim != 2 or P.shape[0] != P.shape[1] or P.shape[0] < n:
        raise ValueError(f"bound has shape {P.shape}; {s.size} legs need ({n}, {n})")
    P = P[:n, :n]  # a joint bound (state, base frequencies): the state block
    if not np.all(np.isfinite(P)):
        raise ValueError("bound is not finite (singular geometry: the state is not observable)")
    M = position_map(leg_time_matrix(np.array([t]), s)[0])
    return np.asarray(M @ P @ M.T)


def ellipse(cov: ArrayLike, p: float = 0.95) -> tuple[float, float, float]:
    """Confidence ellipse of a 2-D Gaussian: ``(semi_major, semi_minor, orientation)``.

    ``orientation`` is the direction of the major axis in radians clockwise from North,
    in ``[0, pi)``; the axes are scaled by ``sqrt(chi2.ppf(p, 2))``.
    """
    P = np.asarray(cov, dtype=float)
    w, V = np.linalg.eigh(0.5 * (P + P.T))
    k = float(np.sqrt(chi2.ppf(p, 2)))
    major = V[:, 1]
    ori = float(np.mod(bearing(major[0], major[1]), np.pi))
    return k * float(np.sqrt(max(w[1], 0.0))), k * float(np.sqrt(max(w[0], 0.0))), ori
