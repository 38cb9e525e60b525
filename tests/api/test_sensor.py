"""seatrack.Sensor and the bounds of the internal sensor and tracker configurations."""

from __future__ import annotations

import numpy as np
import pytest
from tests.api.examples import run_examples

import seatrack
from seatrack.config import ConfigError
from seatrack.filters.base import SensorNoise
from seatrack.tracking import TrackerConfig


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"sigma_range_m": -1.0}, "sigma_range_m"),
        ({"sigma_range_m": 0.0}, "sigma_range_m"),
        ({"sigma_azimuth_deg": float("nan")}, "sigma_azimuth_deg"),
        ({"sigma_elevation_deg": float("inf")}, "sigma_elevation_deg"),
        ({"sigma_range_rate_mps": -0.5}, "sigma_range_rate_mps"),
    ],
)
def test_sensor_refuses_a_bad_sigma_naming_the_argument(kw, name):
    with pytest.raises(ValueError, match=f"^Sensor: {name}: "):
        seatrack.Sensor(**kw)


def test_sensor_converts_degrees_to_radians():
    s = seatrack.Sensor(sigma_range_m=20.0, sigma_azimuth_deg=0.3, sigma_range_rate_mps=0.5)
    n = s.noise()
    assert n.sigma_range == 20.0 and n.sigma_range_rate == 0.5
    assert n.sigma_azimuth == pytest.approx(np.radians(0.3), rel=1e-15)
    assert n.sigma_elevation == SensorNoise().sigma_elevation  # the default
    assert seatrack.Sensor.from_noise(n).noise() == n


def test_configs_built_directly_check_their_bounds():
    with pytest.raises(ConfigError, match=r"SensorNoise.sigma_azimuth \(sigma_azimuth_deg\)"):
        SensorNoise(sigma_azimuth=-0.01)
    with pytest.raises(ConfigError, match="must be finite"):
        SensorNoise(sigma_range=float("nan"))
    with pytest.raises(ConfigError, match=r"TrackerConfig.max_speed \(max_speed_kn\)"):
        TrackerConfig(max_speed=-1.0)
    SensorNoise(sigma_azimuth=np.pi)  # the upper bound itself (180 deg) is allowed


def test_examples():
    run_examples("seatrack.api.sensor")
