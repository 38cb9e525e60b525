"""Echo gate, weights p = g/(g+b), weighted measurement, P_min rule, missed landmarks."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from seatrack.navigation.echoes import GateConfig
from seatrack.navigation.echoes import adaptive_half_angle
from seatrack.navigation.echoes import echo_weights
from seatrack.navigation.echoes import gate_mask
from seatrack.navigation.echoes import local_offsets
from seatrack.navigation.echoes import weighted_measurement

S = np.diag([3.5**2 + 25.0, 10.0**2 + 25.0])  # echo spread + h A h^T, m^2
R_C = 1000.0


def _gate_points(rng, density, half_r, half_t):
    area = 4 * half_r * half_t
    k = rng.poisson(density * area)
    return np.column_stack([rng.uniform(-half_r, half_r, k), rng.uniform(-half_t, half_t, k)])


@pytest.mark.parametrize("density", [1e-5, 1e-4, 1e-3])
def test_gate_evenly_filled_with_clutter_gives_no_update(density):
    cfg = replace(GateConfig(), clutter_density=density)
    half = adaptive_half_angle(R_C, S, [0.0, 1.0], cfg)
    w = np.array([cfg.range_half_width, R_C * half])
    step = 1.0 / np.sqrt(density)  # one false echo per 1/b square metres
    zr = np.arange(-w[0] + step / 2, w[0], step)
    zt = np.arange(-w[1] + step / 2, w[1], step)
    z = np.array([(a, b) for a in zr for b in zt]).reshape(-1, 2)
    st = weighted_measurement(z, echo_weights(z, S, density, cfg.expected_echoes), w, cfg)
    assert not st.updated


@pytest.mark.parametrize(("density", "max_rate"), [(1e-5, 0.0), (1e-4, 0.01), (1e-3, 0.01)])
def test_random_clutter_only_gates_rarely_update(density, max_rate):
    # Poisson clutter can put two false echoes next to the prediction; the method then
    # takes them for the landmark unless the presence test rejects them.
    cfg = replace(GateConfig(), clutter_density=density)
    half = adaptive_half_angle(R_C, S, [0.0, 1.0], cfg)
    w = np.array([cfg.range_half_width, R_C * half])
    rng = np.random.default_rng(2024)
    updated = 0
    for _ in range(500):
        z = _gate_points(rng, density, *w)
        st = weighted_measurement(z, echo_weights(z, S, density, cfg.expected_echoes), w, cfg)
        updated += st.updated
    assert updated <= max_rate * 500


def test_single_clutter_echo_at_the_prediction_gives_no_update():
    cfg = GateConfig()
    z = np.array([[0.0, 0.0]])
    p = echo_weights(z, S, cfg.clutter_density, cfg.expected_echoes)
    assert p[0] > 0.99  # it looks exactly like the landmark...
    st = weighted_measurement(z, p, [48.0, 87.0], cfg)
    assert not st.updated  # ...but one echo is not enough (sum p < min_weight_sum)


def test_true_echoes_in_clutter_are_found():
    cfg = replace(GateConfig(), clutter_density=1e-4)
    rng = np.random.default_rng(5)
    half = adaptive_half_angle(R_C, S, [0.0, 1.0], cfg)
    w = np.array([cfg.range_half_width, R_C * half])
    truth = np.array([6.0, -9.0])
    errs = []
    for _ in range(200):
        true = truth + rng.normal(0, [3.5, 10.0], (8, 2))
        z = np.vstack([true, _gate_points(rng, 1e-4, *w)])
        st = weighted_measurement(z, echo_weights(z, S, 1e-4, cfg.expected_echoes), w, cfg)
        assert st.updated and np.all(st.var > 0)
        errs.append(st.z - truth)
    e = np.asarray(errs)
    # unbiased to within the Monte-Carlo error and far better than the gate size
    assert np.all(np.abs(e.mean(axis=0)) < 3 * e.std(axis=0) / np.sqrt(len(e)) + 0.5)
    assert np.all(np.sqrt(np.mean(e**2, axis=0)) < [3.0, 8.0])


def test_weighted_statistics_and_uniform_correction():
    z = np.array([[1.0], [3.0], [5.0]])
    p = np.array([1.0, 1.0, 2.0])
    cfg = replace(GateConfig(), min_weight_sum=1.0, min_sigma=0.0, min_log_lr=-np.inf)
    st = weighted_measurement(z, p, [40.0], cfg)
    zm = (1 + 3 + 10) / 4.0
    m2 = (1 + 9 + 50) / 4.0
    assert st.z[0] == pytest.approx(zm)
    assert 1.0 / st.var[0] == pytest.approx(1.0 / (m2 - zm**2) - 3.0 / 40.0**2)
    raw = weighted_measurement(z, p, [40.0], replace(cfg, uniform_correction=False))
    assert raw.var[0] == pytest.approx(m2 - zm**2)
    # a spread as wide as a uniform gate: refined precision <= 0 -> missed
    wide = np.linspace(-40, 40, 41)[:, None]
    assert not weighted_measurement(wide, np.ones(41), [40.0], cfg).updated


def test_presence_log_likelihood_ratio():
    cfg = GateConfig()
    z = np.array([[0.0, 0.0], [2.0, -3.0], [40.0, 80.0]])
    b, n_true = cfg.clutter_density, cfg.expected_echoes
    p = echo_weights(z, S, b, n_true)
    st = weighted_measurement(z, p, [48.0, 100.0], replace(cfg, min_log_lr=-np.inf))
    Si = np.linalg.inv(S)
    g = n_true * np.exp(-0.5 * np.einsum("ki,ij,kj->k", z, Si, z))
    g /= 2 * np.pi * np.sqrt(np.linalg.det(S))
    assert st.log_lr == pytest.approx(np.sum(np.log1p(g / b)) - n_true, rel=1e-9)
    # three false echoes next to a very uncertain prediction: sum p >= 2 but not a landmark
    big = S + np.diag([80.0**2, 80.0**2])
    z2 = np.array([[3.0, -20.0], [-10.0, 15.0], [5.0, 5.0]])
    p2 = echo_weights(z2, big, b, n_true)
    assert p2.sum() > cfg.min_weight_sum
    st2 = weighted_measurement(z2, p2, [48.0, 170.0], cfg)
    assert not st2.updated and st2.log_lr < cfg.min_log_lr
    # six echoes of the landmark there: accepted
    z6 = np.array([[1.0, 2.0], [-2.0, 5.0], [0.0, -6.0], [3.0, 1.0], [-1.0, -2.0], [2.0, 8.0]])
    assert weighted_measurement(z6, echo_weights(z6, big, b, n_true), [48.0, 170.0], cfg).updated


def test_weights_follow_g_over_g_plus_b():
    z = np.array([[0.0, 0.0], [10.0, 30.0]])
    b = 1e-4
    p = echo_weights(z, S, b, 5.0)
    Si = np.linalg.inv(S)
    g = (
        5.0
        * np.exp(-0.5 * np.einsum("ki,ij,kj->k", z, Si, z))
        / (2 * np.pi * np.sqrt(np.linalg.det(S)))
    )
    np.testing.assert_allclose(p, g / (g + b), rtol=1e-12)


def test_adaptive_half_angle_pmin_rule():
    cfg = GateConfig()
    half = adaptive_half_angle(R_C, S, [0.0, 1.0], cfg)
    assert cfg.min_half_angle < half < cfg.max_half_angle
    p_edge = echo_weights(
        np.array([[0.0, R_C * half]]), S, cfg.clutter_density, cfg.expected_echoes
    )
    assert p_edge[0] == pytest.approx(cfg.p_min, rel=1e-9)
    # a very uncertain prediction needs the full 10 deg
    assert adaptive_half_angle(R_C, S * 1e4, [0.0, 1.0], cfg) == cfg.max_half_angle
    # dense clutter narrows the gate
    dense = adaptive_half_angle(R_C, S, [0.0, 1.0], replace(cfg, clutter_density=1e-2))
    assert dense < half


def test_local_offsets_polar_and_cartesian():
    heading, th_c, r_c = np.radians(20.0), np.radians(75.0), 1500.0
    phi_c = th_c - heading
    r = np.array([1500.0, 1512.0, 1490.0])
    phi = phi_c + np.radians([0.0, 0.5, -1.0])
    cart = local_offsets(r, phi, r_c, th_c, phi_c, heading)
    pol = local_offsets(r, phi, r_c, th_c, phi_c, heading, polar=True)
    np.testing.assert_allclose(cart[0], [0.0, 0.0], atol=1e-9)
    # equal to first order: the difference is the curvature term r (1 - cos dphi)
    np.testing.assert_allclose(cart, pol, atol=0.5)
    assert pol[1, 1] > 0  # clockwise (larger bearing) is positive cross-range


def test_gate_mask():
    m = gate_mask([1000, 1049, 1000, 1000], np.radians([10, 10, 14.9, 5.0]), 1000.0,
                  np.radians(10.0), 48.0, np.radians(5.0))  # fmt: skip
    assert m.tolist() == [True, False, True, True]
