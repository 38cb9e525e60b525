"""Tests of seatrack.models.targets: the target classes and the suggested parameters."""

from __future__ import annotations

import dataclasses
import math
from importlib import resources

import numpy as np
import pytest

from seatrack.geometry import G0
from seatrack.models.targets import AIRCRAFT
from seatrack.models.targets import FIGHTER
from seatrack.models.targets import SHIP
from seatrack.models.targets import SUBMARINE
from seatrack.models.targets import TARGET_CLASSES
from seatrack.models.targets import cv_steady_state
from seatrack.models.targets import load_target_classes
from seatrack.models.targets import predicted_mse
from seatrack.models.targets import suggest_parameters
from seatrack.models.targets import target_class

DEG = math.pi / 180
KN = 1852.0 / 3600.0

#: the figures of the four classes as they were written in Python before they moved to
#: seatrack/data/target_classes.toml (field: ship, submarine, aircraft, fighter), computed
#: the same way: the bundled table must give them to the last bit
_FIGURES_BEFORE_THE_TABLE = {
    "speed_typical": (12 * KN, 8 * KN, 120.0, 250.0),
    "speed_max": (30 * KN, 33 * KN, 250.0, 600.0),
    "accel_steady": (0.01, 0.005, 0.1, 0.5),
    "accel_typical": (0.05, 0.04, 5.0, 4.0 * G0),
    "accel_max": (0.5, 0.3, G0 * math.tan(30 * DEG), 9.0 * G0),
    "accel_tangential": (0.05, 0.03, 1.0, G0),
    "turn_rate_typical": (0.5 * DEG, 0.5 * DEG, 3.0 * DEG, 4.0 * G0 / 250.0),
    "turn_rate_max": (3.0 * DEG, 2.0 * DEG, 3.0 * DEG, 9.0 * G0 / 250.0),
    "manoeuvre_time": (180.0, 120.0, 60.0, 15.0),
    "straight_time": (900.0, 1200.0, 240.0, 30.0),
    "turn_onset_time": (30.0, 30.0, 5.0, 1.0),
    "p_max_accel": (0.05, 0.05, 0.1, 0.1),
}


def test_four_classes_by_name_and_unknown_name() -> None:
    assert set(TARGET_CLASSES) == {"ship", "submarine", "aircraft", "fighter"}
    assert target_class("fighter") is FIGHTER
    with pytest.raises(ValueError, match="ship, submarine, aircraft, fighter"):
        target_class("frigate")


@pytest.mark.parametrize("tc", list(TARGET_CLASSES.values()), ids=list(TARGET_CLASSES))
def test_every_number_has_a_source(tc) -> None:
    numeric = [f.name for f in dataclasses.fields(tc) if isinstance(getattr(tc, f.name), float)]
    assert numeric and all(tc.sources[name].strip() for name in numeric)


def test_bundled_table_gives_the_figures_bit_for_bit() -> None:
    assert list(TARGET_CLASSES) == ["ship", "submarine", "aircraft", "fighter"]
    assert [SHIP, SUBMARINE, AIRCRAFT, FIGHTER] == list(TARGET_CLASSES.values())
    numeric = [f.name for f in dataclasses.fields(SHIP) if f.name not in ("name", "sources")]
    assert sorted(numeric) == sorted(_FIGURES_BEFORE_THE_TABLE)
    for field, values in _FIGURES_BEFORE_THE_TABLE.items():
        got = [getattr(c, field) for c in TARGET_CLASSES.values()]
        assert all(type(g) is float for g in got), field
        assert [g.hex() for g in got] == [float(v).hex() for v in values], field


def test_sources_cite_the_references_in_full() -> None:
    ship = SHIP.sources
    assert ship["turn_rate_typical"] == (
        "Cockcroft & Lameijer, Guide to the Collision Avoidance Rules, manoeuvring "
        "information: 90 deg in 2-3 min (0.5-0.75 deg/s)"
    )
    assert ship["p_max_accel"].startswith("assumption (no published figure found)")
    for tc in TARGET_CLASSES.values():
        assert not any("{" in s or "}" in s for s in tc.sources.values()), tc.name


def _bundled_toml() -> str:
    f = resources.files("seatrack") / "data" / "target_classes.toml"
    return f.read_text(encoding="utf-8")


