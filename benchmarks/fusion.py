"""Radar-AIS fusion on real traffic: identities, dark, spoofed and shared vessels; speed.

1. **Accuracy.** The bundled hour of Danish North Sea AIS (``dk_northsea_20221101_1h_all``,
   202 vessels; provenance in ``seatrack/data/ais/README.md``), smoothed by the project's AIS
   tracker, is the truth. The real scene has at most a dozen moving vessels within 30 km of
   any one point, too few to measure rates, so each vessel's trajectory is translated (not
   rotated, not re-timed) to a random place within 3-36 km of a radar on an offshore
   platform (56.2 N, 7.1 E, open sea; antenna 40 m, 40 km range, horizon 33 km for 5 m
   targets): real kinematics and reporting, denser traffic (a new draw per seed). The
   radar's plots are simulated every 3 s (detection
   probability 0.9, 20 m / 0.3 deg noise, 20 clutter plots a scan, uniform in range and
   azimuth). Fresh AIS reports are drawn from the truth at each vessel's own median
   reporting interval (10 m noise). Of the vessels the radar covers at mid-hour, a share
   is made **dark** (no AIS at all), **silent** (AIS stops for 15 min from a random time),
   **spoofed** (AIS positions moved 1-5 km from a random time on) and five pairs **share
   an MMSI** (the second vessel transmits the first one's). ``seatrack.fusion`` then runs
   on the plots and the reports (``seatrack fuse``'s path, in process).

   Radar rows are matched to the nearest truth vessel within 250 m. Reported:

   * identity: the share of matched radar rows carrying an AIS identity whose identity
     is the truth vessel's (target >= 99 %);
   * dark: precision and recall of ``class == dark`` over matched rows, a row truly dark
     when its vessel has no AIS at its true position (dark, not yet reported, silent, or
     spoofed at that time); rows within 60 s of a track's start or of a change of the
     truth class are not counted (target: >= 0.95 each, i.e. detected within 60 s); and
     the time from going dark (or from the track's start, if later) to the first ``dark``
     row;
   * spoofed: precision and recall of ``not_seen`` over AIS vessel rows inside coverage,
     positive while the vessel's AIS is moved (60 s grace after the move) (>= 0.95);
   * shared: the share of the shared MMSIs' reports given to the right one of the two
     split vessels (>= 95 %);
   * RMSE: the radar tracks' position error against the truth over the matched rows (and
     over those with an AIS identity) -- what the measurement design changes.

   Both association designs (``[fusion] association``: ``track``, ``measurement``) run
   on the same plots and reports of each seed (``--association`` picks one).

2. **Speed.** The fusion step alone for 1,000 vessels within 38 km of the radar, 200
   scans; median and 95th percentile per scan (target <= 20 ms). Track design:
   :meth:`seatrack.fusion.picture.Fusion.step` (prediction of every AIS vessel, gating,
   scores, assignment, classes and coverage) on radar positions and AIS states drawn
   directly. Measurement design: the AIS reports since the last scan applied to 1,000
   radar track states of the site's per-track filter (gating, scores, assignment, Kalman
   updates), the identities and :meth:`~seatrack.fusion.picture.Fusion.classify`.

    python benchmarks/fusion.py                  # seeds 1-2 (tuned on) and 3-5 (reported)
    python benchmarks/fusion.py --seeds 3 4 5    # the untuned seeds, both designs
    python benchmarks/fusion.py --seeds 3 --quick --association measurement

The defaults of ``[fusion]`` were chosen on seeds 1 and 2 (rows marked ``tuned``);
seeds 3 and later were run only for reporting.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from dataclasses import replace  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from seatrack.data import ais_sample  # noqa: E402
from seatrack.filters.ais import track_reports  # noqa: E402
from seatrack.filters.base import Plots  # noqa: E402
from seatrack.fusion import scenario as sc  # noqa: E402
from seatrack.fusion.associate import ASSOCIATIONS  # noqa: E402
from seatrack.fusion.associate import AisStates  # noqa: E402
from seatrack.fusion.associate import FusionConfig  # noqa: E402
from seatrack.fusion.associate import predict_ais  # noqa: E402
from seatrack.fusion.coverage import Coverage  # noqa: E402
from seatrack.fusion.measurement import AisMeasurements  # noqa: E402
from seatrack.fusion.measurement import ReportUpdater  # noqa: E402
from seatrack.fusion.measurement import measurement_noise  # noqa: E402
from seatrack.fusion.picture import Fusion  # noqa: E402
from seatrack.fusion.picture import Picture  # noqa: E402
from seatrack.fusion.picture import fuse_picture  # noqa: E402
from seatrack.fusion.picture import parse_fusion_config  # noqa: E402
from seatrack.geometry import KNOT_MPS  # noqa: E402
from seatrack.geometry import polar_to_cart  # noqa: E402
from seatrack.io.ais import read_ais  # noqa: E402
from seatrack.io.multitarget import make_filter  # noqa: E402

SITE = {
    "lat_deg": 56.2, "lon_deg": 7.1, "antenna_height_m": 40.0, "max_range_m": 40000.0,
    "sigma_range_m": 20.0, "sigma_azimuth_deg": 0.3, "detection_probability": 0.9,
}  # fmt: skip
ORIGIN = (SITE["lat_deg"], SITE["lon_deg"])
SCAN_S = 3.0
CLUTTER = 20.0
GRACE_S = 60.0
MATCH_M = 250.0
TUNED_SEEDS = (1, 2)


def real_truth() -> tuple[sc.Truth, np.ndarray]:
    """Smoothed tracks of the North Sea hour, each in its own local plane (m), and each
    vessel's median reporting interval (s, clipped to 2..180)."""
    rep = read_ais([ais_sample("dk_northsea_20221101_1h_all.csv")])
    r = rep.take(np.flatnonzero(rep.valid))
    tr = track_reports(r)
    ok = np.isfinite(tr.x_m) & ~tr.outlier
    xy = np.stack([tr.x_m[ok], tr.y_m[ok]], -1)
    mmsi, t = r.mmsi[ok], r.t[ok]
    order = np.lexsort((t, mmsi))
    mmsi, t, xy = mmsi[order], t[order], xy[order]
    first = np.r_[True, (mmsi[1:] != mmsi[:-1]) | (np.diff(t) > 0)]
    mmsi, t, xy = mmsi[first], t[first], xy[first]
    # a real identity collision (two ships on one MMSI) has no knowable truth: left out
    step = np.hypot(*np.diff(xy, axis=0).T)
    fast = np.r_[False, (mmsi[1:] == mmsi[:-1]) & (step > 50 * KNOT_MPS * np.diff(t) + 500.0)]
    keep = ~np.isin(mmsi, mmsi[fast])
    mmsi, t, xy = mmsi[keep], t[keep], xy[keep]
    ids, vessel = np.unique(mmsi, return_inverse=True)
    interval = np.array([np.median(np.diff(t[vessel == v])) if (vessel == v).sum() > 1
                         else 10.0 for v in range(ids.size)])  # fmt: skip
    truth = sc.Truth(vessel.astype(np.int64), t, xy, ids.astype(np.int64))
    return truth, np.clip(interval, 2.0, 180.0)


