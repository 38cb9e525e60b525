"""Active window FIRST/NBR: the patent's example of Fig. 1 (landmarks R1..R14)."""

from __future__ import annotations

import numpy as np

from seatrack.navigation.window import Window
from seatrack.navigation.window import in_range
from seatrack.navigation.window import settle_window
from seatrack.navigation.window import step_window

N = 15  # order numbers 0..14; R1..R14 use 1..14


def vis(numbers) -> np.ndarray:
    v = np.zeros(N, bool)
    v[list(numbers)] = True
    return v


def test_b1_window_and_index():
    # at B1 only R7..R12 are in radar range: FIRST = 7, NBR = 6 - 1 = 5
    w = Window(7, 5)
    assert step_window(w, vis(range(7, 13))) == w
    assert w.index_of(9) == 2  # R9 has index 2 at B1 (7 + 2 = 9)
    assert w.indices().tolist() == [7, 8, 9, 10, 11, 12]


def test_b2_window_and_index():
    # at B2, R5 and R6 are added and R11, R12 dropped: FIRST = 5, NBR = 5
    w = settle_window(Window(7, 5), vis(range(5, 11)))
    assert w == Window(5, 5)
    assert w.index_of(9) == 4  # 5 + 4 = 9


def test_single_steps_of_the_patent_text():
    base = set(range(7, 13))
    # "if 6 was appropriate, FIRST = 6"; "if 7 was inappropriate, FIRST = 8"
    assert step_window(Window(7, 5), vis(base | {6})).first == 6
    assert step_window(Window(7, 5), vis(base - {7})).first == 8
    # "if 13 is appropriate NBR = 6"; "if 12 was inappropriate NBR = 4"
    assert step_window(Window(7, 5), vis(base | {13})) == Window(7, 6)
    assert step_window(Window(7, 5), vis(base - {12})) == Window(7, 4)
    # [reading] the upper end stays fixed when FIRST moves
    assert step_window(Window(7, 5), vis(base | {6})).last == 12
    # one step per revision: R5 is only reached on the next revision
    assert step_window(Window(7, 5), vis(base | {5, 6})) == Window(6, 6)


def test_empty_window_reseeds():
    w = step_window(Window(7, 5), np.zeros(N, bool))
    assert w.nbr < 0 or not np.any(np.zeros(N, bool)[w.indices()])
    w = settle_window(Window(0, -1), vis([3, 4, 5]))
    assert w == Window(3, 2)


def test_in_range():
    xy = np.array([[0.0, 2999.0], [0.0, 3001.0], [-100.0, 0.0]])
    assert in_range(xy, [0.0, 0.0], 3000.0).tolist() == [True, False, True]
