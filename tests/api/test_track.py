"""seatrack.track: arguments, the sensor, the docstring examples."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from tests.api.examples import labelled_plots
from tests.api.examples import run_examples

import seatrack
from seatrack.config import ConfigError
from seatrack.io.table import InputError


def test_track_arguments_are_checked():
    with pytest.raises(ValueError, match="unknown method"):
        seatrack.track(labelled_plots(), method="nope")
    with pytest.raises(InputError, match="association: must be gnn or jpda"):
        seatrack.track(labelled_plots(), association="nn")
    sensor = seatrack.Sensor(sigma_range_m=5.0)
    with pytest.raises(ConfigError, match="both in the config and as sensor="):
        seatrack.track(labelled_plots(), sensor=sensor, config={"sigma_range_m": 3.0})


def test_sensor_given_as_argument_equals_the_same_config_keys():
    sensor = seatrack.Sensor(sigma_range_m=5.0, sigma_azimuth_deg=0.1)
    a = seatrack.track(labelled_plots(), sensor=sensor)
    b = seatrack.track(
        labelled_plots(), config={"sensor": {"sigma_range_m": 5.0, "sigma_azimuth_deg": 0.1}}
    )
    pd.testing.assert_frame_equal(a, b)
    c = seatrack.track(labelled_plots())
    assert not np.array_equal(a["std_x_m"].to_numpy(), c["std_x_m"].to_numpy())


def test_examples():
    run_examples("seatrack.api.track")
