"""The batched track driver: gross errors rejected, lost tracks started again."""

import math

import numpy as np
import pytest

from seatrack.filters import registry
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import plot_gaussian
from seatrack.filters.driver import GROSS_NIS
from seatrack.filters.driver import RESTART_AFTER
from seatrack.filters.driver import run_tracks
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig

SENSOR = SensorNoise(sigma_range=20.0, sigma_azimuth=math.radians(0.3))


def _plots(n_tracks=4, n=60, seed=1, jump=None):
    """Straight ships at 8-20 km, one plot every 2 s; ``jump=(track, k, dx)`` moves the
    plots of ``track`` from its ``k``-th on by ``dx`` metres east (another target)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 2.0
    rows, vels = [], []
    for j in range(n_tracks):
        p0 = rng.uniform(8e3, 20e3) * np.array([math.sin(j), math.cos(j)])
        v = rng.uniform(3, 10) * np.array([math.cos(j), -math.sin(j)])
        pos = p0 + t[:, None] * v
        if jump is not None and jump[0] == j:
            pos[jump[1] :, 0] += jump[2]
        rows.append(pos)
        vels.append(np.broadcast_to(v, pos.shape))
    pos, vel = np.concatenate(rows), np.concatenate(vels)
    rng_true = np.hypot(pos[:, 0], pos[:, 1])
    r = rng_true + SENSOR.sigma_range * rng.normal(size=len(pos))
    az = np.arctan2(pos[:, 0], pos[:, 1]) + SENSOR.sigma_azimuth * rng.normal(size=len(pos))
    rdot = np.einsum("ij,ij->i", pos, vel) / rng_true + rng.normal(size=len(pos))
    plots = Plots(np.tile(t, n_tracks), r, az % (2 * math.pi), range_rate=rdot)
    return plots, np.repeat(np.arange(n_tracks), n), pos


def _run(plots, ti, gate=math.inf, restart_after=RESTART_AFTER):
    flt = EKF(EKFConfig(q=0.01), SENSOR)
    init = lambda p: plot_gaussian(p, SENSOR, 20.0)  # noqa: E731
    return run_tracks(flt, plots, ti, init, gate=gate, restart_after=restart_after)


def _with_range(plots, idx, values, track=None):
    r = plots.range.copy()
    r[idx] = values
    return Plots(plots.t, r, plots.azimuth, range_rate=plots.range_rate, track=track)


def test_absurd_plots_are_rejected_and_leave_the_tracks_alone():
    plots, ti, _ = _plots()
    idx = np.array([10, 75, 140, 200])  # one absurd plot in every track
    bad = _with_range(plots, idx, [1e-3, 9e6, 1e-3, 9e6])
    clean = _run(plots, ti, GROSS_NIS)
    gated = _run(bad, ti, GROSS_NIS)
    ungated = _run(bad, ti)
    assert (gated["status"][idx] == "rejected").all() and (gated["nis"][idx] > GROSS_NIS).all()
    others = np.setdiff1d(np.arange(len(plots)), idx)
    assert (gated["status"][others] == clean["status"][others]).all()
    dev = np.hypot(gated["x_m"] - clean["x_m"], gated["y_m"] - clean["y_m"])[others]
    assert dev.max() < 3 * SENSOR.sigma_range  # one missing plot on a straight track
    drag = np.hypot(ungated["x_m"] - clean["x_m"], ungated["y_m"] - clean["y_m"])[others]
    assert drag.max() > 1e5  # without the gate the 9,000 km plot drags the track


def test_clean_plots_are_never_gated():
    plots, ti, _ = _plots()
    gated, plain = _run(plots, ti, GROSS_NIS), _run(plots, ti)
    for c in ("x_m", "y_m", "vx_mps", "std_x_m", "nis"):
        assert np.array_equal(gated[c], plain[c], equal_nan=True)
    assert (gated["status"] == plain["status"]).all()


def test_a_lost_track_starts_again_on_its_target():
    """Plots of track 1 jump 50 km from scan 30 on (another target under the same label):
    RESTART_AFTER gross errors, then the track restarts on the last one and follows."""
    n = 60
    plots, ti, truth = _plots(jump=(1, 30, 5e4), n=n)
    out = _run(plots, ti, GROSS_NIS)
    st = out["status"][n : 2 * n]
    k = 30 + RESTART_AFTER - 1
    assert (st[30:k] == "rejected").all() and st[k] == "initiated"
    assert (st[k + 1 :] == "updated").all()
    err = np.hypot(out["x_m"][n + k + 5 : 2 * n] - truth[n + k + 5 : 2 * n, 0],
                   out["y_m"][n + k + 5 : 2 * n] - truth[n + k + 5 : 2 * n, 1])  # fmt: skip
    assert err.max() < 200.0
    assert (out["status"][:n] != "rejected").all()  # the other tracks are untouched


def test_a_wild_first_plot_is_replaced_by_a_restart():
    plots, ti, truth = _plots(n=40)
    bad = _with_range(plots, [0], [9e6])  # track 0 starts 9,000 km away
    out = _run(bad, ti, GROSS_NIS, restart_after=2)
    assert list(out["status"][:4]) == ["initiated", "rejected", "initiated", "updated"]
    err = np.hypot(out["x_m"][10:40] - truth[10:40, 0], out["y_m"][10:40] - truth[10:40, 1])
    assert err.max() < 200.0


def test_restart_after_must_be_positive():
    plots, ti, _ = _plots(n_tracks=1, n=5)
    with pytest.raises(ValueError, match="restart_after"):
        _run(plots, ti, GROSS_NIS, restart_after=0)


@pytest.mark.parametrize("method", sorted(registry.METHODS))
def test_registered_methods_gate_unless_spec(method):
    """Every method but the -spec ones rejects a 9,000 km plot; the -spec ones take it, as
    their sources would."""
    plots, ti, _ = _plots(n_tracks=2, n=30)
    bad = _with_range(plots, [12], [9e6], track=np.array(["a", "b"])[ti])
    table = {"sigma_range_m": 20.0, "sigma_azimuth_deg": 0.3, "sigma_range_rate_mps": 1.0}
    cols = registry.run(method, bad, table)
    expected = "updated" if method.endswith("-spec") else "rejected"
    assert cols["status"][12] == expected
