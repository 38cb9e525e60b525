"""The reference IMM methods (`imm`, `mm-rangerate`): the agile third model of
`mm-rangerate`, its class preset, and that `imm` keeps the two-model bank."""

from __future__ import annotations

import numpy as np
import pytest

from seatrack.filters import registry
from seatrack.filters.cvct_imm import CVCTIMMConfig
from seatrack.filters.cvct_imm import RangeRateIMMConfig
from seatrack.models.targets import FIGHTER
from seatrack.models.targets import SHIP
from seatrack.simulate.families import labelled_runs
from seatrack.simulate.families import weaving


@pytest.fixture(scope="module")
def weave_runs():
    """Four weaving fighters (straight first minute, then a 4 g zig-zag), radar with range
    rate."""
    return [weaving("fighter", 900_000 + k) for k in range(4)]


def test_imm_keeps_two_models_and_mm_rangerate_has_three():
    assert not CVCTIMMConfig().agile
    cfg = RangeRateIMMConfig()
    assert cfg.agile and cfg.q_agile > 0
    imm = registry.build("imm", {}, d=2, range_rate=True).filter
    rr = registry.build("mm-rangerate", {}, d=2, range_rate=True).filter
    assert len(imm.imm.models) == 2 and len(rr.imm.models) == 3
    # rows of the transition matrix are probabilities; the diagonal is p_stay
    T = rr.imm.transition
    np.testing.assert_allclose(T.sum(1), 1.0)
    np.testing.assert_allclose(np.diag(T), cfg.p_stay)


def test_q_agile_zero_gives_the_two_model_bank():
    rr = registry.build("mm-rangerate", {"q_agile": 0.0}, d=2, range_rate=True).filter
    assert len(rr.imm.models) == 2


@pytest.mark.parametrize("target", [FIGHTER, SHIP])
def test_class_preset_puts_the_agile_model_at_the_typical_manoeuvre(target):
    cfg = RangeRateIMMConfig.for_target(target)
    assert cfg.q_agile == 0.0 and cfg.sigma_accel_agile == target.accel_typical
    # the rest is the CV + CT preset of the class
    base = CVCTIMMConfig.for_target(target)
    assert (cfg.sigma_accel_cv, cfg.sigma_accel_ct, cfg.q_omega) == (
        base.sigma_accel_cv,
        base.sigma_accel_ct,
        base.q_omega,
    )
    assert not base.agile


def test_agile_probability_rises_when_the_target_weaves(weave_runs):
    """The agile model is the one a zig-zag selects: its probability over the weaving part
    is well above its probability on the straight first minute (the same tracks)."""
    plots = labelled_runs(weave_runs)
    cols = registry.run("mm-rangerate", plots, weave_runs[0].sensor_table())
    p = np.asarray(cols["p_agile"]).reshape(len(weave_runs), -1)
    total = (
        np.asarray(cols["p_cv"]) + np.asarray(cols["p_ct"]) + np.asarray(cols["p_agile"])
    ).reshape(p.shape)
    np.testing.assert_allclose(total, 1.0, atol=1e-9)
    t = weave_runs[0].plots.t
    straight = (t > 20.0) & ~weave_runs[0].manoeuvring
    weave = (t > 90.0) & weave_runs[0].manoeuvring
    assert p[:, weave].mean() > 2.0 * p[:, straight].mean()
    assert p[:, weave].mean() > 0.2


@pytest.mark.parametrize("method", ["imm", "mm-rangerate"])
def test_derived_conversions_give_the_same_update(weave_runs, method):
    """``derive`` (the driver converts every plot of a file once) changes nothing: an update
    on plots carrying the converted positions is the update that converts them itself."""
    from dataclasses import replace

    plots = labelled_runs(weave_runs)
    m = registry.build(method, {}, d=2, range_rate=True)
    flt = m.filter
    first, nxt = plots.take(np.arange(4)), plots.take(np.arange(4, 8))  # later plots
    x0, P0 = m.initiate(first)
    state = flt.predict(flt.initiate(first.t, x0, P0), nxt.t)
    plain = flt.update(state, nxt)
    with_derived = flt.update(state, replace(nxt, derived=flt.derive(nxt)))
    assert nxt.derived == {} and set(flt.derive(nxt)) >= {"z", "R"}
    for a, b in zip(plain.iter_arrays(), with_derived.iter_arrays(), strict=True):
        assert np.array_equal(a, b, equal_nan=True)
