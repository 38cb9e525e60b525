"""Scenario simulation: leg-based trajectories and sensors (seeded, reproducible)."""

from seatrack.simulate.sensors import Measurements
from seatrack.simulate.sensors import NoiseModel
from seatrack.simulate.sensors import observe
from seatrack.simulate.sensors import uniform_clutter
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import Trajectory
from seatrack.simulate.trajectories import leg_times
from seatrack.simulate.trajectories import trajectory

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
