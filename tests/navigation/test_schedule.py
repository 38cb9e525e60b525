"""Scheduler: next landmark by antenna angle and the JUMP counters (patent example)."""

from __future__ import annotations

import numpy as np

from seatrack.navigation.schedule import ScheduleConfig
from seatrack.navigation.schedule import next_landmark

D = np.radians


def test_patent_5_vs_11_degrees():
    # window indices 0..5 at B1 (R7..R12); index 1 (R8) just processed at 110 deg;
    # index 0 (R7) 5 deg further on: closer than gate width + margin = 11 deg
    th = D(np.array([115.0, 110.0, 300.0, 185.0, 250.0, 20.0]))
    ok = np.ones(6, bool)
    ch = next_landmark(th, ok, np.zeros(6, int), processed=1)
    assert ch.jump.tolist() == [0, 1, 0, 0, 0, 0]  # JUMP1 = 1, JUMP0 stays 0
    assert ch.index == 3  # R10, 75 deg > 11 deg
    np.testing.assert_allclose(np.degrees(ch.gap), 75.0)


def test_landmarks_in_line_alternate_between_revolutions():
    # only two landmarks, 5 deg apart: each served on alternate revolutions
    th = D(np.array([115.0, 110.0]))
    ok = np.ones(2, bool)
    jump = np.zeros(2, int)
    served, cur, turned = [], 1, 0.0
    for _ in range(6):
        ch = next_landmark(th, ok, jump, processed=cur)
        jump, cur = ch.jump, ch.index
        turned += ch.gap
        served.append(cur)
    assert served == [0, 1, 0, 1, 0, 1]
    # every service waits more than one revolution for the in-line partner
    assert np.degrees(turned) > 360.0 * 5


def test_start_and_jump_decrement():
    th = D(np.array([30.0, 60.0, 200.0]))
    ok = np.array([True, True, True])
    cfg = ScheduleConfig()
    # antenna at 10 deg: s = 10 + 11 = 21 deg; first reachable is index 0
    ch = next_landmark(th, ok, np.zeros(3, int), None, D(10.0), cfg)
    assert ch.index == 0
    np.testing.assert_allclose(np.degrees(ch.gap), 9.0)
    # a landmark with JUMP = 2 is skipped (and decremented) when passed
    ch = next_landmark(th, ok, np.array([2, 0, 0]), None, D(10.0), cfg)
    assert ch.index == 1 and ch.jump.tolist() == [1, 0, 0]
    # ineligible landmarks are never chosen
    ch = next_landmark(th, np.array([False, False, True]), np.zeros(3, int), None, D(10.0), cfg)
    assert ch.index == 2
    ch = next_landmark(th, np.zeros(3, bool), np.zeros(3, int), None, 0.0, cfg)
    assert ch.index == -1
