from dataclasses import replace

import numpy as np

from seatrack.filters.base import Plots
from seatrack.filters.registry import COMMON_COLUMNS
from seatrack.filters.registry import build
from seatrack.filters.registry import run
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory
from seatrack.simulate.files import plots_from_measurements


def _plots(meas, with_el=True, with_rr=True):
    pt = plots_from_measurements(meas)
    return replace(
        pt,
        elevation=pt.elevation if with_el else None,
        range_rate=pt.range_rate if with_rr else None,
    )


def run_ekf(plots: Plots, cfg: dict) -> tuple[np.ndarray, np.ndarray]:
    """States and covariances of one track, plot by plot through the contract."""
    m = build("ekf", cfg, d=plots.d, range_rate=plots.has_range_rate)
    f = m.filter
    first = plots.take([0])
    s = f.initiate(first.t, *m.initiate(first))
    xs, Ps = [s.x[0]], [s.P[0]]
    for k in range(1, len(plots)):
        pk = plots.take([k])
        s = f.update(f.predict(s, pk.t), pk)
        xs.append(s.x[0])
        Ps.append(s.P[0])
    return np.array(xs), np.array(Ps)


def test_ekf_3d_with_range_rate_is_consistent_on_straight_target():
    tr = trajectory([20000.0, 15000.0, 3000.0], np.radians(250), 200.0, [Leg.straight(300)], dt=2.0)
    sig = [30.0, np.radians(0.3), np.radians(0.3), 1.0]
    # the truth is exactly straight, so a consistent filter needs (almost) no process noise
    cfg = {
        "q": 1e-6,
        "sigma_range_m": 30.0,
        "sigma_azimuth_deg": 0.3,
        "sigma_elevation_deg": 0.3,
        "sigma_range_rate_mps": 1.0,
        "initial_speed_sigma_mps": 300.0,
    }
    nees = []
    for seed in range(30):
        m = observe(
            tr,
            None,
            ["range", "azimuth", "elevation", "range_rate"],
            NoiseModel(sig),
            np.random.default_rng(seed),
        )
        x, P = run_ekf(_plots(m), cfg)
        e = x - tr.state("cv3")
        nees.append(np.einsum("ki,kij,kj->k", e[50:], np.linalg.inv(P[50:]), e[50:]))
    anees = np.mean(nees)
    # 30 runs x 101 steps of a 6-dof chi-square (correlated in time): loose but two-sided
    assert 4.5 < anees < 8.0


def test_ekf_method_columns_and_2d():
    tr = trajectory([3000.0, 1000.0], np.radians(10), 8.0, [Leg.straight(200)], dt=5.0)
    own = trajectory([0.0, 0.0], np.radians(90), 5.0, [Leg.straight(200)], dt=5.0)
    m = observe(
        tr, own, ["range", "azimuth"], NoiseModel([5.0, np.radians(1.0)]), np.random.default_rng(0)
    )
    pt = _plots(m, with_el=False, with_rr=False)
    cols = run("ekf", pt, {"sigma_range_m": 5.0, "sigma_azimuth_deg": 1.0, "q": 1e-3})
    for c in (*COMMON_COLUMNS, "nis", "status"):
        assert cols[c].shape == (len(pt),)
    assert np.all(np.isnan(cols["z_m"]))  # 2-D plots: z columns empty
    err = np.hypot(cols["x_m"] - tr.pos[:, 0], cols["y_m"] - tr.pos[:, 1])
    raw = m.sensor_pos[:, :2] + m.z[:, :1] * np.stack([np.sin(m.z[:, 1]), np.cos(m.z[:, 1])], -1)
    raw_err = np.hypot(*(raw - tr.pos[:, :2]).T)
    half = len(pt) // 2
    assert np.sqrt(np.mean(err[half:] ** 2)) < 0.5 * np.sqrt(np.mean(raw_err[half:] ** 2))
