"""The registry's method names, the ``-spec`` scheme and the ``target`` key.

Each source method stays available exactly as its source describes under ``NAME-spec``
(tested here against the spec texts: the fuzzy vote raises Q only on the scan after it
fires, algorithm A injects P/3 and P/10, the patent's steps 1-11); the name without the
suffix is the best version of the idea. ``target`` is one shared key, parsed once, that
gives every method the process noise of a target class; keys beside it win.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from seatrack.config import ConfigError
from seatrack.filters import registry
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import plot_gaussian
from seatrack.filters.converted import convert_plots
from seatrack.filters.multimodel import DEFAULT_ALPHAS
from seatrack.filters.multimodel import MultiModelFilter
from seatrack.filters.multimodel import MultiModelState
from seatrack.filters.robust import robust_update
from seatrack.models.targets import AIRCRAFT
from seatrack.models.targets import FIGHTER
from seatrack.models.targets import SHIP
from seatrack.models.targets import TARGET_CLASSES
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory

SPEC = {
    "turning": "Turning",
    "robust": "Robust",
    "robust-adaptive": "RobustAdaptive",
    "mm": "MultiModel",
    "mm-rangerate": "MultiModelRangeRate",
}
CFG = {"sigma_range_m": 10.0, "sigma_azimuth_deg": 0.1}


def _turn_plots(rate_dps=3.0, dt=2.0, seed=5, range_rate=False):
    """An aircraft: 100 s straight, a 300 s steady turn at ``rate_dps``, straight again."""
    rng = np.random.default_rng(seed)
    legs = [
        Leg.straight(100.0),
        Leg.turn(math.radians(rate_dps * 300), math.radians(rate_dps)),
        Leg.straight(300.0),
    ]
    times = np.arange(0.0, 700.0, dt)
    tr = trajectory([8e3, 6e3], 1.0, 100.0, legs, times=times)
    comps = ("range", "azimuth", "range_rate") if range_rate else ("range", "azimuth")
    sig = [10.0, math.radians(0.1), 0.5][: len(comps)]
    m = observe(tr, None, comps, NoiseModel(sig), rng)
    rr = m.z[:, 2] if range_rate else None
    return Plots(tr.t, m.z[:, 0], m.z[:, 1], None, rr, m.sensor_pos, m.sensor_vel,
                 track=np.full(times.size, "a"))  # fmt: skip


def test_every_spec_method_has_its_own_name_and_a_default():
    for name, cls in SPEC.items():
        assert registry.METHODS[f"{name}-spec"].class_name == cls
        assert registry.METHODS[f"{name}-spec"].group == "reference"
        assert registry.METHODS[name].class_name != cls  # the default is the departure
    assert {n for n in registry.METHODS if n.endswith("-spec")} == {f"{n}-spec" for n in SPEC}
    assert set(registry.names("reference")) == {f"{n}-spec" for n in SPEC}


@pytest.mark.parametrize("name", list(registry.METHODS))
@pytest.mark.parametrize("target", list(TARGET_CLASSES))
def test_every_method_takes_every_target(name, target):
    m = registry.build(name, {"target": target, **CFG}, range_rate=True)
    assert m.filter.config != registry.build(name, CFG, range_rate=True).filter.config


@pytest.mark.parametrize("value", ["boat", 3, ["ship"], ""])
def test_bad_target_names_the_key_and_the_classes(value):
    with pytest.raises(ConfigError, match=r"cfg.toml: target: must be one of ship, submarine"):
        registry.build("ekf", {"target": value}, source="cfg.toml")


def test_unknown_key_lists_the_target_key():
    with pytest.raises(ConfigError, match=r"sensor keys: .*target"):
        registry.build("turning", {"q_level": 1.0})


def test_target_sets_the_class_values_and_keys_beside_it_win():
    c = registry.build("robust-adaptive", {"target": "aircraft"}).filter.config
    assert c.accel_levels == (AIRCRAFT.accel_steady, AIRCRAFT.accel_max)
    assert c.sojourn_times == (AIRCRAFT.straight_time, AIRCRAFT.manoeuvre_time)
    assert c.initial_speed_sigma == AIRCRAFT.speed_max
    c = registry.build("robust-adaptive", {"target": "aircraft", "initial_speed_sigma_mps": 7.0})
    assert c.filter.config.initial_speed_sigma == 7.0
    assert registry.build("ekf", {"target": "ship"}).filter.config.sigma_accel == SHIP.accel_typical
    c = registry.build("mm-spec", {"target": "fighter"}).filter.config
    assert c.accel == FIGHTER.accel_typical
    # the sensor section is untouched by a target
    assert registry.build("turning", {"target": "ship"}).filter.sensor == SensorNoise()


def test_without_a_target_the_level_methods_tune_themselves():
    for name in ("turning", "robust", "robust-adaptive", "huber", "student-t", "mm"):
        c = registry.build(name, {}).filter.config
        assert c.accel_levels == () and c.q_levels == (1e-4, 1e-2, 1.0, 1e2, 5e3), name


# ---------------------------------------------------------------------------
# turning-spec: CN 104407337 as written
# ---------------------------------------------------------------------------
def test_turning_spec_has_the_patents_parameters():
    c = registry.build("turning-spec", {}).filter.config
    assert c.q_heading == 1e-6 and c.turn_rate_threshold == 1.0
    assert c.delta_omega_threshold == pytest.approx(0.02)
    assert c.queue_length == 5 and c.count == 3  # M > 3, K = M - 2
    assert c.velocity_threshold is None  # d_t > N
    assert c.sigma_accel is None


def test_turning_spec_raises_q_only_on_the_scan_after_the_vote_fires():
    """S5: ``Q' = c Q_nom`` for the NEXT cycle only, nominal on every other scan -- also in
    a steady turn, where the vote fires only while the estimated turn rate changes."""
    plots = _turn_plots()
    out = registry.run("turning-spec", plots, {**CFG, "target": "aircraft"})
    fired = np.isin(out["turn_state"], ["rising", "falling"])
    raised = out["q_gain"] > 1.0
    assert np.array_equal(raised[1:], fired[:-1])
    t = plots.t
    assert raised[(t > 100) & (t < 400)].any()
    assert not raised[(t > 20) & (t < 100)].any() and not raised[t > 500].any()
    # in the steady turn the spec's Q falls back to nominal again and again (it is not kept
    # raised while the target turns -- what the default changes)
    steady = raised[(t > 140) & (t < 400)]
    assert np.count_nonzero(steady[:-1] & ~steady[1:]) >= 3 and not steady.all()


def test_turning_default_keeps_the_turn_decision_through_a_steady_turn():
    plots = _turn_plots()
    out = registry.run("turning", plots, {**CFG, "target": "aircraft"})
    t, p = plots.t, out["p_manoeuvre"]
    assert np.mean(p[(t > 120) & (t < 400)] > 0.5) > 0.9
    assert np.mean(p[(t > 20) & (t < 100)] < 0.1) > 0.9 and np.mean(p[t > 450] < 0.1) > 0.9
    # the heading filter's turn rate still comes out (3 deg/s in the turn)
    assert np.median(out["turn_rate_dps"][(t > 200) & (t < 400)]) == pytest.approx(3.0, abs=0.3)
    assert {"speed_mps", "heading_deg", "turn_state", "turn_rate_std_dps"} <= set(out)


# ---------------------------------------------------------------------------
# robust-spec, robust-adaptive-spec: Ramazanov as written
# ---------------------------------------------------------------------------
def test_robust_adaptive_spec_injects_p_over_3_and_p_over_10():
    f = registry.build("robust-adaptive-spec", {"sigma_range_m": 1.5}).filter
    c = f.config
    assert (c.l_factor_range, c.l_factor_bearing, c.window) == (3.0, 10.0, 3)
    rng = np.random.default_rng(0)
    B, k = 4, f.k
    A = rng.normal(size=(B, 2, k, k))
    P0 = A @ np.swapaxes(A, -1, -2) + np.eye(k)
    Pc_prev = 2.0 * P0
    innov = np.array([[30.0, 30.0], [0.1, 0.1], [30.0, 0.1], [0.1, 30.0]])
    jwin = np.full((B, 2, c.window), 3.84)  # a run of large J before: diverging
    jwin[1] = 0.0
    jwin[2, 1] = 0.0
    jwin[3, 0] = 0.0
    Xp = np.zeros((B, 2, k))
    _, info = robust_update(Xp, P0, Pc_prev, np.zeros(B), np.full(B, 900.0), innov, jwin,
                            f.model, c, True)  # fmt: skip
    expect = np.array([[True, True], [False, False], [True, False], [False, True]])
    assert np.array_equal(info.adapting, expect)
    for b in range(B):
        for ch, lf in enumerate((3.0, 10.0)):
            want = P0[b, ch] + (Pc_prev[b, ch] / lf if expect[b, ch] else 0.0)
            assert np.allclose(info.P_pred[b, ch], want)


def test_robust_spec_is_algorithm_r_with_the_chi2_threshold():
    f = registry.build("robust-spec", {}).filter
    assert type(f).adaptive is False
    assert (f.config.delta_range, f.config.delta_bearing) == (3.84, 3.84)


# ---------------------------------------------------------------------------
# mm-spec, mm-rangerate-spec: JP H06-95138 as written (steps 1-11)
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["mm-spec", "mm-rangerate-spec"])
def test_mm_spec_runs_the_patents_eleven_steps(name):
    """The registry's method equals :class:`MultiModelFilter` (whose compiled steps 1-11
    tests/filters/test_multimodel.py checks against the spec written out) on the plots
    converted as the method converts them, with the embodiment's hypotheses."""
    plots = _turn_plots(rate_dps=6.0, range_rate=True)
    sensor = SensorNoise(10.0, math.radians(0.1), sigma_range_rate=0.5)
    cfg = {**CFG, "sigma_range_rate_mps": 0.5}
    out = registry.run(name, plots, cfg)
    m = registry.build(name, cfg, range_rate=True).filter
    assert np.allclose(m.mm.alphas, np.asarray(DEFAULT_ALPHAS)[:, :2])
    assert m.mm.config.p_stay == 0.9
    cm = convert_plots(plots.range, plots.azimuth, None, 10.0, math.radians(0.1),
                       method="unbiased")  # fmt: skip
    # the same start as the method: the one initiator on the first plot
    x0, P0 = plot_gaussian(plots.take([0]), sensor, m.config.initial_speed_sigma, m.range_rate)
    start = MultiModelState(x0[0], P0[0], m.mm.config.prior_vector())
    ref = MultiModelFilter(m.mm.config, d=2).run(
        plots.t, cm.z, cm.R, plots.range_rate if m.range_rate else None, initial=start
    )
    assert np.allclose(out["x_m"][1:], ref.x[1:, 0], rtol=1e-9, atol=1e-6)
    assert np.allclose(out["vy_mps"][1:], ref.x[1:, 3], rtol=1e-9, atol=1e-6)
    beta = np.stack([out[f"p_{n}"] for n in m.mm.names], -1)
    assert np.allclose(beta[1:], ref.beta[1:], atol=1e-9)


