"""Map survey: landmark corrections from a recorded passage, poorly visible landmarks."""

from __future__ import annotations

import numpy as np

from seatrack.navigation.navigator import AuxData
from seatrack.navigation.navigator import Echoes
from seatrack.navigation.navigator import NavigatorConfig
from seatrack.navigation.navigator import navigate
from seatrack.navigation.survey import SurveyConfig
from seatrack.navigation.survey import survey
from seatrack.simulate.radar_echoes import EchoEnvironment
from seatrack.simulate.radar_echoes import channel_landmarks
from seatrack.simulate.radar_echoes import river_route
from seatrack.simulate.radar_echoes import simulate_radar

ROUTE = river_route(2000.0, 4.0)
TRUE = channel_landmarks(ROUTE, 8, np.random.default_rng(1))


def _pass(nav_map, true_map, seed, map_sigma):
    rng = np.random.default_rng(seed)
    sim = simulate_radar(ROUTE, true_map, rng, env=EchoEnvironment(), nav_map=nav_map)
    gt = np.arange(0.0, ROUTE.t[-1], 1.0)
    tr = np.column_stack([np.interp(gt, sim.truth_t, sim.truth[:, i]) for i in range(2)])
    aux = AuxData(gnss=(gt, tr + rng.normal(0.0, 5.0, tr.shape)))
    e = sim.echoes
    return navigate(
        nav_map,
        Echoes(e.t, e.antenna, e.range),
        sim.truth[0],
        NavigatorConfig(map_sigma=map_sigma),
        gyro=(sim.gyro_t, sim.gyro_rate),
        aux=aux,
        t0=0.0,
    )


def test_displaced_point_reflector_is_corrected():
    j = int(np.flatnonzero(~TRUE.is_contour)[1])
    wrong = TRUE.xy.copy()
    wrong[j] += [30.0, -25.0]
    nav_map = TRUE.with_xy(wrong)
    res = _pass(nav_map, TRUE, 4, 20.0)
    sv = survey(nav_map, [res])
    before = np.hypot(*(nav_map.xy[j] - TRUE.xy[j]))
    after = np.hypot(*(sv.corrected.xy[j] - TRUE.xy[j]))
    assert after < 0.3 * before
    # the correct landmarks move little
    others = np.delete(np.arange(len(TRUE)), j)
    assert np.all(np.hypot(*sv.correction[others].T) < 8.0)
    assert sv.n_records[j] > 20


def test_contour_element_is_corrected_along_its_normal_only():
    j = int(np.flatnonzero(TRUE.is_contour)[0])
    n = np.array([np.sin(TRUE.normal[j]), np.cos(TRUE.normal[j])])
    wrong = TRUE.xy.copy()
    wrong[j] += 25.0 * n
    nav_map = TRUE.with_xy(wrong)
    sv = survey(nav_map, [_pass(nav_map, TRUE, 5, 20.0)])
    c = sv.correction[j]
    assert abs(c @ n + 25.0) < 8.0  # most of the normal error removed
    assert abs(c @ np.array([n[1], -n[0]])) < 1e-9  # nothing along the line


def test_poorly_visible_landmark_is_flagged_and_dropped():
    j = 3
    true = TRUE.with_xy(TRUE.xy + np.where(np.arange(len(TRUE))[:, None] == j, 5000.0, 0.0))
    res = _pass(TRUE, true, 6, 3.0)  # the map says j is there, but it gives no echo
    sv = survey(TRUE, [res], SurveyConfig(drop_poor=True))
    assert sv.poorly_visible[j]
    assert sv.visibility[j] < 0.1
    others = np.delete(sv.visibility, j)
    assert np.all(others > 0.3)  # (a bank edge seen at grazing angles may also be < 0.5)
    assert TRUE.ids[j] not in sv.corrected.ids.tolist()
    assert len(sv.corrected) == len(TRUE) - int(sv.poorly_visible.sum())
