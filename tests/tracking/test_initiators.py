"""Two-point initiation as a role: a pair within the speed gate starts one track, a pair
too fast for it waits; the unit-suffixed arguments are converted once."""

from __future__ import annotations

import numpy as np

from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.ekf import EKF
from seatrack.tracking.components import TrackerConfig
from seatrack.tracking.initiators import TwoPointInitiator
from seatrack.tracking.roles import Tracker

SN = SensorNoise(sigma_range=10.0, sigma_azimuth=np.radians(0.2))


def test_arguments_in_knots_match_the_configuration_keys():
    a = TwoPointInitiator(max_speed_kn=30, initial_speed_sigma_kn=8, init_scans=2)
    b = TwoPointInitiator.from_config(
        TrackerConfig.from_keys(max_speed_kn=30, initial_speed_sigma_kn=8, init_scans=2)
    )
    assert (a.max_speed, a.initial_speed_sigma, a.init_scans) == (
        b.max_speed, b.initial_speed_sigma, b.init_scans)  # fmt: skip
    assert a.max_speed == 30 * 1852 / 3600


def _two_scans(step_m: float) -> list[Plots]:
    """One plot at 8 km, then one ``step_m`` further north 2.5 s later."""
    r = np.array([8000.0, 8000.0 + step_m])
    return [Plots(np.array([2.5 * k]), r[k : k + 1], np.zeros(1)) for k in range(2)]


def test_the_speed_gate_starts_slow_pairs_only():
    slow, fast = _two_scans(25.0), _two_scans(250.0)  # 20 kn and 194 kn
    for plots, started in ((slow, 1), (fast, 0)):
        init = TwoPointInitiator(max_speed_kn=40)
        trk = Tracker(EKF(sensor=SN), initiator=init, sensor=SN)
        trk.step(0.0, plots[0])
        res = trk.step(2.5, plots[1])
        assert res.track.size == started
        assert sum(len(e) for e in init.pending) == 2 - 2 * started  # the rest wait
    assert res.started_from.shape == (2, 0)
