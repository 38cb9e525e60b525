"""Settings chosen from the data: scan period and the process noise of the class."""

import numpy as np
import pytest

from seatrack.filters.base import SensorNoise
from seatrack.filters.ekf import EKF, EKFConfig
from seatrack.tracking.adaptive import NoiseLevels
from seatrack.tracking.auto import noise_levels, per_track_filter, scan_period


def test_scan_period_is_the_median_interval():
    assert scan_period([0, 0, 2.5, 2.5, 5.0, 10.0]) == pytest.approx(2.5)
    assert scan_period([3.0, 3.0]) == 1.0


def test_noise_levels_scale_with_the_period():
    lo, hi = noise_levels(2.5)
    lo2, hi2 = noise_levels(5.0)
    assert lo < hi and lo2 == pytest.approx(2 * lo) and hi2 == pytest.approx(2 * hi)
    with pytest.raises(ValueError):
        noise_levels(0.0)


def test_per_track_filter_adapts_only_when_q_is_not_given():
    sn = SensorNoise()
    auto = per_track_filter(EKF, EKFConfig(), set(), sn, 2, False, 2.5)
    assert isinstance(auto, NoiseLevels)
    assert auto.flt.config.q == pytest.approx(noise_levels(2.5)[0])
    fixed = per_track_filter(EKF, EKFConfig(q=0.7), {"q"}, sn, 3, True, 2.5)
    assert isinstance(fixed, EKF) and fixed.config.q == 0.7 and fixed.d == 3
    assert np.isclose(fixed.R[0, 0], sn.sigma_range**2)
