"""Motion and measurement models (pure functions plus thin configuration objects)."""

from seatrack.models.measurement import (
    Bearing,
    MeasurementModel,
    Position,
    RangeBearing,
    RangeBearingElevation,
    RangeRate,
    Stacked,
)
from seatrack.models.motion import (
    ConstantAcceleration,
    ConstantVelocity,
    CoordinatedTurn,
    MotionModel,
)
from seatrack.models.numdiff import numerical_jacobian

__all__ = [
    "Bearing",
    "ConstantAcceleration",
    "ConstantVelocity",
    "CoordinatedTurn",
    "MeasurementModel",
    "MotionModel",
    "Position",
    "RangeBearing",
    "RangeBearingElevation",
    "RangeRate",
    "Stacked",
    "numerical_jacobian",
]
