"""AIS tracker: compiled CT step, synthetic turning vessels with glitches, and the real data
bundled in seatrack/data/ais (every row accounted for, glitches flagged, flags implausible, hold-out
prediction against linear interpolation)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ais_samples import FILES
from ais_samples import data_file
from seatrack.evaluate.holdout import ais_holdout
from seatrack.filters.ais import AisTrackerConfig
from seatrack.filters.ais import OffsetInputs
from seatrack.filters.ais import ct_step
from seatrack.filters.ais import position_noise
from seatrack.filters.ais import sogcog_model
from seatrack.filters.ais import timestamp_offsets
from seatrack.filters.ais import track_reports
from seatrack.filters.ais import track_vessels
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import angle_diff
from seatrack.geometry import bearing
from seatrack.geometry import local_frames
from seatrack.io.ais import AisReports
from seatrack.io.ais import read_ais_csv
from seatrack.models import numerical_jacobian
from seatrack.models.motion import ct_jacobian
from seatrack.models.motion import ct_noise
from seatrack.models.motion import ct_transition
from seatrack.simulate import Leg
from seatrack.simulate import trajectory

CFG = AisTrackerConfig()


_CACHE: dict[str, tuple[AisReports, object]] = {}


def tracked(name: str) -> tuple[AisReports, object]:
    if name not in _CACHE:
        r = read_ais_csv(data_file(name))
        _CACHE[name] = (r, track_reports(r, CFG))
    return _CACHE[name]


# ---------------------------------------------------------------------------
# compiled CT step
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("w", [0.0, 1e-7, 2e-4, 0.03, -0.08])
@pytest.mark.parametrize("dt", [0.0, 1.0, 9.5, 120.0])
def test_ct_step_equals_motion_models(w: float, dt: float) -> None:
    x = np.array([120.0, -40.0, 3.1, -5.2, w])
    fx, F, Q = ct_step(x, dt, 0.05, 2e-6)
    assert np.allclose(fx, ct_transition(x, dt), rtol=1e-12, atol=1e-9)
    assert np.allclose(F, ct_jacobian(x, dt), rtol=1e-10, atol=1e-9)
    assert np.allclose(Q, ct_noise(dt, 0.05, 2e-6), rtol=1e-12, atol=1e-15)
    Jn = numerical_jacobian(lambda s: ct_step(s, dt, 0.05, 2e-6)[0], x, eps=1e-6)
    assert np.allclose(F, Jn, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("v", [(3.0, 4.0), (-0.5, 7.0), (-6.0, -0.2), (0.02, -0.03)])
def test_sogcog_model_jacobian(v: tuple[float, float]) -> None:
    x = np.array([10.0, 20.0, v[0], v[1], 0.01])
    h, H = sogcog_model(x)
    assert h[0] == pytest.approx(np.hypot(*v))
    assert angle_diff(h[1], bearing(*v)) == pytest.approx(0.0, abs=1e-12)
    Hn = numerical_jacobian(lambda s: sogcog_model(s)[0], x, eps=1e-7, angular=[False, True])
    assert np.allclose(H, Hn, rtol=1e-5, atol=1e-6)


# ---------------------------------------------------------------------------
# synthetic vessels: truth known
# ---------------------------------------------------------------------------
def _synthetic(n_vessels: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    legs = [
        Leg.straight(300.0),
        Leg.turn(math.radians(90.0), math.radians(1.0)),
        Leg.straight(300.0),
        Leg.turn(math.radians(-120.0), math.radians(0.5)),
        Leg.straight(200.0),
    ]
    out: dict[str, list[np.ndarray]] = {
        k: [] for k in ("vessel", "t", "z", "truth", "vel", "w", "kind", "sog")
    }
    for v in range(n_vessels):
        t = np.cumsum(rng.uniform(2.0, 12.0, 220))
        t = t[t < 1330.0]
        tr = trajectory([0.0, 0.0], rng.uniform(0, 2 * np.pi), 6.0, legs, times=t)
        z = tr.pos[:, :2] + rng.normal(0.0, 4.0, (t.size, 2))
        kind = np.zeros(t.size, dtype=int)
        # gross jumps: 300 m off
        jumps = rng.choice(np.arange(10, t.size - 10), 4, replace=False)
        ang = rng.uniform(0, 2 * np.pi, jumps.size)
        z[jumps] += 300.0 * np.stack([np.sin(ang), np.cos(ang)], -1)
        kind[jumps] = 1
        # stale reports: the previous report's position repeated >= 5 s later (>= 30 m of
        # motion at 6 m/s)
        cand = np.setdiff1d(np.arange(10, t.size - 10), np.r_[jumps, jumps + 1, jumps - 1])
        cand = cand[t[cand] - t[cand - 1] >= 5.0]
        stale = rng.choice(cand, 4, replace=False)
        stale = stale[kind[stale - 1] == 0]
        z[stale] = z[stale - 1]
        kind[stale] = 2
        ok = np.ones(t.size, dtype=bool)
        out["vessel"].append(np.full(t.size, v)[ok])
        out["t"].append(t[ok])
        out["z"].append(z[ok])
        out["truth"].append(tr.pos[ok, :2])
        out["vel"].append(tr.vel[ok, :2])
        out["w"].append(tr.turn_rate[ok])
        out["kind"].append(kind[ok])
        # reported SOG, 0.1 kn resolution as in AIS
        out["sog"].append(np.round(tr.speed[ok] / KNOT_MPS, 1) * KNOT_MPS)
    return {k: np.concatenate(v) for k, v in out.items()}


def test_synthetic_turning_vessels_with_glitches() -> None:
    s = _synthetic(12, seed=7)
    st = track_vessels(s["vessel"], s["t"], s["z"], CFG, sog=s["sog"])
    clean = s["kind"] == 0
    assert st.outlier[s["kind"] == 1].all()  # every 300 m jump
    assert (st.outlier_kind[s["kind"] == 2] == 2).all()  # every stale repeat
    assert st.outlier[clean].mean() < 0.005  # false alarms
    err = np.hypot(*(st.state[:, :2] - s["truth"]).T)
    assert np.sqrt(np.mean(err[clean] ** 2)) < 0.6 * 4.0 * np.sqrt(2)  # below raw noise
    assert np.sqrt(np.mean(err[~clean] ** 2)) < 8.0  # glitches do not pull the track
    speed_err = np.hypot(*(st.state[:, 2:4] - s["vel"]).T)
    assert np.sqrt(np.mean(speed_err**2)) < 0.4
    course_err = angle_diff(
        bearing(st.state[:, 2], st.state[:, 3]), bearing(s["vel"][:, 0], s["vel"][:, 1])
    )
    assert np.median(np.abs(np.degrees(course_err))) < 2.0
    # turn rate in the middle half of the 90-s, 1 deg/s turn (t = 300..390 s): the smoothed
    # turn-rate random walk blurs the onset and the end of the turn over ~20 s
    in_turn = (s["t"] > 322.5) & (s["t"] < 367.5)
    assert np.all(np.abs(s["w"][in_turn] - math.radians(1.0)) < 1e-9)
    assert in_turn.sum() > 50
    w_err = np.degrees(st.state[in_turn, 4] - s["w"][in_turn])
    w_std = np.degrees(st.std[in_turn, 4])
    # ~0.8 deg/s estimated: the slow turn-rate random walk of the defaults (ships) lags a
    # 90-s turn; the error is within the reported 1-sigma
    assert abs(np.median(w_err)) < np.median(w_std)
    assert 0.6 < np.median(np.degrees(st.state[in_turn, 4])) < 1.2
    # 1-sigma is honest on average: position NEES per axis within a loose chi-square band
    nees = ((st.state[clean, :2] - s["truth"][clean]) / st.std[clean, :2]) ** 2
    assert 0.3 < nees.mean() < 2.0


def test_batch_equals_one_vessel_at_a_time() -> None:
    s = _synthetic(5, seed=3)
    together = track_vessels(s["vessel"], s["t"], s["z"], CFG)
    shuffle = np.random.default_rng(1).permutation(s["t"].size)
    shuffled = track_vessels(s["vessel"][shuffle], s["t"][shuffle], s["z"][shuffle], CFG)
    assert np.array_equal(shuffled.state, together.state[shuffle], equal_nan=True)
    for v in range(5):
        m = s["vessel"] == v
        alone = track_vessels(s["vessel"][m], s["t"][m], s["z"][m], CFG)
        assert np.array_equal(alone.state, together.state[m])
        assert np.array_equal(alone.outlier, together.outlier[m])


# ---------------------------------------------------------------------------
# real data
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("name", FILES)
def test_real_every_row_accounted_for(name: str) -> None:
    r, tr = tracked(name)
    # an outlier across a long gap (kind 3) has no track around it, hence no estimate
    gap_out = tr.outlier_kind == 3
    ok = r.valid & ~gap_out
    for f in ("lat", "lon", "speed", "course", "turn_rate", "std_pos_m", "std_speed"):
        a = getattr(tr, f)
        assert np.isfinite(a[ok]).all(), f
        assert np.isnan(a[~ok]).all(), f
    assert (tr.segment[ok] > 0).all() and (tr.segment[~ok] == -1).all()
    print(
        f"{name}: {len(r)} rows = {int(ok.sum())} with estimates "
        f"({int(tr.outlier.sum())} outliers) + {int(gap_out.sum())} outliers after gaps "
        f"+ {int((~r.valid).sum())} rejected"
    )
    assert not tr.outlier[~r.valid].any()
    # smoothed positions stay near the used reports (here: within 100 m for 99.9 %)
    fr = local_frames(r.mmsi, r.lat, r.lon, r.valid)
    used = ok & ~tr.outlier
    d = np.hypot(tr.x_m[used] - fr.enu[used, 0], tr.y_m[used] - fr.enu[used, 1])
    assert np.quantile(d, 0.999) < 100.0


def _sorted_valid(r: AisReports) -> np.ndarray:
    ok = np.flatnonzero(r.valid)
    return ok[np.lexsort((r.t[ok], r.mmsi[ok]))]


@pytest.mark.parametrize(
    "name", ["dk_northsea_20221101_1h_selected.csv", "dk_northsea_20221101_1h_all.csv"]
)
def test_real_known_glitches_are_flagged(name: str) -> None:
    r, tr = tracked(name)
    o = _sorted_valid(r)
    E = local_frames(r.mmsi, r.lat, r.lon, r.valid).enu[o, :2]
    m, t, fl = r.mmsi[o], r.t[o], tr.outlier[o]
    d0 = CFG.n_sigma * math.sqrt(2) * CFG.sigma_pos_m
    same = m[1:] == m[:-1]
    dt = t[1:] - t[:-1]
    dist = np.hypot(*(E[1:] - E[:-1]).T)
    # the README's jumps: consecutive reports implying more than 50 kn
    jump = same & (dt > 0) & (dist > 50 * KNOT_MPS * np.where(dt > 0, dt, 1))
    first = np.r_[True, ~same][:-1]  # pair starts at a vessel's first report
    # implausible even with the noise allowance and one second of timestamp slack
    hard = jump & ((dist - d0) / (dt + CFG.time_resolution_s) > CFG.max_speed_kn * KNOT_MPS)
    covered = fl[1:] | fl[:-1]
    print(
        f"{name}: README jumps {jump.sum()}, flagged {np.sum(jump & covered)}; "
        f"implausible with allowance {hard.sum()}, flagged {np.sum(hard & covered)}"
    )
    assert np.all(covered[hard & ~first])
    assert np.sum(jump & covered) >= 0.85 * jump.sum()
    # frozen positions (README: exact repeat of the previous position at > 3 kn)
    frozen = np.r_[False, same & (dist == 0) & (dt > 0)] & (r.sog_kn[o] > 3)
    run_start = t.copy()
    for i in range(1, t.size):
        if same[i - 1] and dist[i - 1] == 0:
            run_start[i] = run_start[i - 1]
    moved = r.sog_kn[o] * KNOT_MPS * (t - run_start) > d0
    print(
        f"frozen reports {frozen.sum()}, of which moved beyond the noise allowance "
        f"{np.sum(frozen & moved)}, flagged stale {np.sum(frozen & moved & fl)}"
    )
    assert np.all(tr.outlier_kind[o][frozen & moved] == 2)
    # the identity collision (vessel 170): Aarhus and the North Sea alternate
    v170 = m == 170
    assert fl[v170].sum() >= 4
    acc = v170 & ~fl
    seg = tr.segment[o]
    for i, j in zip(np.flatnonzero(acc)[:-1], np.flatnonzero(acc)[1:], strict=True):
        if seg[i] == seg[j]:
            v = (np.hypot(*(E[j] - E[i])) - d0) / (t[j] - t[i] + 1.0)
            assert v <= CFG.max_speed_kn * KNOT_MPS


@pytest.mark.parametrize("name", FILES)
def test_real_flagged_reports_are_implausible(name: str) -> None:
    """Independent check of every flag against the accepted reports around it."""
    r, tr = tracked(name)
    o = _sorted_valid(r)
    E = local_frames(r.mmsi, r.lat, r.lon, r.valid).enu[o, :2]
    m, t, kind = r.mmsi[o], r.t[o], tr.outlier_kind[o]
    acc = kind == 0
    d0 = CFG.n_sigma * math.sqrt(2) * CFG.sigma_pos_m
    tau = CFG.time_resolution_s
    vmax = CFG.max_speed_kn * KNOT_MPS
    n_checked = 0
    for i in np.flatnonzero(kind > 0):
        n_checked += 1
        if kind[i] == 2:  # stale: exact repeat of the previous report while moving
            assert m[i - 1] == m[i] and np.array_equal(E[i], E[i - 1]) and t[i] > t[i - 1]
            k = i
            while m[k - 1] == m[i] and np.array_equal(E[k - 1], E[i]):
                k -= 1
            # moving: reported SOG, or the track speed significantly above zero
            sog = r.sog_kn[o][i] * KNOT_MPS if np.isfinite(r.sog_kn[o][i]) else 0.0
            spd = max(sog, tr.speed[o][i] - CFG.n_sigma * tr.std_speed[o][i])
            assert spd * (t[i] - t[k]) > d0, (r.line[o[i]], spd, t[i] - t[k])
            continue
        p = i - 1
        while p >= 0 and m[p] == m[i] and not acc[p]:
            p -= 1
        n = i + 1
        while n < t.size and m[n] == m[i] and not acc[n]:
            n += 1
        has_p = p >= 0 and m[p] == m[i]
        has_n = n < t.size and m[n] == m[i]
        implausible = False
        if has_p:
            implausible |= (np.hypot(*(E[i] - E[p])) - d0) / (t[i] - t[p] + tau) > vmax
        if has_n:
            implausible |= (np.hypot(*(E[n] - E[i])) - d0) / (t[n] - t[i] + tau) > vmax
        if has_p and has_n:
            w = (t[i] - t[p]) / (t[n] - t[p]) if t[n] > t[p] else 0.5
            e = np.hypot(*(E[i] - (E[p] + w * (E[n] - E[p]))))
            a = 2 * (e - d0) / ((t[i] - t[p] + tau) * (t[n] - t[i] + tau))
            implausible |= a > CFG.max_accel_mps2
        assert implausible, f"{name} line {r.line[o[i]]} flagged but plausible"
    print(f"{name}: {n_checked} flags checked")


# ---------------------------------------------------------------------------
# hold-out: withhold every 5th report of each vessel and predict it from the track
# ---------------------------------------------------------------------------
def _holdout(
    r: AisReports, cfg: AisTrackerConfig = CFG
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    res = ais_holdout(r, cfg)  # every 5th report of each vessel withheld
    return res.track, res.interp, res.row


def test_real_holdout_beats_linear_interpolation() -> None:
    trk, lin, moving, sparse, per_file, med_file = [], [], [], [], [], {}
    lines = []
    for name in FILES:
        r = read_ais_csv(data_file(name))
        et, el, rows = _holdout(r)
        med_file[name] = (np.median(et), np.median(el))
        mv = r.sog_kn[rows] >= 2.0  # moving at the withheld report (reported SOG)
        trk.append(et)
        lin.append(el)
        moving.append(mv)
        sparse.append(np.full(et.size, name.startswith("us_boston")))
        per_file.append((np.percentile(et, 95), np.percentile(el, 95)))
        lines.append(
            f"{name:38s} n={et.size:5d}  median {np.median(et):5.2f} vs {np.median(el):5.2f} m"
            f"  p95 {np.percentile(et, 95):6.2f} vs {np.percentile(el, 95):6.2f} m"
        )
    et, el = np.concatenate(trk), np.concatenate(lin)
    mv, sp = np.concatenate(moving), np.concatenate(sparse)
    stats = {
        "all": (np.median(et), np.median(el), np.percentile(et, 95), np.percentile(el, 95)),
        "moving": (
            np.median(et[mv]),
            np.median(el[mv]),
            np.percentile(et[mv], 95),
            np.percentile(el[mv], 95),
        ),
        "sparse": (
            np.median(et[sp]),
            np.median(el[sp]),
            np.percentile(et[sp], 95),
            np.percentile(el[sp], 95),
        ),
    }
    print("hold-out error, track vs linear interpolation (every 5th report withheld):")
    print("\n".join(lines))
    for k, (a, b, c, d) in stats.items():
        print(f"pooled {k:7s} median {a:5.2f} vs {b:5.2f} m   p95 {c:6.2f} vs {d:6.2f} m")
    # median and 95th percentile better in every file (withholding the 2nd, 3rd or 4th of
    # each five instead, the 95th percentile of the two dense Danish files is within 5 % of
    # interpolation's, on either side; the medians stay better)
    for name in FILES:
        assert med_file[name][0] < med_file[name][1], name
    assert all(a < b for a, b in per_file)
    assert stats["all"][0] < stats["all"][1]
    assert stats["all"][2] < stats["all"][3]
    assert stats["moving"][0] < stats["moving"][1]
    assert stats["moving"][2] < stats["moving"][3]
    assert stats["sparse"][0] < stats["sparse"][1]
    assert stats["sparse"][2] < 0.6 * stats["sparse"][3]


def test_real_estimated_noise_improves_dense_files() -> None:
    """The per-vessel noise estimate (vs the fixed 5 m sigma) lowers the hold-out median on
    the dense files, where the cross-track GNSS noise is well below a metre."""
    fixed = AisTrackerConfig(estimate_noise=False)
    for name in ("dk_northsea_20221101_1h_selected.csv", "dk_northsea_20221101_1h_all.csv"):
        r = read_ais_csv(data_file(name))
        est = np.median(_holdout(r)[0])
        fix = np.median(_holdout(r, fixed)[0])
        print(f"{name}: hold-out median {est:.2f} m (estimated noise) vs {fix:.2f} m (fixed)")
        assert est < 0.95 * fix


def test_real_refinement_improves_dense_files() -> None:
    """The refinement pass (whole-second timestamp offsets, steady or manoeuvring process
    noise per vessel) lowers the hold-out median on the files with whole-second stamps."""
    coarse = AisTrackerConfig(refine=False)
    for name in FILES[1:4]:
        r = read_ais_csv(data_file(name))
        ref = np.median(_holdout(r)[0])
        raw = np.median(_holdout(r, coarse)[0])
        print(f"{name}: hold-out median {ref:.3f} m (refined) vs {raw:.3f} m (refine=False)")
        assert ref < 0.9 * raw


# ---------------------------------------------------------------------------
# position noise estimate
# ---------------------------------------------------------------------------
def _jittered_vessels(seed: int) -> dict[str, np.ndarray]:
    """Three vessels: 7 m/s straight + turn, 3 m/s, and one at rest on a 2-m grid; reports
    every 2-12 s, white position noise 0.4 m, timestamp error 0.5 s (moving vessels)."""
    rng = np.random.default_rng(seed)
    out: dict[str, list[np.ndarray]] = {k: [] for k in ("vessel", "t", "z")}
    for v, speed in enumerate((7.0, 3.0, 0.0)):
        t = np.cumsum(rng.uniform(2.0, 12.0, 400))
        legs = [Leg.straight(1500.0), Leg.turn(math.radians(60.0), math.radians(0.3))]
        legs += [Leg.straight(3000.0)]
        tau = rng.normal(0.0, 0.5, t.size) if speed > 0 else np.zeros(t.size)
        tr = trajectory([0.0, 0.0], 0.7, max(speed, 1e-9), legs, times=t + tau)
        z = tr.pos[:, :2] + rng.normal(0.0, 0.4, (t.size, 2))
        if speed == 0:
            z = 2.0 * np.round(z / 2.0)  # at rest, rounded to a 2 m grid: mostly repeats
        out["vessel"].append(np.full(t.size, v))
        out["t"].append(t)
        out["z"].append(z)
    return {k: np.concatenate(a) for k, a in out.items()}


def test_position_noise_recovers_position_and_timestamp_sigma() -> None:
    s = _jittered_vessels(5)
    use = np.ones(s["t"].size, dtype=bool)
    sig = position_noise(s["vessel"], s["t"], s["z"], use, CFG)
    for v in (0, 1):
        sp, st = sig[s["vessel"] == v][0]
        assert 0.3 < sp < 0.55, (v, sp)  # 0.4 m (the turn adds a little)
        assert 0.4 < st < 0.6, (v, st)  # 0.5 s
    # the vessel at rest repeats its grid point (>90 % of reports): the trimmed residual
    # scale is 0 -> the floor (a limitation: the 2-m grid's 0.58 m is not seen)
    sp, st = sig[s["vessel"] == 2][0]
    assert sp == CFG.sigma_pos_min_m
    assert st == pytest.approx(CFG.sigma_time_min_s)
    # withheld reports do not enter the estimate
    held = np.zeros_like(use)
    held[::5] = True
    z2 = s["z"].copy()
    z2[held] += 1000.0
    a = position_noise(s["vessel"], s["t"], s["z"], ~held, CFG)
    b = position_noise(s["vessel"], s["t"], z2, ~held, CFG)
    assert np.array_equal(a, b)
    # too few residuals: the configured sigma and the timestamp floor
    few = position_noise(
        np.zeros(5, np.int64), np.arange(5.0), np.zeros((5, 2)), np.ones(5, bool), CFG
    )
    assert np.all(few[:, 0] == CFG.sigma_pos_m) and np.all(few[:, 1] == CFG.sigma_time_min_s)


def test_course_is_referred_to_true_north_far_from_the_frame_origin(tmp_path: Path) -> None:
    """A vessel sailing along the 60 N parallel for 150 km: true course 090 everywhere,
    although its frame's North (at the first report) differs by ~2 deg at the far end."""
    t = np.arange(0.0, 15000.0, 10.0)
    lon = 3.0 + np.degrees(10.0 * t / (6_394_209.0 * math.cos(math.radians(60.0))))
    p = tmp_path / "east.csv"
    with p.open("w") as fh:
        fh.write("mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg\n")
        for ti, lo in zip(t, lon, strict=True):
            stamp = np.datetime_as_string(np.datetime64(int(1.6e9 + ti), "s"))
            fh.write(f"1,{stamp}Z,60.000000,{lo:.6f},19.4,90.0,90\n")
    r = read_ais_csv(p)
    tr = track_reports(r, CFG)
    far = slice(-200, -20)  # away from the ends of the track
    assert lon[-1] - lon[0] > 2.5
    assert np.abs(np.degrees(tr.course[far]) - 90.0).max() < 0.1
    assert np.abs(tr.lat[far] - 60.0).max() < 2e-6
    assert np.abs(tr.speed[far] - 10.0).max() < 0.05
    # in the frame's plane the same motion points ~2 deg off East
    plane = np.degrees(bearing(np.gradient(tr.x_m, t), np.gradient(tr.y_m, t)))
    assert np.abs(plane[far] - 90.0).min() > 1.5


