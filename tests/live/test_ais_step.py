"""The compiled causal AIS step: initialisation, update, outliers, long gaps."""

from __future__ import annotations

import math

import numpy as np

from seatrack.filters.ais import OutlierKind
from seatrack.filters.ais.kernel import kernel_params
from seatrack.live.ais import causal_config
from seatrack.live.ais_step import ESTIMATE
from seatrack.live.ais_step import NO_ESTIMATE
from seatrack.live.ais_step import NX
from seatrack.live.ais_step import SCALARS
from seatrack.live.ais_step import causal_step
from seatrack.live.ais_step import param_array

NAN = math.nan


class Vessel:
    def __init__(self) -> None:
        self.par = kernel_params(causal_config())
        self.p = param_array(self.par)
        self.st = np.zeros(len(SCALARS))
        self.st[SCALARS.index("prev_t")] = NAN
        self.st[SCALARS.index("sog_t")] = -math.inf
        self.x, self.P, self.std = np.zeros(NX), np.zeros((NX, NX)), np.empty(NX)

    def step(self, t, x, y, vx=NAN, vy=NAN, sog=NAN, cog=NAN):
        return causal_step(self.p, self.st, self.x, self.P, t, x, y, vx, vy, sog, cog, self.std)


def test_first_report_initialises_a_segment():
    v = Vessel()
    status, kind, nis = v.step(100.0, 10.0, 20.0, 3.0, 4.0, 5.0, math.atan2(3.0, 4.0))
    assert status == ESTIMATE and kind == 0 and math.isnan(nis)
    np.testing.assert_array_equal(v.x, [10.0, 20.0, 3.0, 4.0, 0.0])
    assert v.st[SCALARS.index("segment")] == 1
    assert v.std[0] == v.par.sigma_pos


def test_update_moves_towards_the_report_and_keeps_p_symmetric_pd():
    v = Vessel()
    v.step(0.0, 0.0, 0.0, 0.0, 5.0, 5.0, 0.0)
    status, kind, nis = v.step(10.0, 0.0, 51.0, 0.0, 5.0, 5.0, 0.0)
    assert status == ESTIMATE and kind == 0 and 0.0 <= nis < v.par.gate
    assert 50.0 < v.x[1] < 51.0
    np.testing.assert_allclose(v.P, v.P.T, rtol=0, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(v.P) > 0)


def test_implausible_jump_is_flagged_then_reinitialises():
    v = Vessel()
    v.step(0.0, 0.0, 0.0, 0.0, 5.0, 5.0, 0.0)
    v.step(10.0, 0.0, 50.0, 0.0, 5.0, 5.0, 0.0)
    kinds = [v.step(11.0 + k, 50_000.0, 50.0)[1] for k in range(v.par.reinit_after)]
    assert kinds[:-1] == [OutlierKind.IMPLAUSIBLE_JUMP] * (v.par.reinit_after - 1)
    assert kinds[-1] == 0 and v.x[0] == 50_000.0
    assert v.st[SCALARS.index("segment")] == 2


def test_implausible_jump_after_a_long_gap_gets_no_estimate():
    v = Vessel()
    v.step(0.0, 0.0, 0.0)
    status, _, _ = v.step(v.par.max_gap + 10.0, 1e9, 0.0)
    assert status == NO_ESTIMATE
    assert v.x[0] == 0.0


def test_stale_position_is_flagged():
    v = Vessel()
    v.step(0.0, 0.0, 0.0, 0.0, 5.0, 5.0, 0.0)
    v.step(10.0, 0.0, 50.0, 0.0, 5.0, 5.0, 0.0)
    _, kind, _ = v.step(40.0, 0.0, 50.0, 0.0, 5.0, 5.0, 0.0)  # same position, 5 m/s
    assert kind == OutlierKind.STALE_POSITION