def relocate(truth: sc.Truth, rng: np.random.Generator) -> sc.Truth:
    """Each vessel's trajectory translated (not rotated) so that its median position lies
    uniformly at random within 3-36 km of the radar: the real kinematics and reporting,
    denser than the real scene around any one place."""
    n = truth.mmsi.size
    centre = polar_to_cart(np.sqrt(rng.uniform(3.0**2, 36.0**2, n)) * 1000.0,
                           rng.uniform(0, 2 * math.pi, n))  # fmt: skip
    med = np.array([np.median(truth.pos[truth.vessel == v], axis=0) for v in range(n)])
    pos = truth.pos - med[truth.vessel] + centre[truth.vessel]
    return sc.Truth(truth.vessel, truth.t, pos, truth.mmsi)


@dataclass
class Scene:
    corruption: sc.Corruption
    who: np.ndarray
    picture: Picture
    seconds: float


@dataclass
class Inputs:
    """One seed's truth, its corruption and the simulated plots and reports."""

    truth: sc.Truth
    corruption: sc.Corruption
    who: np.ndarray
    reports: Any
    plots: Any


def fuse_scene(inputs: Inputs, cov: Coverage, setup: Any, cfg: FusionConfig) -> Scene:
    """The fused picture of one seed's inputs (by ``cfg.association``)."""
    tic = time.perf_counter()
    pic = fuse_picture(inputs.reports, inputs.plots, setup, cfg, coverage=cov)
    return Scene(inputs.corruption, inputs.who, pic, time.perf_counter() - tic)


