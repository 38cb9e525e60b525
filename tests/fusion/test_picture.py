"""The fused picture on a simulated scene (fixed seed): dark, spoofed, shared, outside."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from seatrack.config import ConfigError
from seatrack.fusion import scenario as sc
from seatrack.fusion.associate import AisStates
from seatrack.fusion.coverage import Coverage
from seatrack.fusion.picture import CLASSES
from seatrack.fusion.picture import Fusion
from seatrack.fusion.picture import Picture
from seatrack.fusion.picture import fuse_picture
from seatrack.fusion.picture import parse_fusion_config

T0 = 1.7e9
ORIGIN = (56.0, 7.0)  # open North Sea


@pytest.fixture(scope="module", params=["track", "measurement"])
def scene(request: pytest.FixtureRequest) -> tuple[Picture, sc.Truth, np.ndarray]:
    """The scene fused by each association design (every test below holds for both)."""
    setup, cfg = parse_fusion_config({
        "lat_deg": ORIGIN[0], "lon_deg": ORIGIN[1], "max_range_m": 20000.0,
        "sigma_range_m": 20.0, "sigma_azimuth_deg": 0.3, "blind_sectors_deg": [[250.0, 265.0]],
        "fusion": {"dark_delay_s": 10.0, "association": request.param},
    })  # fmt: skip
    cov = Coverage.of(setup.site)
    start = np.array([
        [-8000, 0], [8000, 500], [0, -9000], [2000, 9000], [-5000, -5000], [5000, -3000.0],
        [-9000, -1500], [0, 26000],  # in the blind sector; beyond the radar's range
    ])  # fmt: skip
    truth = sc.straight_truth(start, np.array([90, 270, 0, 180, 45, 300, 200, 90.0]),
                              np.array([12, 10, 15, 8, 11, 9, 2, 10.0]), T0, 600)  # fmt: skip
    rng = np.random.default_rng(1)
    plots, _ = sc.simulate_plots(truth, np.arange(T0, T0 + 600, 3.0), cov, setup.sensor, 5.0, rng)
    corr = sc.Corruption(
        dark=(4,), spoof=(5,), spoof_offset=((2000.0, 0.0),), spoof_start=(T0 + 200,),
        spoof_end=(T0 + 600,), shared=((2, 3),),
    )  # fmt: skip
    rep, who = sc.ais_reports(truth, np.full(8, 6.0), ORIGIN, corr, 10.0, rng)
    return fuse_picture(rep, plots, setup, cfg, coverage=cov), truth, who


def _track_of(pic: Picture, truth: sc.Truth, vessel: int) -> int:
    """The radar track nearest to a truth vessel at its last time."""
    t = pic.radar.t.max()
    alive, pos, _ = sc.interpolate(truth, t)
    p = pos[list(alive).index(vessel)]
    at = pic.radar.t == t
    k = np.argmin(np.hypot(*(pic.radar.pos[at] - p).T))
    return int(pic.radar.track[at][k])


def test_ais_vessels_get_their_identity(scene) -> None:
    pic, truth, _ = scene
    for v in (0, 1, 2, 3):
        tr = _track_of(pic, truth, v)
        rows = pic.radar.track == tr
        names = pic.ais.vessel_name[pic.radar_vessel[rows][pic.radar_vessel[rows] >= 0]]
        want = str(truth.mmsi[2]) + "#2" if v == 3 else str(truth.mmsi[v])
        assert Counter(names.tolist()).most_common(1)[0][0] == want
        assert np.mean(pic.klass[rows] == 1) > 0.95
        assert np.nanmin(pic.identity_prob[rows][5:]) > 0.9


def test_a_dark_vessel_is_flagged_dark(scene) -> None:
    pic, truth, _ = scene
    rows = pic.radar.track == _track_of(pic, truth, 4)
    assert not (pic.klass[rows] == 1).any()
    t = pic.radar.t[rows]
    first_dark = t[pic.klass[rows] == 2].min()
    assert first_dark - t.min() <= 15.0
    assert (pic.klass[rows][t >= first_dark] == 2).all()


def test_a_spoofed_vessel_is_not_seen_and_its_radar_track_turns_dark(scene) -> None:
    pic, truth, _ = scene
    spoof = np.flatnonzero(pic.ais.vessel_name == f"{truth.mmsi[5]}#2")
    assert spoof.size == 1
    rows = pic.v_vessel == spoof[0]
    late = pic.v_time[rows] >= T0 + 200 + 40
    assert pic.v_not_seen[rows][late].all()
    r = pic.radar.track == _track_of(pic, truth, 5)
    assert (pic.klass[r][pic.radar.t[r] >= T0 + 200 + 60] == 2).all()
    assert (pic.klass[r][pic.radar.t[r] < T0 + 195] == 1).mean() > 0.95


def test_a_shared_mmsi_is_split_into_two_vessels(scene) -> None:
    pic, truth, who = scene
    mm = pic.reports.mmsi[pic.ais.rows] == truth.mmsi[2]
    true_v = who[pic.ais.rows][mm]
    sub = np.array([0 if "#" not in n else 1 for n in pic.ais.vessel_name[pic.ais.vessel[mm]]])
    assert np.mean(sub == (true_v == 3)) >= 0.95
    assert pic.ais.conflict[mm].all() and not pic.ais.conflict[~mm].any()


def test_nothing_outside_coverage_is_dark_or_not_seen(scene) -> None:
    pic, truth, _ = scene
    assert pic.radar_covered[pic.klass == 2].all()
    assert pic.v_covered[pic.v_not_seen].all()
    for v in (6, 7):  # blind sector, beyond range: AIS only, never flagged
        name = str(truth.mmsi[v])
        k = np.flatnonzero(pic.ais.vessel_name == name)
        rows = pic.v_vessel == k[0]
        assert rows.sum() > 100 and not pic.v_covered[rows].any() and not pic.v_not_seen[rows].any()
    honest = np.isin(pic.ais.vessel_name[pic.v_vessel], [str(m) for m in truth.mmsi[:4]])
    assert not pic.v_not_seen[honest].any()


def test_fusion_keys_are_checked() -> None:
    with pytest.raises(ConfigError, match="fusion: gate"):
        parse_fusion_config({"lat_deg": 56.0, "lon_deg": 7.0, "fusion": {"gate": -1.0}})
    with pytest.raises(ConfigError, match=r"\[fusion\] must be a table"):
        parse_fusion_config({"lat_deg": 56.0, "lon_deg": 7.0, "fusion": 3})
    assert math.isclose(parse_fusion_config({"lat_deg": 1.0, "lon_deg": 2.0})[1].gate, 16.0)
    with pytest.raises(ConfigError, match="fusion: association"):
        parse_fusion_config({"lat_deg": 56.0, "lon_deg": 7.0, "fusion": {"association": "x"}})


def test_measurement_design_refuses_a_filter_it_cannot_update() -> None:
    """The measurement design and an IMM per-track filter (states of its own): a
    ConfigError naming the source."""
    setup, cfg = parse_fusion_config({"lat_deg": 56.0, "lon_deg": 7.0, "method": "imm",
                                      "fusion": {"association": "measurement"}})  # fmt: skip
    truth = sc.straight_truth(np.array([[1000.0, 0.0]]), np.array([90.0]), np.array([10.0]),
                              T0, 60)  # fmt: skip
    cov = Coverage.of(setup.site, land=False)
    rng = np.random.default_rng(0)
    plots, _ = sc.simulate_plots(truth, np.arange(T0, T0 + 60, 3.0), cov, setup.sensor, 0.0, rng)
    rep, _ = sc.ais_reports(truth, np.full(1, 6.0), ORIGIN, sc.Corruption(), 10.0, rng)
    with pytest.raises(ConfigError, match="site.toml: fusion: association"):
        fuse_picture(rep, plots, setup, cfg, source="site.toml", coverage=cov)


def test_track_covariance_lies_along_the_line_of_sight() -> None:
    from seatrack.filters.base import SensorNoise
    from seatrack.fusion.picture import track_covariance

    s = SensorNoise(sigma_range=20.0, sigma_azimuth=math.radians(0.3))
    pos = np.array([[30000.0 / math.sqrt(2), 30000.0 / math.sqrt(2)]])
    c = track_covariance(pos, np.array([100.0]), np.array([100.0]), s)[0]
    assert np.allclose(c, c.T) and np.trace(c) == pytest.approx(2e4)
    w, v = np.linalg.eigh(c)
    # small axis along the line of sight (bearing 45 deg), ratio (r s_az / s_r)^2
    assert abs(abs(v[:, 0] @ pos[0]) / 30000.0 - 1.0) < 1e-9
    assert w[1] / w[0] == pytest.approx((30000.0 * math.radians(0.3) / 20.0) ** 2)


def test_step_without_ais_vessels_and_states_replaced() -> None:
    """Radar tracks with no AIS vessel predicted: none, then dark after ``dark_delay_s``
    inside coverage; :meth:`Fusion.set_states` adds vessels, never removes them."""
    setup, cfg = parse_fusion_config({"lat_deg": 56.0, "lon_deg": 7.0, "max_range_m": 20000.0,
                                      "fusion": {"dark_delay_s": 6.0}})  # fmt: skip
    cov = Coverage.of(setup.site, land=False)
    empty = AisStates(np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)),
                      np.zeros((0, 2, 2)), np.zeros((0, 2, 2)), np.zeros(0))  # fmt: skip
    fusion = Fusion(cov, empty, cfg)
    ids, pos = np.array([0, 3]), np.array([[1000.0, 0.0], [0.0, 30000.0]])  # in, out of range
    tcov = np.tile(np.eye(2) * 100.0, (2, 1, 1))
    first = fusion.step(T0, ids, pos, tcov)
    later = fusion.step(T0 + 6.0, ids, pos, tcov)
    assert first.ais_vessel.tolist() == [-1, -1] and first.klass.tolist() == [0, 0]
    assert [CLASSES[k] for k in later.klass] == ["dark", "unknown"]
    one = AisStates(np.array([0]), np.array([T0 + 6.0]), np.array([[1000.0, 0.0]]),
                    np.zeros((1, 2)), np.eye(2)[None] * 25.0, np.eye(2)[None] * 0.01,
                    np.array([60.0]))  # fmt: skip
    fusion.set_states(one)
    res = [fusion.step(T0 + 6.0 + k, ids, pos, tcov) for k in range(1, 4)][-1]
    assert res.ais_vessel.tolist() == [0, -1] and CLASSES[res.klass[0]] == "ais"
    with pytest.raises(ValueError, match="fewer vessels"):
        fusion.set_states(empty)
