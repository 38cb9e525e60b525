"""Tests of seatrack.evaluate.tracking: Monte-Carlo comparison of track methods, the
position CRB of constant-velocity scenarios and the summary statistics."""

import numpy as np
import pytest

from seatrack.evaluate.montecarlo import MonteCarloResult
from seatrack.evaluate.tracking import compare_methods
from seatrack.evaluate.tracking import method_config
from seatrack.evaluate.tracking import position_crb
from seatrack.evaluate.tracking import run_methods
from seatrack.evaluate.tracking import summarize
from seatrack.evaluate.tracking import tracking_sensor
from seatrack.simulate.scenarios import bundled_scenario
from seatrack.simulate.scenarios import load_scenario
from seatrack.simulate.scenarios import parse_scenario

CV = {
    "duration_s": 120.0,
    "targets": [{"position_m": [4000.0, 9000.0], "course_deg": 150.0, "speed_mps": 10.0}],
    "sensors": [
        {
            "name": "radar",
            "type": "radar2d",
            "sigma": {"azimuth_deg": 0.3, "range_m": 20.0},
            "scan_period_s": 2.0,
            "platform": "fixed",
            "position_m": [0.0, 0.0],
        }
    ],
    # a nearly noise-free CV model with a vague velocity start: close to the efficient
    # (batch) estimator of a straight-line target
    "evaluate": {"ekf": {"q": 1e-6, "initial_speed_sigma_mps": 1000.0}},
}


def test_ekf_attains_the_cv_position_crb():
    sc = parse_scenario(CV, "cv.toml")
    crb = position_crb(sc)
    assert crb is not None and crb.shape == (1, 61)
    assert np.isnan(crb[0, 0]) and np.all(np.isfinite(crb[0, 1:]))
    assert np.all(np.diff(crb[0, 5:]) < 0)  # more plots, smaller bound (straight approach)
    res = compare_methods(sc, ["ekf"], runs=100, seed=4)
    (row,) = summarize(res, ["ekf"], skip=20, crb=crb)
    assert 0.9 < row["rmse_over_crb"] < 1.1
    assert row["failures"] == 0


def test_unknown_method_in_evaluate_table_is_an_error():
    doc = dict(CV, evaluate={"ekff": {"q": 1.0}})
    with pytest.raises(ValueError, match=r"cv.toml: evaluate.ekff: no track method"):
        compare_methods(parse_scenario(doc, "cv.toml"), ["ekf"], runs=1, seed=0)


def test_position_crb_applies_only_to_cv_gaussian_scenarios():
    assert position_crb(load_scenario(bundled_scenario("demo"))) is None  # manoeuvres
    doc = dict(CV)
    doc["sensors"] = [dict(CV["sensors"][0], epsilon=0.1, outlier_scale=10.0)]
    assert position_crb(parse_scenario(doc, "eps.toml")) is None
    assert position_crb(load_scenario(bundled_scenario("linear_cv"))) is not None
    # a target starting on the sensor: the bearing (and its information) is undefined there;
    # no bound rather than a failed evaluation ("matrix has non-finite entries" before)
    doc = dict(CV, targets=[dict(CV["targets"][0], position_m=[0.0, 0.0])])
    sc = parse_scenario(doc, "on.toml")
    assert position_crb(sc) is None
    (row,) = summarize(compare_methods(sc, ["ekf"], runs=2, seed=1), ["ekf"], crb=None)
    assert row["failures"] == 0


def test_method_config_and_sensor_choice():
    sc = load_scenario(bundled_scenario("demo"))
    s = tracking_sensor(sc)
    assert s.name == "radar"
    cfg = method_config(sc, s, "ekf")
    assert cfg["sigma_range_m"] == pytest.approx(25.0)
    assert cfg["sigma_azimuth_deg"] == pytest.approx(0.4)
    assert cfg["sigma_range_rate_mps"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="passive"):
        tracking_sensor(sc, "sonar")
    with pytest.raises(ValueError, match="no active sensor"):
        tracking_sensor(load_scenario(bundled_scenario("tma_classic")))
    sc2 = parse_scenario(CV, "cv.toml")
    assert method_config(sc2, tracking_sensor(sc2), "ekf")["q"] == 1e-6