def test_mm_rangerate_default_uses_range_rate_in_the_update():
    m = registry.build("mm-rangerate", {}, range_rate=True).filter
    assert m.range_rate and m.config.q_ct == 1000.0
    with pytest.raises(ValueError, match="range_rate"):
        registry.build("mm-rangerate", {}, range_rate=False)


def test_a_target_preset_is_a_config_of_the_method():
    """``target`` is only a shorthand: the preset equals the keys it stands for."""
    for name in registry.METHODS:
        cls = registry.method_class(name)
        pre = cls.Config.for_target(SHIP)
        assert dataclasses.is_dataclass(pre) and isinstance(pre, cls.Config), name


def test_a_record_checks_its_group_and_noise_rule():
    rec = registry.METHODS["ekf"]
    assert rec.config is rec.load().Config and rec.path == "seatrack.filters.ekf.EKF"
    with pytest.raises(ValueError, match="group"):
        registry.MethodRecord("x", "m", "C", "d", "w", group="favourite")
    with pytest.raises(ValueError, match="noise"):
        registry.MethodRecord("x", "m", "C", "d", "w", noise="auto")
    with pytest.raises(ValueError, match="unknown method 'nope'"):
        registry.record("nope")
    groups = [registry.names(g) for g in registry.GROUPS]
    assert sorted(sum(groups, [])) == sorted(registry.METHODS) and all(groups)


