"""TMA test scenarios built with :mod:`seatrack.simulate` (the project's one simulator).

:func:`classic_scenario` is the bearings-only scenario of Ristic, Arulampalam & Gordon,
*Beyond the Kalman Filter* (2004), ch. 6: observer at the origin, 5 kn, course 140 deg,
turning to 20 deg in four equal steps over samples 13-16; target at (4.92, 0.85) km,
4 kn, course -140 deg; bearing sigma 1.5 deg; T = 60 s; 32 bearings.

[reading] The book's observer changes course by 30 deg at each of samples 13-16; here, as
in the bundled ``data/scenarios/tma_classic.toml``, the own ship makes one coordinated port
turn of 120 deg at 0.5 deg/s from t = 660 s to t = 900 s, which passes through exactly the
book's courses at the sample times (110, 80, 50, 20 deg at samples 13-16; sample k at
t = 60 (k - 1) s).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.geometry import knots_to_mps
from seatrack.geometry import velocity_from_course
from seatrack.simulate import Leg
from seatrack.simulate import Measurements
from seatrack.simulate import NoiseModel
from seatrack.simulate import Trajectory
from seatrack.simulate import observe
from seatrack.simulate import trajectory
from seatrack.tma.legs import leg_starts
from seatrack.tma.measurements import SOUND_SPEED
from seatrack.tma.measurements import BowAngles
from seatrack.tma.measurements import Frequencies
from seatrack.tma.measurements import bow_angle
from seatrack.tma.measurements import doppler_ratio
from seatrack.tma.problem import Bearings

FloatArray = NDArray[np.float64]

__all__ = ["TMAScenario", "classic_scenario", "scenario_from_trajectories"]


@dataclass(frozen=True)
class TMAScenario:
    """Truth of a bearings-only scenario.

    Attributes
    ----------
    target, observer : sampled :class:`~seatrack.simulate.Trajectory` at the bearing times.
    sigma : bearing standard deviation, rad.
    state : true ``beta`` (spec layout) at ``t0 = target.t[0]`` for the legs ``manoeuvres``.
    manoeuvres : true leg start times after ``t0`` (s).
    """

    target: Trajectory
    observer: Trajectory
    sigma: float
    state: FloatArray
    manoeuvres: tuple[float, ...] = ()

    @property
    def times(self) -> FloatArray:
        return self.target.t

    @property
    def starts(self) -> FloatArray:
        return leg_starts(float(self.target.t[0]), self.manoeuvres)

    def measurements(self, rng: np.random.Generator) -> Measurements:
        """One noisy realisation as simulator :class:`~seatrack.simulate.Measurements`."""
        return observe(self.target, self.observer, ("azimuth",), NoiseModel([self.sigma]), rng)

    def bearings(self, rng: np.random.Generator) -> Bearings:
        """One noisy realisation of the bearings (via :func:`seatrack.simulate.observe`)."""
        m = self.measurements(rng)
        return Bearings(m.t, m.z[:, 0], m.sensor_pos[:, :2])

    def frequencies(
        self,
        rng: np.random.Generator,
        base_frequency: float,
        sigma_hz: float,
        sound_speed: float = SOUND_SPEED,
        tonal: str = "1",
    ) -> Frequencies:
        """Noisy received frequencies of one tonal at the bearing times (model of
        :mod:`seatrack.tma.measurements`, own-ship velocity from the true trajectory)."""
        d = self.target.pos[:, :2] - self.observer.pos[:, :2]
        g, _, _ = doppler_ratio(d, self.observer.vel[:, :2], self.target.vel[:, :2], sound_speed)
        f = base_frequency * g + sigma_hz * rng.standard_normal(g.shape)
        n = self.times.size
        return Frequencies(
            self.times, f, self.observer.pos[:, :2], self.observer.vel[:, :2],
            np.full(n, sigma_hz), np.full(n, tonal),
        )  # fmt: skip

    def bow_angles(self, rng: np.random.Generator, sigma: float) -> BowAngles:
        """Noisy angles on the bow (rad) at the bearing times."""
        d = self.target.pos[:, :2] - self.observer.pos[:, :2]
        a = bow_angle(d, self.target.vel[:, :2]) + sigma * rng.standard_normal(self.times.size)
        return BowAngles(self.times, a, self.observer.pos[:, :2], np.full(self.times.size, sigma))

    def bearings_batch(self, rng: np.random.Generator, n_runs: int) -> list[Bearings]:
        """``n_runs`` independent realisations."""
        return [self.bearings(rng) for _ in range(n_runs)]


def scenario_from_trajectories(
    target: Trajectory, observer: Trajectory, sigma: float, manoeuvres: Sequence[float] = ()
) -> TMAScenario:
    """Scenario whose true ``beta`` is read from a piecewise-straight target trajectory.

    The velocity of each leg is the target velocity at the first sample inside the leg.
    """
    starts = leg_starts(float(target.t[0]), manoeuvres)
    vel = []
    for s in starts:
        i = int(np.searchsorted(target.t, s, side="left"))
        i = min(i, target.t.size - 1)
        vel.append(target.vel[i, :2])
    state = np.concatenate([target.pos[0, :2]] + vel)
    return TMAScenario(target, observer, sigma, state, tuple(float(m) for m in manoeuvres))


def classic_scenario(n: int = 32, dt: float = 60.0, sigma_deg: float = 1.5) -> TMAScenario:
    """The Ristic-Arulampalam-Gordon bearings-only scenario (ch. 6), see module docstring."""
    times = dt * np.arange(n)
    rate = math.radians(0.5)
    obs_legs = [  # straight to t = 11 dt, then the turn (see module docstring)
        Leg.straight(11 * dt),
        Leg.turn(math.radians(-120.0), rate),
        Leg.straight(max(times[-1], 1.0)),
    ]
    observer = trajectory(
        [0.0, 0.0], math.radians(140.0), float(knots_to_mps(5.0)), obs_legs, times=times
    )
    course, speed = math.radians(-140.0), float(knots_to_mps(4.0))
    target = trajectory([4920.0, 850.0], course, speed, [Leg.straight(times[-1] + dt)], times=times)
    state = np.concatenate([[4920.0, 850.0], velocity_from_course(course, speed)])
    return TMAScenario(target, observer, math.radians(sigma_deg), state)
