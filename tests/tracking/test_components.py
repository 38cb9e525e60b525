"""The tracker's configuration (keys in their edge units from Python) and the track
managers' rules on hand-made track tables."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from seatrack.config import ConfigError
from seatrack.tracking.components import JPDA
from seatrack.tracking.components import ExistenceManager
from seatrack.tracking.components import MofNManager
from seatrack.tracking.components import TrackerConfig
from seatrack.tracking.components import TrackStatus
from seatrack.tracking.existence import logit
from seatrack.tracking.initiators import TwoPointInitiator
from seatrack.tracking.tracks import TrackTable

KN = 1852.0 / 3600.0


def test_from_keys_takes_the_unit_suffixed_keys():
    cfg = TrackerConfig.from_keys(
        max_speed_kn=30, initial_speed_sigma_kn=10, turn_rate_dps=2, mean_life_s=600,
        max_position_std_m=500, m_of_n=[4, 6],
    )  # fmt: skip
    assert cfg.max_speed == 30 * KN and cfg.initial_speed_sigma == 10 * KN
    assert cfg.turn_rate == pytest.approx(math.radians(2)) and cfg.mean_life == 600.0
    assert cfg.max_position_std == 500.0 and cfg.m_of_n == (4, 6)
    assert TrackerConfig.from_keys() == TrackerConfig()
    with pytest.raises(ConfigError, match="unknown key 'max_speed_mps'"):
        TrackerConfig.from_keys(max_speed_mps=10)
    with pytest.raises(ConfigError, match="max_speed_kn: must be >= 0.001"):
        TrackerConfig.from_keys(max_speed_kn=-5)


def _table(
    p: list[float], confirmed: list[bool], hits: list[int], age: list[int], misses: list[int]
) -> TrackTable:
    n = len(p)
    return TrackTable(
        np.arange(1, n + 1), logit(np.array(p)), np.array(confirmed), np.array(hits),
        np.array(age), np.array(misses),
    )  # fmt: skip


def test_existence_manager_reports_and_deletes_by_existence():
    m = ExistenceManager(confirm=0.7, delete=0.05, max_position_std_m=100.0)
    tr = _table([0.9, 0.5, 0.01, 0.95], [False] * 4, [2] * 4, [2] * 4, [0] * 4)
    status = m.status(tr, np.array([True, True, False, False]))
    assert status.tolist() == [TrackStatus.CONFIRMED, TrackStatus.TENTATIVE,
                               TrackStatus.TENTATIVE, TrackStatus.COASTING]  # fmt: skip
    assert tr.confirmed.tolist() == [True, False, False, True]
    P = np.tile(np.eye(4) * 50.0**2, (4, 1, 1))
    P[3, :2, :2] = np.eye(2) * 200.0**2  # too uncertain
    assert m.survivors(tr, P, 2, 0.9).tolist() == [True, True, False, False]
    with pytest.raises(ValueError, match="delete < confirm"):
        ExistenceManager(confirm=0.3, delete=0.4)


def test_m_of_n_manager_confirms_and_deletes_by_counts():
    m = MofNManager(3, 4, max_misses=2)
    tr = _table([0.5] * 4, [False, False, False, True], [3, 2, 2, 5], [3, 3, 4, 9], [0, 1, 2, 2])
    status = m.status(tr, np.array([True, False, False, False]))
    assert status.tolist() == [TrackStatus.CONFIRMED, TrackStatus.TENTATIVE,
                               TrackStatus.TENTATIVE, TrackStatus.COASTING]  # fmt: skip
    P = np.tile(np.eye(4), (4, 1, 1))
    # 2 hits in 4 scans: 3 of 4 is out of reach; the confirmed track missed 2 in a row
    assert m.survivors(tr, P, 2, 0.9).tolist() == [True, True, False, False]
    auto = MofNManager(3, 4)
    assert auto.max_misses(0.9) == 3  # Pd 0.9: three misses in a row, probability 0.001
    assert auto.max_misses(0.5) == math.ceil(math.log(0.001) / math.log(0.5) - 1e-9)
    with pytest.raises(ValueError, match="2 <= m <= n"):
        MofNManager(5, 3)


@pytest.mark.parametrize(
    ("build", "argument"),
    [
        (lambda: JPDA(prune=-0.1), "prune"),
        (lambda: JPDA(prune=math.nan), "prune"),
        (lambda: ExistenceManager(max_position_std_m=-1.0), "max_position_std_m"),
        (lambda: ExistenceManager(max_position_std_m=math.inf), "max_position_std_m"),
        (lambda: ExistenceManager(confirm=math.nan), "confirm"),
        (lambda: MofNManager(max_position_std_m=0.0), "max_position_std_m"),
        (lambda: MofNManager(max_position_std_m=math.nan), "max_position_std_m"),
        (lambda: MofNManager(m=math.nan), "m <= n"),
        (lambda: MofNManager(m=2.5, n=4), "m <= n"),
        (lambda: MofNManager(max_misses=0), "max_misses"),
        (lambda: MofNManager(max_misses=1.5), "max_misses"),
        (lambda: TwoPointInitiator(max_speed_kn=-1.0), "max_speed_kn"),
        (lambda: TwoPointInitiator(initial_speed_sigma_kn=math.nan), "initial_speed_sigma_kn"),
        (lambda: TwoPointInitiator(births_per_scan=-0.5), "births_per_scan"),
    ],
)
def test_role_constructors_reject_bad_numbers_naming_the_argument(build, argument):
    with pytest.raises(ValueError, match=re.escape(argument)):
        build()


def test_role_constructors_accept_whole_floats():
    assert (MofNManager(m=2.0, n=3.0, max_misses=4.0).max_misses(0.9)) == 4
