"""Motion and measurement models (pure functions plus thin configuration objects)."""

from seatrack.models.measurement import Bearing
from seatrack.models.measurement import MeasurementModel
from seatrack.models.measurement import Position
from seatrack.models.measurement import RangeBearing
from seatrack.models.measurement import RangeBearingElevation
from seatrack.models.measurement import RangeRate
from seatrack.models.measurement import Stacked
from seatrack.models.motion import ConstantAcceleration
from seatrack.models.motion import ConstantVelocity
from seatrack.models.motion import CoordinatedTurn
from seatrack.models.motion import MotionModel
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