def test_loading_the_bundled_file_again_gives_equal_classes(tmp_path) -> None:
    p = tmp_path / "classes.toml"
    p.write_text(_bundled_toml(), encoding="utf-8")
    again = load_target_classes(p)
    assert dict(again) == dict(TARGET_CLASSES)
    assert all(dict(again[n].sources) == dict(c.sources) for n, c in TARGET_CLASSES.items())


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "[ship.speed_max]\nkn = 30",
            "[ship.speed_max]\nmph = 30",
            r"ship\.speed_max: unknown key\(s\) mph \(the value goes under one unit key of kn, mps",
        ),
        ("[ship.speed_max]\nkn = 30", "[ship.speed_max]\nkn = 30\nmps = 3", "2 unit keys"),
        (
            "[ship.turn_rate_max]\ndps",
            "[ship.turn_rate_max]\nkn",
            "unknown key.*one unit key of dps, rad_s",
        ),
        ("[ship.p_max_accel]\nvalue = 0.05", "[ship.p_max_accel]\nvalue = '5 %'", "a number"),
        ("[ship.p_max_accel]\nvalue = 0.05", "[ship.p_max_accel]\nvalue = true", "a number"),
        (
            "[ship.p_max_accel]\nvalue = 0.05",
            "[ship.p_max_sway]\nvalue = 0.05",
            r"ship: unknown key\(s\) p_max_sway",
        ),
        (
            '[ship.p_max_accel]\nvalue = 0.05\nsource = "{ASSUMED}"',
            "",
            r"ship: missing key\(s\) p_max_accel",
        ),
        ("[ship.p_max_accel]\nvalue = 0.05", "[ship.p_max_accel]\nvalue = 0.6", "< 0.5"),
        ('source = "{ASSUMED}"', 'source = "{ASSUMD}"', "unknown reference {ASSUMD}"),
        ('source = "{SINGER}"', "sauce = 1", "manoeuvre_time: unknown key.*sauce"),
        ('source = "{SINGER}"', "", "manoeuvre_time: missing key\\(s\\) source"),
        ("[ship.speed_max]\nkn = 30", "[ship.speed_max]\nkn = 3", "speed_typical > speed_max"),
    ],
)
def test_a_bad_table_is_refused_naming_the_file_and_key(tmp_path, old, new, message) -> None:
    text = _bundled_toml()
    assert old in text
    p = tmp_path / "classes.toml"
    p.write_text(text.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(ValueError, match=message) as e:
        load_target_classes(p)
    assert str(e.value).startswith(f"{p}: ")


def test_unknown_and_missing_keys_of_a_class_are_named(tmp_path) -> None:
    p = tmp_path / "classes.toml"
    p.write_text("[boat]\nkeel = 1\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"boat: unknown key\(s\) keel"):
        load_target_classes(p)
    p.write_text("[references]\n", encoding="utf-8")
    with pytest.raises(ValueError, match="no target class"):
        load_target_classes(p)
    p.write_text("[ship\n", encoding="utf-8")
    with pytest.raises(ValueError, match=f"^{p}: "):
        load_target_classes(p)


def test_missing_source_or_inconsistent_numbers_are_rejected() -> None:
    src = dict(SHIP.sources)
    del src["turn_rate_max"]
    with pytest.raises(ValueError, match="no source for turn_rate_max"):
        dataclasses.replace(SHIP, sources=src)
    with pytest.raises(ValueError, match="accel_steady <= accel_typical"):
        dataclasses.replace(SHIP, accel_typical=1.0)
    with pytest.raises(ValueError, match="must be positive"):
        dataclasses.replace(SHIP, manoeuvre_time=0.0)


def test_classes_are_ordered_by_agility() -> None:
    order = [SUBMARINE, SHIP, AIRCRAFT, FIGHTER]
    acc = [c.accel_typical for c in order]
    assert acc == sorted(acc)
    assert AIRCRAFT.turn_rate_typical == pytest.approx(3 * DEG)  # standard-rate turn
    assert FIGHTER.accel_max == pytest.approx(9 * 9.80665)
    # typical lateral acceleration = typical turn rate x typical speed (within 25 %)
    for c in (SHIP, SUBMARINE, AIRCRAFT, FIGHTER):
        assert c.accel_typical == pytest.approx(c.turn_rate_typical * c.speed_typical, rel=0.25)


def test_derived_noise_parameters() -> None:
    T = 4.0
    assert AIRCRAFT.q_steady(T) < AIRCRAFT.q_manoeuvre(T) < AIRCRAFT.q_max(T)
    assert AIRCRAFT.q_manoeuvre(T) == pytest.approx(AIRCRAFT.accel_typical**2 * T)
    # Singer: sigma^2 = A^2/3 (1 + 4 Pmax - P0), P0 = straight fraction
    p0 = 1 - AIRCRAFT.manoeuvre_fraction
    s2 = AIRCRAFT.accel_max**2 / 3 * (1 + 4 * AIRCRAFT.p_max_accel - p0)
    assert AIRCRAFT.singer_sigma**2 == pytest.approx(s2)
    assert AIRCRAFT.singer_q == pytest.approx(2 * s2 / AIRCRAFT.singer_tau)
    # IMM persistence: mean sojourn time T / (1 - p) close to the class times for T << tau
    a, b = SHIP.p_stay(1.0)
    assert 1 / (1 - a) == pytest.approx(SHIP.straight_time, rel=0.01)
    assert 1 / (1 - b) == pytest.approx(SHIP.manoeuvre_time, rel=0.01)
    M = FIGHTER.transition_matrix(2.0)
    np.testing.assert_allclose(M.sum(1), 1.0)
    assert FIGHTER.q_turn_rate == pytest.approx(FIGHTER.turn_rate_typical**2 / 15.0)
    assert FIGHTER.q_turn_rate_onset == pytest.approx(FIGHTER.turn_rate_typical**2 / 1.0)
    assert AIRCRAFT.q_tangential(4.0) == pytest.approx(AIRCRAFT.accel_tangential**2 * 4.0)
    with pytest.raises(ValueError, match="dt must be a positive"):
        SHIP.q_steady(0.0)


def _simulate_cv_kf(q: float, sigma: float, T: float, accel: float, q_true: float, n: int):
    """Monte-Carlo of the one-axis CV KF: filtered position errors after convergence."""
    rng = np.random.default_rng(5)
    F = np.array([[1.0, T], [0.0, 1.0]])
    Q1 = np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
    g = np.array([T**2 / 2, T])
    H = np.array([1.0, 0.0])
    B = 4000
    x = np.zeros((B, 2))
    xh = np.zeros((B, 2))
    P = np.eye(2) * 1e4
    Lq = np.linalg.cholesky(q_true * Q1 + 1e-15 * np.eye(2))
    err = []
    for k in range(n):
        x = x @ F.T + g * accel + rng.standard_normal((B, 2)) @ Lq.T
        xh = xh @ F.T
        P = F @ P @ F.T + q * Q1
        S = P[0, 0] + sigma**2
        K = P[:, 0] / S
        z = x[:, 0] + sigma * rng.standard_normal(B)
        xh = xh + np.outer(z - xh[:, 0], K)
        P = P - np.outer(K, H @ P)
        if k > n - 20:
            err.append(xh[:, 0] - x[:, 0])
    return np.concatenate(err)


def test_steady_state_matches_monte_carlo() -> None:
    q, sigma, T = 2.0, 30.0, 2.0
    ss = cv_steady_state(q, sigma, T, q_true=q)
    e = _simulate_cv_kf(q, sigma, T, 0.0, q, 200)
    # a matched filter: noise variance is the steady-state filtered variance alpha sigma^2
    assert ss.noise_var == pytest.approx(ss.alpha * sigma**2, rel=1e-6)
    assert np.var(e) == pytest.approx(ss.noise_var, rel=0.05)
    # a constant acceleration through a noise-free filter: the lag
    e_acc = _simulate_cv_kf(q, 1e-9 + sigma, T, 3.0, 0.0, 300)
    assert np.mean(e_acc) == pytest.approx(ss.lag * 3.0, rel=0.05)
    assert ss.lag < 0  # the estimate trails an accelerating target


def test_suggestion_balances_noise_and_lag() -> None:
    s = suggest_parameters("aircraft", 4.0, 40.0, 0.08 * DEG, 30e3)
    assert s.q_steady < s.q_fixed < s.q_max
    sig = s.sigma_position
    best = predicted_mse(AIRCRAFT, s.q_fixed, sig, 4.0)
    for f in (0.3, 3.0):
        assert predicted_mse(AIRCRAFT, s.q_fixed * f, sig, 4.0) > best
    assert s.predicted_rmse == pytest.approx(math.sqrt(best))
    assert s.tracking_index_manoeuvre == pytest.approx(
        AIRCRAFT.accel_typical * 16 / max(sig), rel=1e-9
    )
    # a quieter sensor gives a smaller predicted error
    s2 = suggest_parameters("aircraft", 4.0, 10.0, 0.02 * DEG, 30e3)
    assert s2.predicted_rmse < s.predicted_rmse
    # a class that never manoeuvres wants the steady q (up to the search tolerance)
    calm = dataclasses.replace(SHIP, manoeuvre_time=1e-3, straight_time=1e9)
    s3 = suggest_parameters(calm, 2.5, 10.0, 0.3 * DEG, 5e3)
    assert s3.q_fixed == pytest.approx(calm.q_steady(2.5), rel=0.1)
