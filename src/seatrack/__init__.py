"""seatrack: maritime and radar target tracking and navigation.

Bearings-only target motion analysis, multiple-model, robust-adaptive and turning-target
filters, landmark navigation and AIS tracking on one Kalman core. x East, y North, z Up;
SI units and radians inside; bearings clockwise from North.
"""

__version__ = "0.1.0"
