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
    with pytest.raises(InputError, match="or an Associator"):
        seatrack.track(labelled_plots(), association=3)
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


def test_an_associator_object_replaces_the_association_role():
    """A user's associator given as ``association`` is the tracker's associator; one that
    wraps the default GNN gives the GNN's tracks and is called once per scan."""
    from seatrack.tracking.roles import GNN

    class Counting:
        def __init__(self):
            self.calls, self.inner = 0, GNN()

        def associate(self, flt, pred, scan, hyp):
            self.calls += 1
            return self.inner.associate(flt, pred, scan, hyp)

    plots = {k: v for k, v in labelled_plots().items() if k != "track"}
    own = Counting()
    a = seatrack.track(plots, association=own)
    b = seatrack.track(plots, association="gnn")
    pd.testing.assert_frame_equal(a, b)
    assert own.calls > 0 and len(a) > 0


def test_examples():
    run_examples("seatrack.api.track")