def test_every_method_accepts_the_sensor_keys_and_failures_are_reported(monkeypatch):
    """The sensor sigmas go to every registered method (each accepts SENSOR_KEYS);
    a method that raises is reported as a failed run, not fatal."""
    import seatrack.filters.registry as registry

    sc = load_scenario(bundled_scenario("demo"))
    s = tracking_sensor(sc)
    data = sc.simulate(np.random.default_rng(0)).sensor("radar")
    methods = list(registry.METHODS)
    cfg = {m: method_config(sc, s, m) for m in methods}
    assert set(registry.SENSOR_KEYS) - {"sigma_elevation_deg"} <= set(cfg["ekf"])
    out = run_methods(data, methods, cfg)
    for m in methods:
        assert all(not r.error for r in out[m]), (m, [r.error for r in out[m]])

    def broken(name, plots, config, source="config"):
        raise RuntimeError("boom")

    monkeypatch.setattr(registry, "run", broken)
    out = run_methods(data, ["broken"], {"broken": {}})
    assert all(r.error == "RuntimeError: boom" for r in out["broken"])


def test_summarize_statistics_by_hand():
    runs, targets, scans = 4, 1, 5
    pos = np.zeros((runs, targets, scans, 3))
    pos[..., 0] = 3.0
    pos[..., 1] = 4.0
    std = np.full((runs, targets, scans, 3), 2.0)
    vel = np.zeros_like(pos)
    vel[..., 0] = 1.0
    arrays = {
        "m/pos_err": pos,
        "m/vel_err": vel,
        "m/std": std,
        "m/seconds": np.full(runs, 0.01),
        "m/plots": np.full(runs, 10),
        "m/failed": np.zeros(runs, int),
    }
    (row,) = summarize(
        MonteCarloResult(arrays, runs, 0), ["m"], skip=1, crb=np.full((1, scans), 2.5)
    )
    assert row["pos_rmse_m"] == pytest.approx(5.0)
    assert row["vel_rmse_mps"] == pytest.approx(1.0)
    assert row["peak_pos_m"] == pytest.approx(5.0)
    assert row["anees_x"] == pytest.approx(9 / 4) and row["anees_y"] == pytest.approx(16 / 4)
    assert row["rmse_over_crb"] == pytest.approx(2.0)
    assert row["us_per_plot"] == pytest.approx(1e3)
    # 4-run 95 % bounds (1 dof) are [0.121, 2.786]: x (2.25) inside, y (4.0) outside
    assert row["in_bounds_pct"] == pytest.approx(50.0)


def test_evaluate_bound_is_below_every_method_within_monte_carlo_error():
    """linear_cv with the methods' velocity prior in the bound: RMSE/bound >= 1 for each
    method, up to three Monte-Carlo standard errors (fixed seed). Without the prior the
    range-bearing EKF is below the bound (the issue's 0.93)."""
    sc = load_scenario(bundled_scenario("linear_cv"))
    methods = ["ekf-rb", "robust-spec"]  # the two nearest the bound on linear_cv
    crb = position_crb(sc, None, methods)
    plain = position_crb(sc, None)
    assert np.nanmean(crb[:, 3:] ** 2) < np.nanmean(plain[:, 3:] ** 2)
    runs = 30
    res = compare_methods(sc, methods, runs=runs, seed=11)
    rows = summarize(res, methods, skip=3, crb=crb)
    for m, row in zip(methods, rows, strict=True):
        pe = res[f"{m}/pos_err"][..., 3:, :2]
        per_run = np.nanmean(np.sum(pe * pe, axis=-1), axis=(1, 2))  # (runs,)
        r = row["rmse_over_crb"]
        se = r * np.std(per_run, ddof=1) / np.mean(per_run) / np.sqrt(runs) / 2
        assert r >= 1.0 - 3.0 * se, (m, r, se)
