"""Settings chosen from the data: scan period, the per-track filter from the registry and
the process noise of the class."""

import numpy as np
import pytest

from seatrack.config import ConfigError
from seatrack.filters.cvct_imm import CVCTIMM
from seatrack.filters.ekf import EKF
from seatrack.filters.registry import METHODS
from seatrack.tracking.adaptive import NoiseLevels
from seatrack.tracking.auto import noise_levels
from seatrack.tracking.auto import per_track_filter
from seatrack.tracking.auto import scan_period
from seatrack.tracking.auto import user_gave_noise


def test_scan_period_is_the_median_interval():
    assert scan_period([0, 0, 2.5, 2.5, 5.0, 10.0]) == pytest.approx(2.5)
    assert scan_period([3.0, 3.0]) == 1.0


def test_noise_levels_scale_with_the_period():
    lo, hi = noise_levels(2.5)
    lo2, hi2 = noise_levels(5.0)
    assert lo < hi and lo2 == pytest.approx(2 * lo) and hi2 == pytest.approx(2 * hi)
    with pytest.raises(ValueError):
        noise_levels(0.0)


def test_every_registered_method_has_a_noise_rule():
    assert {r.noise for r in METHODS.values()} == {"levels", "wrap", "own"}
    assert [n for n, r in METHODS.items() if r.noise == "levels"] == ["ekf"]


def test_ekf_gets_the_noise_levels_only_when_q_is_not_given():
    sensor = {"sigma_range_m": 20.0, "sigma_azimuth_deg": 0.2}
    m, rule = per_track_filter("ekf", sensor, 2, False, 2.5)
    assert rule == "levels" and isinstance(m.filter, NoiseLevels)
    assert m.filter.flt.config.q == pytest.approx(noise_levels(2.5)[0])
    assert m.filter.extra[1] == pytest.approx(noise_levels(2.5)[1] - noise_levels(2.5)[0])
    assert m.filter.flt.R[0, 0] == pytest.approx(400.0)  # the sensor keys reach the filter
    m, rule = per_track_filter("ekf", {"q": 0.7, "sensor": {"sigma_range_m": 5.0}}, 3, True, 2.5)
    assert rule == "given" and isinstance(m.filter, EKF) and m.filter.config.q == 0.7
    assert m.filter.d == 3 and m.filter.R[0, 0] == pytest.approx(25.0)


def test_methods_with_their_own_manoeuvre_handling_keep_their_defaults():
    m, rule = per_track_filter("imm", {}, 2, False, 2.5)
    assert rule == "own" and isinstance(m.filter, CVCTIMM)
    m, rule = per_track_filter("huber", {}, 3, False, 2.5)
    assert rule == METHODS["huber"].noise and m.horizontal  # 2-D method on 3-D plots
    m, rule = per_track_filter("imm", {"q_ct": 1.0}, 2, False, 2.5, rule="wrap")
    assert rule == "given" and isinstance(m.filter, CVCTIMM)


def test_bad_rules_and_keys_are_errors():
    with pytest.raises(ValueError, match="has no q"):
        per_track_filter("imm", {}, 2, False, 2.5, rule="levels")
    with pytest.raises(ValueError, match="noise rule"):
        per_track_filter("ekf", {}, 2, False, 2.5, rule="auto")
    with pytest.raises(ConfigError, match="bogus"):
        per_track_filter("ekf", {"bogus": 1}, 2, False, 2.5)
    with pytest.raises(ValueError, match="range_rate"):
        per_track_filter("mm-rangerate", {}, 2, False, 2.5)


def test_user_gave_noise():
    assert user_gave_noise({"q": 1.0}) and user_gave_noise({"sigma_a": 0.1})
    assert not user_gave_noise({"sigma_range_m": 10.0, "sensor": {}})
    assert not np.any([user_gave_noise({k: 1}) for k in ("p_stay", "initial_speed_sigma_mps")])