@pytest.mark.parametrize(
    "bad",
    [
        {"sigma_time_fine_s": 0.0},
        {"steady_nis_ratio": -1.0},
        {"max_turn_rate_dps": 0.0},
        {"max_time_offset_s": -1},
        {"offset_passes": -1},
        {"q_accel_steady": -0.1},
        {"min_offset_share": 1.0},
    ],
)
def test_refinement_settings_are_checked(bad: dict) -> None:
    with pytest.raises(ValueError, match=next(iter(bad))):
        AisTrackerConfig(**bad)


def test_compiled_two_d_update_equals_the_kalman_core() -> None:
    """The tracker's 2-D Joseph update (position with offset, SOG/COG rows) equals
    seatrack.kalman.update_core on random states, covariances and measurement matrices."""
    from seatrack.filters.ais.ct import update2 as _update2
    from seatrack.kalman import update_core

    rng = np.random.default_rng(8)
    for trial in range(200):
        a = rng.normal(size=(5, 5))
        P = a @ a.T + 0.1 * np.eye(5)
        x = rng.normal(size=5)
        if trial % 2:
            d = float(rng.integers(-2, 3))
            H = np.zeros((2, 5))
            H[0, 0] = H[1, 1] = 1.0
            H[0, 2] = H[1, 3] = -d
        else:
            H = np.zeros((2, 5))
            H[:, 2:4] = rng.normal(size=(2, 2))
        b = rng.normal(size=(2, 2))
        R = b @ b.T + 0.05 * np.eye(2)
        y = rng.normal(size=2)
        xo, Po, K = np.empty(5), np.empty((5, 5)), np.empty((5, 2))
        nis = _update2(x, P, y, H, R, xo, Po, K)
        xr, Pr, Sr, Kr = np.empty(5), np.empty((5, 5)), np.empty((2, 2)), np.empty((5, 2))
        nis_r, _ = update_core(x, P, y, H, R, xr, Pr, Sr, Kr)
        np.testing.assert_allclose(xo, xr, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(Po, Pr, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(K, Kr, rtol=1e-9, atol=1e-12)
        assert nis == pytest.approx(nis_r, rel=1e-9)
        assert np.array_equal(Po, Po.T)
    # a measurement matrix that makes S singular leaves the state alone (inf NIS)
    H = np.zeros((2, 5))
    xo, Po, K = np.empty(5), np.empty((5, 5)), np.empty((5, 2))
    assert _update2(x, P, y, H, np.zeros((2, 2)), xo, Po, K) == np.inf
    assert np.array_equal(xo, x) and np.array_equal(Po, P)


# ---------------------------------------------------------------------------
# whole-second timestamp offsets and the refinement pass
# ---------------------------------------------------------------------------
def _offset_vessels(
    seed: int, p_off: float, sigma: float = 0.3, integer_times: bool = True
) -> dict[str, np.ndarray]:
    """Eight vessels at 4-9 m/s (straight, then a 60 deg turn), reports every 2-12 s logged at
    whole seconds; a report stamped ``d`` s late shows the position at ``t - d``, ``d`` = +-1
    with probability ``p_off`` each side; white position noise ``sigma`` (m)."""
    rng = np.random.default_rng(seed)
    out: dict[str, list[np.ndarray]] = {k: [] for k in ("vessel", "t", "z", "truth", "d")}
    for v in range(8):
        t = np.cumsum(rng.uniform(2.0, 12.0, 300))
        if integer_times:
            t = np.round(t)
        d = rng.choice([-1.0, 0.0, 1.0], t.size, p=[p_off, 1 - 2 * p_off, p_off])
        legs = [Leg.straight(600.0), Leg.turn(math.radians(60.0), math.radians(0.5))]
        legs += [Leg.straight(3000.0)]
        speed = rng.uniform(4.0, 9.0)
        course = rng.uniform(0, 2 * math.pi)
        seen = trajectory([0.0, 0.0], course, speed, legs, times=t - d).pos[:, :2]
        truth = trajectory([0.0, 0.0], course, speed, legs, times=t).pos[:, :2]
        out["vessel"].append(np.full(t.size, v))
        out["t"].append(t)
        out["z"].append(seen + rng.normal(0.0, sigma, (t.size, 2)))
        out["truth"].append(truth)
        out["d"].append(d)
    return {k: np.concatenate(a) for k, a in out.items()}


def test_whole_second_timestamp_offsets_are_found_and_modelled() -> None:
    s = _offset_vessels(11, p_off=0.1)
    st = track_vessels(s["vessel"], s["t"], s["z"], CFG)
    coarse = track_vessels(s["vessel"], s["t"], s["z"], AisTrackerConfig(refine=False))
    hit = np.mean(st.time_offset == s["d"])
    found = np.mean(st.time_offset[s["d"] != 0] == s["d"][s["d"] != 0])
    false = np.mean(st.time_offset[s["d"] == 0] != 0)
    print(f"offsets right for {hit:.3f} of the reports; {found:.3f} of the offsets found, ")
    print(f"{false:.3f} of the exact reports given one")
    # (~20 % of the reports are offset)
    assert hit > 0.95
    assert found > 0.85 and false < 0.03
    # offsets are logged minus true time, in whole seconds
    assert set(np.unique(st.time_offset)) <= {-2.0, -1.0, 0.0, 1.0, 2.0}
    # the state stays at the logged time: position error against the truth at t
    err = np.hypot(*(st.state[:, :2] - s["truth"]).T)
    err0 = np.hypot(*(coarse.state[:, :2] - s["truth"]).T)
    print(
        f"median position error {np.median(err):.2f} m with offsets, "
        f"{np.median(err0):.2f} m without"
    )
    assert np.median(err) < 0.5 * np.median(err0)
    assert np.median(err) < 1.1774 * 0.3  # median 2-D error of an exact report (Rayleigh)


def test_no_offsets_where_the_data_show_none() -> None:
    # precise timestamps (not whole seconds) and 4 m noise: an offset cannot show
    s = _offset_vessels(12, p_off=0.0, sigma=4.0, integer_times=False)
    st = track_vessels(s["vessel"], s["t"], s["z"], CFG)
    assert np.all(st.time_offset == 0.0)
    # offsets of 1 s would show (0.3 m noise) but there are none: the share test
    s = _offset_vessels(13, p_off=0.0)
    st = track_vessels(s["vessel"], s["t"], s["z"], CFG)
    assert np.mean(st.time_offset != 0.0) < CFG.min_offset_share


def _displaced(seed: int, n: int = 400) -> dict[str, np.ndarray]:
    """Reports displaced by d s along known velocities (0.2 m noise, 0.1 s timing)."""
    rng = np.random.default_rng(seed)
    v = np.c_[rng.uniform(3, 8, n), rng.uniform(-2, 2, n)]
    p = rng.normal(0.0, 100.0, (n, 2))
    d = rng.choice([-2.0, -1.0, 0.0, 1.0, 2.0], n, p=[0.02, 0.13, 0.7, 0.13, 0.02])
    z = p - v * d[:, None] + rng.normal(0.0, 0.2, (n, 2))
    sig = np.c_[np.full(n, 0.2), np.full(n, 0.1)]
    return {"v": v, "p": p, "d": d, "z": z, "sig": sig, "state": np.c_[p, v, np.zeros(n)]}


def test_timestamp_offsets_score_against_an_exact_track() -> None:
    """The MAP offset of reports displaced by d s along a known (exact) track is d."""
    s = _displaced(4)
    n = s["d"].size
    zero_cov = np.zeros((n, 2, 2))
    use = np.ones(n, bool)
    got = timestamp_offsets(
        OffsetInputs(s["z"], s["state"], s["sig"], np.zeros(n), use), zero_cov, CFG
    )
    assert np.mean(got == s["d"]) > 0.99
    # against a track made with the true offsets already applied: the same answer
    z_shift = s["z"]
    got2 = timestamp_offsets(
        OffsetInputs(z_shift, s["state"], s["sig"], s["d"], use), zero_cov, CFG
    )
    assert np.array_equal(got, got2)
    # unusable rows and rows without a state are 0
    state = s["state"].copy()
    state[:10] = np.nan
    use[10:20] = False
    holes = OffsetInputs(s["z"], state, s["sig"], np.zeros(n), use)
    got = timestamp_offsets(holes, zero_cov, CFG)
    assert np.all(got[:20] == 0.0)
    off = AisTrackerConfig(max_time_offset_s=0)
    assert np.all(
        timestamp_offsets(OffsetInputs(s["z"], state, s["sig"], np.zeros(n), use), zero_cov, off)
        == 0
    )


def test_timestamp_offsets_leave_one_out_undoes_the_pull_of_the_report() -> None:
    """A smoothed track that used the report sits between the report and the track of the
    other reports: ``r = R (M + R)^-1 e`` with ``A = M (M + R)^-1 R`` its covariance. Given
    ``A``, the leave-one-out residual recovers the offsets that the shrunk residual hides."""
    s = _displaced(5)
    n = s["d"].size
    v = s["v"]
    sp = 0.2
    st = 0.29  # the timestamp sigma of the run that made the track
    R = sp**2 * np.eye(2) + st**2 * v[:, :, None] * v[:, None, :]
    M = np.broadcast_to(np.diag([1.5, 1.5]), (n, 2, 2))  # prediction from the others
    e = s["z"] - s["p"]  # residual against the others' track (= -v d + noise)
    MR = np.linalg.inv(M + R)
    r = np.einsum("nij,njk,nk->ni", R, MR, e)
    A = M @ MR @ R
    sig = np.c_[np.full(n, sp), np.full(n, st)]
    state = np.c_[s["z"] - r, v, np.zeros(n)]  # the smoothed track
    use = np.ones(n, bool)
    inputs = OffsetInputs(s["z"], state, sig, np.zeros(n), use)
    loo = timestamp_offsets(inputs, A, CFG)
    shrunk = timestamp_offsets(inputs, A, CFG, leave_one_out=False)
    print(
        f"right: leave-one-out {np.mean(loo == s['d']):.3f}, "
        f"smoothed {np.mean(shrunk == s['d']):.3f}"
    )
    assert np.mean(loo == s["d"]) > 0.99
    assert np.mean(shrunk == s["d"]) < 0.95


@pytest.mark.parametrize("name", FILES)
def test_real_states_stay_within_physical_limits(name: str) -> None:
    """Speed <= max_speed_kn and |turn rate| <= min(max_turn_rate_dps, max_accel / speed)
    on every output row (the filter and the smoother are both projected)."""
    r, tr = tracked(name)
    ok = np.isfinite(tr.speed)
    vmax = CFG.max_speed_kn * KNOT_MPS
    assert np.all(tr.speed[ok] <= vmax * (1 + 1e-9))
    with np.errstate(divide="ignore"):
        lim = np.minimum(math.radians(CFG.max_turn_rate_dps), CFG.max_accel_mps2 / tr.speed[ok])
    assert np.all(np.abs(tr.turn_rate[ok]) <= lim * (1 + 1e-9))


def test_vessel_groups_share_the_offset_prior_and_equal_one_table() -> None:
    """Tracking vessels in groups (bounded memory, Dask partitions) gives the result of one
    table: the timestamp-offset prior is estimated from the counts of all groups."""
    from seatrack.filters.ais.tracker import VesselInputs
    from seatrack.filters.ais.tracker import track_vessel_groups

    r, _ = tracked("dk_northsea_20221101_1h_selected.csv")
    ok = r.valid
    fr = local_frames(r.mmsi, r.lat, r.lon, ok)
    m, t, xy = r.mmsi[ok], r.t[ok], fr.enu[ok, :2]
    whole = track_vessels(m, t, xy, CFG)
    vessels = np.unique(m)
    parts = [np.isin(m, vessels[k::3]) for k in range(3)]
    groups = track_vessel_groups([VesselInputs(m[p], t[p], xy[p]) for p in parts], CFG)
    assert np.count_nonzero(whole.time_offset) > 100  # the prior matters on this file
    for p, g in zip(parts, groups, strict=True):
        for f in ("state", "std", "outlier_kind", "segment", "nis", "time_offset"):
            assert np.array_equal(getattr(whole, f)[p], getattr(g, f), equal_nan=True), f


def test_vessel_rows_layout_and_largest_vessel_per_chunk():
    from seatrack.filters.ais.kernel import largest_vessel
    from seatrack.filters.ais.kernel import vessel_rows

    vessel = np.array([0, 0, 0, 4, 7, 7], dtype=np.int64)
    starts, chunks, t, xy, mask = vessel_rows(vessel, [0, 1, 2, 3, 4, 5], np.zeros((6, 2)), [1] * 6)
    assert starts.tolist() == [0, 3, 4, 6]
    assert t.dtype == np.float64 and xy.flags.c_contiguous and mask.dtype == np.bool_
    sizes = [largest_vessel(starts, chunks, c) for c in range(chunks.size - 1)]
    assert max(sizes) == 3 and min(sizes) >= 1


def test_take_rows_keeps_whole_vessels_and_recomputes_their_boundaries():
    from seatrack.filters.ais.kernel import KernelInputs
    from seatrack.filters.ais.kernel import take_rows
    from seatrack.filters.ais.kernel import vessel_index

    n = 6
    starts = np.array([0, 3, 4, 6], dtype=np.int64)
    inp = KernelInputs(starts, *(np.arange(n, dtype=float) for _ in KernelInputs._fields[1:]))
    assert vessel_index(starts).tolist() == [0, 0, 0, 1, 2, 2]
    keep = np.array([True, True, True, False, True, True])
    sub = take_rows(inp, keep, toff=np.full(n, 7.0))
    assert sub.starts.tolist() == [0, 3, 5] and sub.t.tolist() == [0, 1, 2, 4, 5]
    assert sub.toff.tolist() == [7.0] * 5
    same = take_rows(inp, None, sig=np.zeros(n))
    assert same.t is inp.t and same.sig.tolist() == [0.0] * n