def make_inputs(
    real: sc.Truth, interval: np.ndarray, cov: Coverage, setup: Any, seed: int
) -> Inputs:
    """A relocated truth, its corruption, plots and reports."""
    rng = np.random.default_rng(seed)
    truth = relocate(real, rng)
    t0, t1 = truth.t.min(), truth.t.max()
    mid = 0.5 * (t0 + t1)
    alive, pos, vel = sc.interpolate(truth, mid)
    moving = np.hypot(vel[:, 0], vel[:, 1]) > 1.0
    whole = np.array([truth.t[truth.vessel == v].min() < t0 + 300 and
                      truth.t[truth.vessel == v].max() > t1 - 300 for v in alive])  # fmt: skip
    cand = alive[cov.covered(pos[:, 0], pos[:, 1]) & moving & whole]
    cand = rng.permutation(cand)
    k = max(2, int(round(0.1 * cand.size)))
    dark, silent, spoof = cand[:k], cand[k : 2 * k], cand[2 * k : 3 * k]
    pairs = cand[3 * k : 3 * k + 10].reshape(-1, 2)
    s_start = t0 + rng.uniform(600, 1800, silent.size)
    p_start = t0 + rng.uniform(600, 1800, spoof.size)
    ang = rng.uniform(0, 2 * math.pi, spoof.size)
    dist = rng.uniform(1000.0, 5000.0, spoof.size)
    off = polar_to_cart(dist, ang)
    corr = sc.Corruption(
        dark=tuple(int(v) for v in dark), silent=tuple(int(v) for v in silent),
        silent_start=tuple(s_start), silent_end=tuple(s_start + 900.0),
        spoof=tuple(int(v) for v in spoof), spoof_offset=tuple(map(tuple, off)),
        spoof_start=tuple(p_start), spoof_end=tuple(np.full(spoof.size, t1 + 1.0)),
        shared=tuple((int(a), int(b)) for a, b in pairs),
    )  # fmt: skip
    scans = np.arange(math.ceil(t0), t1, SCAN_S)
    plots, _ = sc.simulate_plots(truth, scans, cov, setup.sensor, CLUTTER, rng)
    rep, who = sc.ais_reports(truth, interval, ORIGIN, corr, 10.0, rng)
    return Inputs(truth, corr, who, rep, plots)


