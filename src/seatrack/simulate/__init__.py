"""Scenario simulation: leg-based trajectories and sensors (seeded, reproducible)."""

from seatrack.simulate.sensors import Measurements, NoiseModel, observe, uniform_clutter
from seatrack.simulate.trajectories import Leg, Trajectory, leg_times, trajectory

__all__ = [
    "Leg",
    "Measurements",
    "NoiseModel",
    "Trajectory",
    "leg_times",
    "observe",
    "trajectory",
    "uniform_clutter",
]
