"""``seatrack.Sensor``: the measurement noise of a radar or sonar, in the units of the files."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from seatrack.config import parse_config
from seatrack.config import to_edge
from seatrack.filters.base import SensorNoise

__all__ = ["Sensor"]


@dataclass(frozen=True)
class Sensor:
    """Measurement noise (1-sigma) of the plots of one sensor.

    The names and units are the keys of the ``[sensor]`` table of a configuration file.
    An argument left ``None`` takes the documented default of
    :class:`seatrack.filters.base.SensorNoise` (a coastal surveillance radar).

    Parameters
    ----------
    sigma_range_m : float, optional
        Range noise, m (> 0, at most 1e6).
    sigma_azimuth_deg : float, optional
        Azimuth noise, degrees (> 0, at most 180).
    sigma_elevation_deg : float, optional
        Elevation noise, degrees (> 0, at most 90); used by 3-D plots only.
    sigma_range_rate_mps : float, optional
        Range-rate noise, m/s (> 0, at most 1e5); used by plots with a range rate only.

    Raises
    ------
    ValueError
        (a :class:`seatrack.config.ConfigError`) naming the argument, for a value that is
        not a finite number in its range (zero and negative sigmas included).

    Examples
    --------
    >>> import seatrack
    >>> s = seatrack.Sensor(sigma_range_m=20.0, sigma_azimuth_deg=0.3)
    >>> round(s.noise().sigma_azimuth, 6)  # radians inside seatrack
    0.005236
    >>> seatrack.Sensor(sigma_range_m=-1.0)
    Traceback (most recent call last):
    ...
    seatrack.config.ConfigError: Sensor: sigma_range_m: must be > 0 m, got -1.0
    """

    sigma_range_m: float | None = None
    sigma_azimuth_deg: float | None = None
    sigma_elevation_deg: float | None = None
    sigma_range_rate_mps: float | None = None

    def __post_init__(self) -> None:
        self.noise()  # every argument checked here, by name

    def table(self) -> dict[str, Any]:
        """The given arguments as a ``[sensor]`` configuration table (file keys and units)."""
        return {k: v for k, v in vars(self).items() if v is not None}

    def noise(self) -> SensorNoise:
        """The internal :class:`~seatrack.filters.base.SensorNoise` (SI units, radians)."""
        return parse_config(SensorNoise, self.table(), source="Sensor")

    @classmethod
    def from_noise(cls, noise: SensorNoise) -> Sensor:
        """The sensor of an internal :class:`~seatrack.filters.base.SensorNoise`."""
        return cls(**to_edge(noise))