def _truly_dark(
    c: sc.Corruption, v: np.ndarray, t: np.ndarray, first_report: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Whether vessel ``v`` has no AIS at its true position at ``t`` (dark, before its
    first report, silent, or spoofed); and the time of the last change of that state
    (-inf for none)."""
    dark = np.isin(v, c.dark)
    first = first_report[np.maximum(v, 0)]
    dark |= t < first
    change = np.where(t >= first, first, -np.inf)
    for vs, a, b in ((c.silent, c.silent_start, c.silent_end), (c.spoof, c.spoof_start,
                                                                c.spoof_end)):  # fmt: skip
        for x, s, e in zip(vs, a, b, strict=True):
            m = v == x
            dark[m] |= (t[m] >= s) & (t[m] < e)
            change[m] = np.where(t[m] >= e, e, np.where(t[m] >= s, s, change[m]))
    return dark, change


def _prf(pred: np.ndarray, true: np.ndarray) -> tuple[float, float, int, int]:
    tp = int((pred & true).sum())
    return (tp / max(int(pred.sum()), 1), tp / max(int(true.sum()), 1), int(pred.sum()),
            int(true.sum()))  # fmt: skip


def evaluate(scene: Scene, truth: sc.Truth) -> dict[str, Any]:
    pic, c = scene.picture, scene.corruption
    r = pic.radar
    match = np.full(r.t.size, -1, np.int64)
    err = np.full(r.t.size, np.nan)
    for t in np.unique(r.t):
        rows = np.flatnonzero(r.t == t)
        alive, pos, _ = sc.interpolate(truth, float(t))
        if alive.size == 0:
            continue
        d, k = cKDTree(pos).query(r.pos[rows])
        match[rows] = np.where(d < MATCH_M, alive[np.minimum(k, alive.size - 1)], -1)
        err[rows] = d
    # the true vessel of each AIS vessel (majority of its reports)
    a = pic.ais
    n_v = a.vessel_mmsi.size
    true_of = np.full(n_v, -1, np.int64)
    who = scene.who[a.rows]
    for v in range(n_v):
        w = who[a.vessel == v]
        if w.size:
            true_of[v] = int(np.bincount(w).argmax())
    m = match >= 0
    track_start = {int(k): float(r.t[r.track == k].min()) for k in np.unique(r.track)}
    start = np.array([track_start[int(k)] for k in r.track])
    first_report = np.full(truth.mmsi.size, np.inf)
    np.minimum.at(first_report, scene.who, pic.reports.t)
    dark_true, change = _truly_dark(c, match, r.t, first_report)
    settled = m & (r.t - np.maximum(start, change) >= GRACE_S)
    named = m & (pic.radar_vessel >= 0) & ~dark_true
    right = true_of[np.maximum(pic.radar_vessel, 0)] == match
    out: dict[str, Any] = {"identity": float(right[named].mean()), "named_rows": int(named.sum())}
    # position error of the radar tracks against the truth (matched rows; those with AIS)
    out["rmse_m"] = float(np.sqrt(np.mean(err[m] ** 2)))
    out["rmse_ais_m"] = float(np.sqrt(np.mean(err[m & (pic.klass == 1)] ** 2)))
    p, rc, npred, ntrue = _prf((pic.klass == 2)[settled], dark_true[settled])
    out.update(dark_precision=p, dark_recall=rc, dark_rows=ntrue)
    # time to detect: per episode, from going dark (or the track's start, if later) to
    # the first dark row of the vessel's tracks
    lat: list[float] = []
    episodes = (
        [(v, -np.inf) for v in c.dark]
        + list(zip(c.silent, c.silent_start))
        + list(zip(c.spoof, c.spoof_start))
    )
    for v, s0 in episodes:
        rows = np.flatnonzero((match == v) & dark_true & (r.t >= s0))
        if rows.size == 0:
            continue
        onset = np.maximum(start[rows], s0).min()
        hit = rows[pic.klass[rows] == 2]
        lat.append(float(r.t[hit].min() - onset) if hit.size else math.inf)
    out["episodes"] = len(lat)
    out["sizes"] = f"{len(c.dark)}/{len(c.silent)}/{len(c.spoof)}/{len(c.shared)}"
    out["detect_median_s"] = float(np.median(lat)) if lat else math.nan
    out["detect_max_s"] = float(np.max(lat)) if lat else math.nan
    out["detect_within_60s"] = float(np.mean(np.array(lat) <= 60.0)) if lat else math.nan
    # spoofed: not_seen over AIS vessel rows inside coverage
    tv = true_of[pic.v_vessel]
    spoofed = np.zeros(tv.size, bool)
    grace = np.zeros(tv.size, bool)
    for x, s in zip(c.spoof, c.spoof_start, strict=True):
        mm = tv == x
        spoofed[mm] = pic.v_time[mm] >= s
        grace[mm] = (pic.v_time[mm] >= s) & (pic.v_time[mm] < s + GRACE_S)
    first_seen = {
        int(v): float(pic.v_time[pic.v_vessel == v].min()) for v in np.unique(pic.v_vessel)
    }
    fresh = pic.v_time - np.array([first_seen[int(v)] for v in pic.v_vessel]) < GRACE_S
    # a vessel's truth ends where its data ends: its AIS predicted beyond is not judged
    v_end = np.array([truth.t[truth.vessel == v].max() for v in range(truth.mmsi.size)])
    v_start = np.array([truth.t[truth.vessel == v].min() for v in range(truth.mmsi.size)])
    known = (tv >= 0) & (pic.v_time <= v_end[tv]) & (pic.v_time >= v_start[tv])
    use = pic.v_covered & ~grace & ~fresh & known
    p, rc, npred, ntrue = _prf(pic.v_not_seen[use], spoofed[use])
    out.update(spoof_precision=p, spoof_recall=rc, spoof_rows=ntrue)
    # shared MMSIs: reports given to the right split vessel
    ok = []
    for x, y in c.shared:
        mm = np.isin(who, (x, y)) & (a.vessel >= 0)
        ok.append(true_of[a.vessel[mm]] == who[mm])
    out["shared"] = float(np.concatenate(ok).mean()) if ok else math.nan
    out["per_scan_ms"] = 1e3 * float(np.median(pic.seconds_per_scan))
    out["seconds"] = scene.seconds
    return out


def _speed_scene(n: int, scans: int) -> tuple[Any, ...]:
    """``n`` vessels within 38 km of the radar, straight and steady: start positions,
    velocities, their AIS reports (10 m noise; rows sorted by vessel, time) as
    :class:`AisStates`, and a random generator."""
    rng = np.random.default_rng(0)
    r0 = 38000.0 * np.sqrt(rng.uniform(0.01, 1.0, n))
    p0 = polar_to_cart(r0, rng.uniform(0, 2 * math.pi, n))
    vel = polar_to_cart(rng.uniform(0, 20, n) * KNOT_MPS, rng.uniform(0, 2 * math.pi, n))
    period = rng.choice([2.0, 6.0, 10.0], n)
    horizon = scans * SCAN_S
    vessel, tt, pos, vv = [], [], [], []
    for v in range(n):
        t = np.arange(rng.uniform(0, period[v]), horizon, period[v])
        vessel.append(np.full(t.size, v))
        tt.append(t)
        pos.append(p0[v] + vel[v] * t[:, None] + rng.normal(0, 10, (t.size, 2)))
        vv.append(np.tile(vel[v], (t.size, 1)))
    m = sum(x.size for x in tt)
    states = AisStates(
        np.concatenate(vessel), np.concatenate(tt), np.concatenate(pos), np.concatenate(vv),
        np.tile(np.eye(2) * 100.0, (m, 1, 1)), np.tile(np.eye(2) * 0.04, (m, 1, 1)),
        np.full(n, 30.0),
    )  # fmt: skip
    return p0, vel, states, rng


def speed(
    cov: Coverage, cfg: FusionConfig, setup: Any, n: int = 1000, scans: int = 200
) -> np.ndarray:
    """Seconds per scan of the fusion step with ``n`` vessels (radar and AIS drawn directly).

    Track design: :meth:`Fusion.step` on radar positions drawn about the truth. Measurement
    design: the AIS reports since the last scan applied to ``n`` radar tracks of the
    site's per-track filter (the tracker's default: the adaptive process noise over the
    EKF) (:class:`ReportUpdater`), the identities and :meth:`Fusion.classify`; the radar
    tracks are predicted to the scan outside the timing (the tracker's part)."""
    p0, vel, states, rng = _speed_scene(n, scans)
    fusion = Fusion(cov, states, cfg)
    ids = np.arange(n, dtype=np.int64)
    rcov = np.tile(np.eye(2) * 625.0, (n, 1, 1))
    out = np.zeros(scans)
    if cfg.association == "measurement":
        o = np.argsort(states.t, kind="stable")
        r = measurement_noise(np.full(o.size, 10.0), np.full(o.size, 0.5), states.vel[o], cfg)
        meas = AisMeasurements(states.vessel[o], states.t[o], states.pos[o], r)
        scan_t = np.repeat(np.arange(scans) * SCAN_S, 2)
        dummy = Plots(scan_t, np.full(scan_t.size, 1000.0), np.zeros(scan_t.size))
        flt = make_filter(setup.site.method, setup.method_table, dummy, "site",
                          setup.tracker)[0].filter  # fmt: skip
        x0 = np.concatenate([p0 + rng.normal(0, 25, (n, 2)), vel], -1)
        track = flt.initiate(np.zeros(n), x0, np.tile(np.diag([625.0, 625.0, 4.0, 4.0]),
                                                       (n, 1, 1)))  # fmt: skip
        updater = ReportUpdater(flt, meas, cfg)
        everyone = np.ones(n, bool)
    for k in range(scans):
        t = 10.0 + k * SCAN_S
        if cfg.association == "measurement":
            tic = time.perf_counter()
            track = updater.update(track, ids, everyone, t)
            pred = predict_ais(states, t, cfg)
            updater.prune(ids, pred.vessel)
            a = updater.assignment(ids, pred.vessel)
            fusion.classify(t, ids, track.x[:, :2], pred, a)
            out[k] = time.perf_counter() - tic
            track = flt.predict(track, np.full(n, t))
            continue
        z = p0 + vel * t + rng.normal(0, 25, (n, 2))
        tic = time.perf_counter()
        fusion.step(t, ids, z, rcov)
        out[k] = time.perf_counter() - tic
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, nargs="*", default=[1, 2, 3, 4, 5])
    ap.add_argument("--quick", action="store_true", help="skip the speed case")
    ap.add_argument("--association", choices=(*ASSOCIATIONS, "both"), default="both",
                    help="the design(s) to run (default both, side by side)")  # fmt: skip
    ap.add_argument("--fusion", nargs="*", default=[], metavar="KEY=VALUE",
                    help="[fusion] keys to change (numbers), e.g. dark_delay_s=5")  # fmt: skip
    args = ap.parse_args()
    keys = {k: float(v) for k, v in (kv.split("=", 1) for kv in args.fusion)}
    setup, cfg = parse_fusion_config({**SITE, "fusion": keys}, "benchmark site")
    if keys:
        print(f"[fusion] changed: {keys}")
    cov = Coverage.of(setup.site, cfg.land_mask, cfg.land_cell)
    real, interval = real_truth()
    print(
        f"truth: {real.mmsi.size} vessels, {real.t.size} smoothed states, median reporting "
        f"interval {np.median(interval):.0f} s; radar horizon {cov.horizon_m / 1000:.1f} km"
    )
    head = ("seed", "design", "dark/silent/spoofed/shared pairs", "identity (rows)",
            "dark P", "dark R", "(rows)", "detect med/max s", "<=60s (episodes)", "spoof P",
            "spoof R", "(rows)", "shared", "RMSE m (with AIS)", "ms/scan", "run s")  # fmt: skip
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(" | ".join(head))
    designs = ASSOCIATIONS if args.association == "both" else (args.association,)
    rows: dict[str, list[dict[str, Any]]] = {d: [] for d in designs}
    for seed in args.seeds:
        inputs = make_inputs(real, interval, cov, setup, seed)
        for design in designs:
            scene = fuse_scene(inputs, cov, setup, replace(cfg, association=design))
            e = evaluate(scene, inputs.truth)
            if seed not in TUNED_SEEDS:
                rows[design].append(e)
            tag = f"{seed}{' (tuned)' if seed in TUNED_SEEDS else ''}"
            print(f"{tag} | {design} | {e['sizes']} | {100 * e['identity']:.2f} % "
                  f"({e['named_rows']}) | {e['dark_precision']:.3f} | {e['dark_recall']:.3f} | "
                  f"({e['dark_rows']}) | {e['detect_median_s']:.0f}/{e['detect_max_s']:.0f} | "
                  f"{e['detect_within_60s']:.2f} ({e['episodes']}) | "
                  f"{e['spoof_precision']:.3f} | {e['spoof_recall']:.3f} | ({e['spoof_rows']}) | "
                  f"{100 * e['shared']:.1f} % | {e['rmse_m']:.1f} ({e['rmse_ais_m']:.1f}) | "
                  f"{e['per_scan_ms']:.2f} | {e['seconds']:.0f}", flush=True)  # fmt: skip
    print(
        "targets: identity >= 99 %, dark P/R >= 0.95 (within 60 s), spoof P/R >= 0.95, "
        "shared >= 95 %"
    )
    for design, es in rows.items():
        if es:
            worst = {k: min(e[k] for e in es) for k in ("identity", "dark_precision",
                     "dark_recall", "spoof_precision", "spoof_recall", "shared")}  # fmt: skip
            print(f"untuned seeds, {design}: worst identity {100 * worst['identity']:.2f} %, "
                  f"dark P/R {worst['dark_precision']:.3f}/{worst['dark_recall']:.3f}, spoof P/R "
                  f"{worst['spoof_precision']:.3f}/{worst['spoof_recall']:.3f}, shared "
                  f"{100 * worst['shared']:.1f} %, largest detect "
                  f"{max(e['detect_max_s'] for e in es):.0f} s, mean RMSE "
                  f"{np.mean([e['rmse_m'] for e in es]):.1f} m (rows with AIS "
                  f"{np.mean([e['rmse_ais_m'] for e in es]):.1f} m)")  # fmt: skip
    if not args.quick:
        for design in designs:
            s = speed(cov, replace(cfg, association=design), setup)
            print(
                f"fusion step ({design}), 1,000 vessels: median {1e3 * np.median(s):.1f} ms, "
                f"95th percentile {1e3 * np.percentile(s, 95):.1f} ms per scan (target <= 20 "
                f"ms); load average {os.getloadavg()[0]:.1f}"
            )


if __name__ == "__main__":
    main()