def _noise_fields(name: str) -> list[tuple[str, str, str]]:
    """``(method, field, key)`` of every bounded sigma / q field of a method's Config."""
    config = registry.method_class(name).Config
    return [
        (name, f.name, str(f.metadata.get("key") or f.name))
        for f in dataclasses.fields(config)
        if f.init
        and f.metadata.get("min") is not None
        and isinstance(f.default, float)
        and ("sigma" in f.name or f.name == "q" or f.name.startswith("q_"))
    ]


NOISE_FIELDS = [row for name in registry.names() for row in _noise_fields(name)]


def test_every_method_has_a_checked_noise_field():
    assert {row[0] for row in NOISE_FIELDS} == set(registry.names())


@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf])
@pytest.mark.parametrize(("name", "field", "key"), NOISE_FIELDS)
def test_config_built_directly_rejects_bad_noise(name, field, key, bad):
    config = registry.method_class(name).Config
    with pytest.raises(ValueError, match=rf"\b{key}\b"):
        config(**{field: bad})


def test_track_index_and_compact_labels_keep_first_appearance_order():
    from seatrack.filters.registry import compact_labels
    from seatrack.filters.registry import track_index

    labels = np.array(["b", "a", "b", "c", "a"])
    codes, names = track_index(labels)
    assert codes.tolist() == [0, 1, 0, 2, 1] and names == ["b", "a", "c"]
    compact = compact_labels(labels)
    assert compact.dtype == object and compact.tolist() == labels.tolist()
    assert compact[0] is compact[2]
    assert track_index(np.array([3, 1, 3]))[1] == ["3", "1"]  # not text: as text
    assert track_index(np.array([], dtype=str))[0].size == 0
