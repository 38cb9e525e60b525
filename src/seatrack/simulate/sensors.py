"""Sensor simulation: passive bearings, active range/bearing(/elevation)(/range rate).

One function, :func:`observe`, measures a target :class:`~seatrack.simulate.trajectories.Trajectory`
from an observer (a trajectory, or a fixed point) with Gaussian noise, optional
epsilon-contaminated noise (Tukey-Huber mixture: with probability ``epsilon`` a
component's noise variance is multiplied by ``outlier_scale``), missed detections, and
returns which components were anomalous so a clairvoyant filter or a test can use it.
:func:`uniform_clutter` adds false plots uniformly in range and azimuth.

Everything draws from a caller-supplied :class:`numpy.random.Generator` (seeded,
reproducible). Angles in radians (azimuth in [0, 2 pi), clockwise from North).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing
from seatrack.geometry import wrap_2pi
from seatrack.models.measurement import range_rate
from seatrack.simulate.trajectories import Trajectory

FloatArray = NDArray[np.float64]

__all__ = ["COMPONENTS", "NoiseModel", "Measurements", "observe", "uniform_clutter"]

#: measurable components and their units
COMPONENTS = {"azimuth": "rad", "range": "m", "elevation": "rad", "range_rate": "m/s"}


@dataclass(frozen=True)
class NoiseModel:
    """Measurement noise, one entry per component (SI units: m, rad, m/s).

    Parameters
    ----------
    sigma : sequence of float
        Nominal standard deviation of each component.
    epsilon : float
        Probability that a component's noise is anomalous (per component, per scan).
    outlier_scale : float or sequence of float
        Variance multiplier ``q1 / q0`` of anomalous noise (e.g. 10 for range, 25 for
        bearing in Ramazanov's set-up).
    """

    sigma: Sequence[float]
    epsilon: float = 0.0
    outlier_scale: float | Sequence[float] = 1.0

    def __post_init__(self) -> None:
        if not 0.0 <= self.epsilon <= 1.0:
            raise ValueError(f"epsilon must be in [0, 1], got {self.epsilon}")
        if any(not np.isfinite(s) or s < 0 for s in self.sigma):
            raise ValueError(f"sigma must be finite and >= 0, got {list(self.sigma)}")


@dataclass(frozen=True)
class Measurements:
    """Simulated measurements.

    Attributes
    ----------
    t : (N,) s
    z : (N, m) -- columns in the order of ``components``; rows of missed detections are NaN
    components : tuple of str
    sensor_pos : (N, 3) m
    sensor_vel : (N, 3) m/s
    outlier : (N, m) bool -- component drawn from the anomalous noise
    detected : (N,) bool
    truth : (N, m) -- noise-free values
    """

    t: FloatArray
    z: FloatArray
    components: tuple[str, ...]
    sensor_pos: FloatArray
    sensor_vel: FloatArray
    outlier: NDArray[np.bool_]
    detected: NDArray[np.bool_]
    truth: FloatArray

    @property
    def angular(self) -> NDArray[np.bool_]:
        """Which components are angles (their noise wraps)."""
        return np.array([COMPONENTS[c] == "rad" for c in self.components])


def _observer_state(
    observer: Trajectory | ArrayLike | None, t: FloatArray
) -> tuple[FloatArray, FloatArray]:
    if observer is None:
        return np.zeros((t.size, 3)), np.zeros((t.size, 3))
    if isinstance(observer, Trajectory):
        if observer.t.shape == t.shape and np.allclose(observer.t, t):
            return observer.pos.copy(), observer.vel.copy()
        pos = observer.at(t)
        i = np.clip(np.searchsorted(observer.t, t) - 1, 0, len(observer.t) - 1)
        return pos, observer.vel[i].copy()
    p = np.zeros(3)
    o = np.asarray(observer, dtype=float)
    p[: o.size] = o
    return np.broadcast_to(p, (t.size, 3)).copy(), np.zeros((t.size, 3))


def observe(
    target: Trajectory,
    observer: Trajectory | ArrayLike | None,
    components: Sequence[str],
    noise: NoiseModel,
    rng: np.random.Generator,
    p_detect: float = 1.0,
) -> Measurements:
    """Measure ``target`` from ``observer`` at the target's sample times.

    Parameters
    ----------
    target : Trajectory
    observer : Trajectory, (2,)/(3,) fixed position, or None (origin)
    components : subset of ``("azimuth", "range", "elevation", "range_rate")`` in any order
        (``"bearing"`` is accepted for ``"azimuth"``).
    noise : NoiseModel with one sigma per component.
    rng : numpy Generator.
    p_detect : probability of detection per scan; missed scans have NaN rows.
    """
    comps = tuple("azimuth" if c == "bearing" else c for c in components)
    for c in comps:
        if c not in COMPONENTS:
            raise ValueError(f"unknown component {c!r}; choose from {', '.join(COMPONENTS)}")
    if len(noise.sigma) != len(comps):
        raise ValueError(f"noise has {len(noise.sigma)} sigmas for {len(comps)} components")
    t = target.t
    spos, svel = _observer_state(observer, t)
    d = target.pos - spos
    dv = target.vel - svel
    rh = np.hypot(d[:, 0], d[:, 1])
    vals = {
        "azimuth": np.asarray(bearing(d[:, 0], d[:, 1])),
        "range": np.linalg.norm(d, axis=1),
        "elevation": np.arctan2(d[:, 2], rh),
        "range_rate": np.asarray(range_rate(d, dv)),
    }
    truth = np.stack([vals[c] for c in comps], -1)
    n, m = truth.shape
    sigma = np.asarray(noise.sigma, dtype=float)
    scale = np.broadcast_to(np.asarray(noise.outlier_scale, dtype=float), (m,))
    outlier = rng.random((n, m)) < noise.epsilon
    std = sigma * np.where(outlier, np.sqrt(scale), 1.0)
    z = truth + std * rng.standard_normal((n, m))
    ang = np.array([COMPONENTS[c] == "rad" for c in comps])
    for ja in np.flatnonzero(ang):
        if comps[ja] == "azimuth":
            z[:, ja] = wrap_2pi(z[:, ja])
    if "range" in comps:
        jr = comps.index("range")
        z[:, jr] = np.abs(z[:, jr])
    detected: NDArray[np.bool_] = np.asarray(rng.random(n) < p_detect)
    z[~detected] = np.nan
    return Measurements(
        t.copy(), z, comps, spos, svel, outlier & detected[:, None], detected, truth
    )


def uniform_clutter(
    t: ArrayLike,
    density: float,
    range_limits: tuple[float, float],
    azimuth_limits: tuple[float, float],
    rng: np.random.Generator,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """False plots uniform in range and azimuth, Poisson in number per scan.

    Parameters
    ----------
    t : scan times (s).
    density : expected false plots per scan in the given window.
    range_limits, azimuth_limits : (lo, hi) in m and rad (azimuth may wrap past 2 pi).

    Returns
    -------
    times, ranges, azimuths : one entry per false plot.
    """
    tt = np.asarray(t, dtype=float)
    counts = rng.poisson(density, tt.size)
    times = np.repeat(tt, counts)
    k = int(counts.sum())
    rng_ = rng.uniform(range_limits[0], range_limits[1], k)
    az = np.asarray(wrap_2pi(rng.uniform(azimuth_limits[0], azimuth_limits[1], k)))
    return times, rng_, az
