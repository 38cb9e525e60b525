"""Deletion by consecutive misses and covariance growth."""

import numpy as np

from seatrack.tracking.deletion import position_std
from seatrack.tracking.deletion import to_delete


def test_position_std_is_the_major_axis():
    P = np.zeros((2, 4, 4))
    P[0, :2, :2] = [[400.0, 0.0], [0.0, 100.0]]
    th = 0.3
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    P[1, :2, :2] = R @ np.diag([900.0, 1.0]) @ R.T
    assert np.allclose(position_std(P, 2), [20.0, 30.0])


def test_to_delete():
    P = np.repeat(np.eye(4)[None], 4, 0) * 100.0
    P[2, 0, 0] = 2000.0**2
    P[3, 1, 1] = np.nan
    misses = np.array([0, 5, 0, 0])
    assert to_delete(misses, P, 2, 5, 1000.0).tolist() == [False, True, True, True]
