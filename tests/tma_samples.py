"""Shared TMA test data: random one-turn geometries and a BEARINGS.csv writer (used by the
tma, io and command tests)."""

import math

import numpy as np

from seatrack.geometry import bearing_rad_to_deg
from seatrack.simulate import Leg
from seatrack.simulate import trajectory
from seatrack.simulate.tma import TMAScenario
from seatrack.simulate.tma import classic_scenario
from seatrack.simulate.tma import scenario_from_trajectories

HEADER = "contact,time_s,bearing_deg,observer_x_m,observer_y_m,sigma_deg\n"


def random_geometry(rng: np.random.Generator) -> TMAScenario:
    """One own-ship turn of 40-140 deg, target 1-40 km away on any course at 1-12 m/s,
    20-80 bearings every 10-60 s, bearing sigma 0.3-2 deg."""
    n, dt = int(rng.integers(20, 80)), float(rng.uniform(10, 60))
    T = n * dt
    times = dt * np.arange(n)
    turn = rng.choice([-1, 1]) * rng.uniform(math.radians(40), math.radians(140))
    legs = [Leg.straight(rng.uniform(0.2, 0.6) * T), Leg.turn(turn, math.radians(1.0))]
    obs = trajectory(
        [0, 0], rng.uniform(0, 2 * np.pi), rng.uniform(2, 8), legs + [Leg.straight(2 * T)],
        times=times,
    )  # fmt: skip
    r0, b0 = math.exp(rng.uniform(math.log(1000), math.log(40000))), rng.uniform(0, 2 * np.pi)
    tgt = trajectory(
        [r0 * math.sin(b0), r0 * math.cos(b0)], rng.uniform(0, 2 * np.pi), rng.uniform(1, 12),
        [Leg.straight(2 * T)], times=times,
    )  # fmt: skip
    return scenario_from_trajectories(tgt, obs, math.radians(rng.uniform(0.3, 2)))


def write_bearings(path, contacts=("A",), rng_seed=0):
    """BEARINGS.csv with one noisy classic-scenario realisation per contact (sigma 1.5 deg)."""
    sc = classic_scenario()
    rng = np.random.default_rng(rng_seed)
    rows = [HEADER]
    for c in contacts:
        b = sc.bearings(rng)
        for t, z, o in zip(b.t, b.bearing, b.observer, strict=True):
            rows.append(f"{c},{t:g},{bearing_rad_to_deg(z):.4f},{o[0]:.2f},{o[1]:.2f},1.5\n")
    path.write_text("".join(rows))
    return path
