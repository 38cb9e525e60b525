"""Monte-Carlo batches of Ramazanov's sonar scenario (spec ``docs/robust.md``).

The truth kinematics of the paper -- a target driven by tangential acceleration ``a_L`` and
turn rate ``w_L`` (spec "Truth model"), seen from a moving own ship -- are exactly the legs
of :func:`seatrack.simulate.trajectory` (``Leg(duration, turn_rate, accel)``), and the
epsilon-contaminated range/bearing noise is :func:`seatrack.simulate.observe` with
``NoiseModel(sigma, epsilon, outlier_scale)``. This module only draws the random geometry of
each run and stacks the runs along a leading batch axis for the vectorised filters.

Geometry of one run (all angles clockwise from North): own ship starts at the origin on a
uniformly random course ``theta`` at ``own_speed``; the target starts at a range drawn
uniformly from ``initial_range`` at the relative bearing ``theta + beta``, ``beta`` uniform
in ``relative_bearing`` (starboard side by default) and steers ``theta + delta_course``,
``delta_course`` uniform in ``course_spread``, at ``target_speed``; then follows ``legs``
(a turn of ``turn_angle`` at ``turn_rate`` with tangential acceleration ``turn_accel``
after ``turn_start`` seconds, when ``manoeuvre`` is set).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.simulate.sensors import NoiseModel
from seatrack.simulate.sensors import observe
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import trajectory

FloatArray = NDArray[np.float64]

__all__ = ["MarineScenario", "SonarRuns", "simulate_runs"]


@dataclass(frozen=True)
class MarineScenario:
    """Parameters of the sonar tracking scenario (SI units, radians).

    Defaults: the paper's noise (range sigma 1.5 m, x10 variance when anomalous; bearing
    sigma 2 deg, x25) and initial range 900-950 m; the rest (not given in the paper) chosen
    here: ping interval ``dt`` = 2 s, 150 plots (300 s), own ship 4 m/s, target 6 m/s; the
    manoeuvre is a 90 deg starboard turn at 1.5 deg/s with a_L = 0.03 m/s^2 starting at 100 s.
    """

    dt: float = 2.0
    steps: int = 150
    sigma_range: float = 1.5
    sigma_bearing: float = float(np.deg2rad(2.0))
    outlier_scale_range: float = 10.0
    outlier_scale_bearing: float = 25.0
    initial_range: tuple[float, float] = (900.0, 950.0)
    relative_bearing: tuple[float, float] = (float(np.deg2rad(60.0)), float(np.deg2rad(120.0)))
    course_spread: tuple[float, float] = (0.0, float(np.deg2rad(30.0)))
    own_speed: float = 4.0
    target_speed: float = 6.0
    manoeuvre: bool = False
    turn_start: float = 100.0
    turn_angle: float = float(np.deg2rad(90.0))
    turn_rate: float = float(np.deg2rad(1.5))
    turn_accel: float = 0.03

    def __post_init__(self) -> None:
        if self.dt <= 0 or self.steps < 2:
            raise ValueError(f"need dt > 0 and steps >= 2, got dt={self.dt}, steps={self.steps}")
        if self.manoeuvre and self.turn_start + self.turn_angle / self.turn_rate > self.duration:
            raise ValueError(
                "the manoeuvre does not fit in the run; lengthen steps or move turn_start"
            )

    @property
    def duration(self) -> float:
        """Run length, s."""
        return self.dt * (self.steps - 1)

    @property
    def legs(self) -> list[Leg]:
        """Target legs (after its initial course and speed)."""
        if not self.manoeuvre:
            return [Leg.straight(self.duration)]
        turn = Leg.turn(self.turn_angle, self.turn_rate)
        turn = Leg(turn.duration, turn.turn_rate, self.turn_accel)
        rest = self.duration - self.turn_start - turn.duration
        legs = [Leg.straight(self.turn_start), turn]
        return legs + ([Leg.straight(rest)] if rest > 0 else [])

    @property
    def noise_sigma(self) -> tuple[float, float]:
        """``(range m, bearing rad)`` nominal sigmas, the component order of :class:`SonarRuns`."""
        return (self.sigma_range, self.sigma_bearing)

    @property
    def outlier_scale(self) -> tuple[float, float]:
        """``q1 / q0`` of [range, bearing]."""
        return (self.outlier_scale_range, self.outlier_scale_bearing)


@dataclass(frozen=True)
class SonarRuns:
    """A batch of simulated runs (leading axis = run).

    Attributes
    ----------
    t : (N,) s
    z : (B, N, 2) measured [range m, true bearing rad in [0, 2 pi)]
    outlier : (B, N, 2) bool -- component drawn from the anomalous noise
    sensor : (B, N, 2) own-ship position East, North, m
    truth : (B, N, 4) target state [x, y, vx, vy]
    accel : (B, N) magnitude of the true target acceleration, m/s^2
    """

    t: FloatArray
    z: FloatArray
    outlier: NDArray[np.bool_]
    sensor: FloatArray
    truth: FloatArray
    accel: FloatArray


def simulate_runs(
    scenario: MarineScenario, n_runs: int, epsilon: float, rng: np.random.Generator
) -> SonarRuns:
    """Draw ``n_runs`` independent runs of ``scenario`` with contamination ``epsilon``.

    The geometry is drawn first (one block of random numbers), then the measurements run by
    run, so two calls with equal seeds and different ``epsilon`` share the same geometry.
    """
    if n_runs < 1:
        raise ValueError(f"n_runs must be >= 1, got {n_runs}")
    sc = scenario
    theta = rng.uniform(0.0, 2 * np.pi, n_runs)
    r0 = rng.uniform(*sc.initial_range, n_runs)
    beta = rng.uniform(*sc.relative_bearing, n_runs)
    dcourse = rng.uniform(*sc.course_spread, n_runs)
    noise = NoiseModel(sc.noise_sigma, epsilon, sc.outlier_scale)
    legs = sc.legs
    zs, outl, sens, truth, acc = [], [], [], [], []
    for b in range(n_runs):
        own = trajectory([0.0, 0.0], theta[b], sc.own_speed, [Leg.straight(sc.duration)], dt=sc.dt)
        start = r0[b] * np.array([np.sin(theta[b] + beta[b]), np.cos(theta[b] + beta[b])])
        tgt = trajectory(start, theta[b] + dcourse[b], sc.target_speed, legs, dt=sc.dt)
        meas = observe(tgt, own, ("range", "azimuth"), noise, rng)
        zs.append(meas.z)
        outl.append(meas.outlier)
        sens.append(own.pos[:, :2])
        truth.append(tgt.state("cv2"))
        acc.append(np.hypot(tgt.acc[:, 0], tgt.acc[:, 1]))
    return SonarRuns(
        own.t.copy(), np.array(zs), np.array(outl), np.array(sens), np.array(truth), np.array(acc)
    )
