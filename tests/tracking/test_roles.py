"""The tracker built from roles: the defaults are the tracker of ``seatrack track``
(every output column identical whichever way it is built), ``step`` scan by scan equals
``run``, a user's own associator (the one in docs/tracking.md) plugs in."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig
from seatrack.simulate.multitarget import TargetPopulation
from seatrack.simulate.multitarget import simulate_multitarget
from seatrack.simulate.scenarios import SensorConfig
from seatrack.tracking import MultiTargetTracker
from seatrack.tracking import run_tracker
from seatrack.tracking.auto import per_track_filter
from seatrack.tracking.auto import scan_period
from seatrack.tracking.gating import innovation_space
from seatrack.tracking.roles import GNN
from seatrack.tracking.roles import JPDA
from seatrack.tracking.roles import Associator
from seatrack.tracking.roles import ExistenceManager
from seatrack.tracking.roles import Initiator
from seatrack.tracking.roles import MofNManager
from seatrack.tracking.roles import Tracker
from seatrack.tracking.roles import TrackerConfig
from seatrack.tracking.roles import TrackerRun
from seatrack.tracking.roles import TrackManager
from seatrack.tracking.roles import TwoPointInitiator

SN = SensorNoise(sigma_range=15.0, sigma_azimuth=np.radians(0.3))
DOC = Path(__file__).resolve().parents[2] / "docs" / "tracking.md"


def _scenario(
    seed: int, targets: int = 8, clutter: float = 15.0, pd: float = 0.9, crossings: int = 1
):
    radar = SensorConfig(
        "r", "radar2d", ("azimuth", "range"), (SN.sigma_azimuth, SN.sigma_range),
        p_detect=pd, clutter_density=clutter, clutter_range=(500.0, 13000.0), scan_period=2.5,
    )  # fmt: skip
    pop = TargetPopulation(targets=targets, births_per_scan=0.0, mean_life=0.0,
                           range_limits=(2000.0, 12000.0), crossings=crossings)  # fmt: skip
    return simulate_multitarget(pop, radar, 100.0, np.random.default_rng(seed))


def _same(a: TrackerRun, b: TrackerRun) -> None:
    for name in ("t", "track", "status", "plot", "plot_track", "scan_times",
                 "clutter_per_scan", "confirmed_ids", "existence"):  # fmt: skip
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x, y), name
    assert list(a.columns) == list(b.columns)
    for name, col in a.columns.items():
        assert np.array_equal(col, b.columns[name], equal_nan=True), name


CONFIGS = [
    {},
    {"association": "jpda"},
    {"confirmation": "m-of-n"},
    {"association": "jpda", "confirmation": "m-of-n", "m_of_n": [2, 3], "max_misses": 3},
]


@pytest.mark.parametrize("keys", CONFIGS)
def test_default_roles_are_the_configured_tracker(keys):
    """Tracker(flt, config) = the same roles given explicitly = MultiTargetTracker =
    run_tracker: every output column identical (the automatic process noise of
    ``seatrack track``)."""
    sim = _scenario(seed=21 + len(keys))
    cfg = TrackerConfig.from_keys(**keys)
    m, _ = per_track_filter("ekf", {}, 2, False, scan_period(sim.plots.t))
    plots = m.prepare(sim.plots)
    default = Tracker(m.filter, sensor=SN, config=cfg).run(plots, all_tracks=True)
    assoc = JPDA() if cfg.association == "jpda" else GNN()
    rule = MofNManager if cfg.confirmation == "m-of-n" else ExistenceManager
    explicit = Tracker(
        m.filter, associator=assoc, initiator=TwoPointInitiator.from_config(cfg),
        manager=rule.from_config(cfg), sensor=SN, config=cfg,
    ).run(plots, all_tracks=True)  # fmt: skip
    old_name = run_tracker(MultiTargetTracker(m.filter, SN, cfg), plots, all_tracks=True)
    assert default.confirmed_ids.size >= 6
    _same(default, explicit)
    _same(default, old_name)


def test_step_by_step_equals_run():
    sim = _scenario(seed=30)
    flt = EKF(EKFConfig(q=0.1), SN)
    run = Tracker(flt).run(sim.plots)
    trk = Tracker(flt)
    times = np.unique(sim.plots.t)
    rows = [trk.step(t, sim.plots.take(np.flatnonzero(sim.plots.t == t))).columns() for t in times]
    for name in ("track", "x_m", "vy_mps", "existence"):
        col = np.concatenate([r[name] for r in rows])
        assert np.array_equal(col, run.columns.get(name, getattr(run, name, None))), name
    assert np.array_equal(np.concatenate([r["time_s"] for r in rows]), run.t)
    assert set(np.concatenate([r["status"] for r in rows])) <= {"confirmed", "coasting"}


def test_a_scan_without_plots_coasts_the_tracks():
    sim = _scenario(seed=31, clutter=0.0, pd=1.0)
    trk = Tracker(EKF(EKFConfig(q=0.1), SN))
    times = np.unique(sim.plots.t)[:6]
    for t in times:
        trk.step(t, sim.plots.take(np.flatnonzero(sim.plots.t == t)))
    res = trk.step(times[-1] + 2.5, Plots(np.zeros(0), np.zeros(0), np.zeros(0)))
    cols = res.columns()
    assert cols["track"].size >= 6 and set(cols["status"]) == {"coasting"}
    assert np.all(res.plot == -1) and np.all(np.isfinite(cols["x_m"]))


def test_the_sensor_noise_defaults_to_the_filter_s():
    """Without ``sensor``, the tracker takes the filter's own nominal noise, also through
    the automatic noise-level wrapper."""
    table = {"sigma_range_m": 25.0, "sigma_azimuth_deg": 0.4}
    m, rule = per_track_filter("ekf", table, 2, False, 2.5)
    own = Tracker(m.filter).sensor
    assert rule == "levels" and own is m.filter.flt.sensor  # type: ignore[attr-defined]
    assert own.sigma_range == 25.0 and own.sigma_azimuth == pytest.approx(np.radians(0.4))
    assert Tracker(m.filter, sensor=SN).sensor == SN


def test_the_roles_honour_their_protocols():
    assert isinstance(GNN(), Associator) and isinstance(JPDA(), Associator)
    assert isinstance(TwoPointInitiator(), Initiator)
    assert isinstance(ExistenceManager(), TrackManager) and isinstance(MofNManager(), TrackManager)
    trk = Tracker(EKF(), config=TrackerConfig.from_keys(association="jpda", confirmation="m-of-n"))
    assert isinstance(trk.associator, JPDA) and isinstance(trk.manager, MofNManager)
    assert isinstance(Tracker(EKF()).associator, GNN)


def test_the_roles_see_the_filter_s_innovation_space_measured_once():
    """The engine measures the filter's innovation space once and gives it to the roles
    with every scan (the initiator weighs its new tracks' plots with it)."""
    seen: list[str] = []

    class Recording(TwoPointInitiator):
        def initiate(self, flt, sensor, scan, free):  # type: ignore[no-untyped-def]
            seen.append(scan.space)
            return super().initiate(flt, sensor, scan, free)

    sim = _scenario(seed=32, targets=3)
    flt = EKF(EKFConfig(q=0.1), SN)
    trk = Tracker(flt, initiator=Recording())
    times = np.unique(sim.plots.t)[:5]
    for t in times:
        trk.step(t, sim.plots.take(np.flatnonzero(sim.plots.t == t)))
    assert seen == [innovation_space(flt, SN)] * times.size == [trk.space] * times.size


def _docs_associator() -> type:
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("### The tracker's roles") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)  # type: ignore[union-attr]
    assert 15 <= code.count("\n") <= 30  # "a few lines"
    space: dict[str, object] = {}
    exec(compile(code, str(DOC), "exec"), space)
    cls = space["NearestNeighbour"]
    assert isinstance(cls, type)
    return cls


def test_the_documented_associator_runs():
    """The greedy nearest neighbour of docs/tracking.md in the default tracker: where no
    two tracks contend for a plot (no crossings, no clutter) it assigns as GNN does (same
    track ids and plots); with crossings and dense clutter it tracks every target too."""
    nn = _docs_associator()
    assert isinstance(nn(), Associator)
    sparse = _scenario(seed=32, targets=4, clutter=0.0, pd=1.0, crossings=0)
    flt = EKF(EKFConfig(q=0.1), SN)
    mine = Tracker(flt, associator=nn()).run(sparse.plots)
    gnn = Tracker(flt).run(sparse.plots)
    assert np.array_equal(mine.plot_track, gnn.plot_track)
    assert np.array_equal(mine.track, gnn.track) and np.array_equal(mine.plot, gnn.plot)
    assert np.allclose(mine.columns["x_m"], gnn.columns["x_m"], rtol=0, atol=1e-6)
    dense = _scenario(seed=33, targets=6, clutter=30.0)
    out = Tracker(flt, associator=nn()).run(dense.plots)
    truth = dense.origin >= 0
    share = np.mean(out.plot_track[truth] >= 0)
    assert share > 0.85 and np.mean(out.plot_track[~truth] >= 0) < 0.05
