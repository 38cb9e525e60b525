"""The fused picture: radar plots and AIS reports in, three tables out (docs/fusion.md).

1. The plots go through the multi-target tracker of the radar's ``radar.toml``
   (:mod:`seatrack.io.multitarget`), in the radar's East-North plane (scan by scan,
   between the AIS updates, for the measurement design).
2. The AIS reports are brought to the same plane (:meth:`Coverage.to_local`), shared MMSIs
   split and jumps removed (:mod:`~seatrack.fusion.anomalies`), and every vessel tracked
   by the project's AIS tracker (:func:`seatrack.filters.ais.track_reports`, forward
   filter only, so that each state uses the reports up to its time).
3. At every radar scan :class:`Fusion` predicts the AIS vessels, associates them with the
   radar tracks and classes both sides. The association is one of two designs
   (``association``): ``track`` (default), the tracker's output against the AIS states
   (:mod:`~seatrack.fusion.associate`); ``measurement``, the tracker run scan by scan with
   the AIS reports since the last scan updating the tracks they are associated with
   (:mod:`~seatrack.fusion.measurement`). The classes are the same for both:

   * a radar track with an AIS vessel is ``ais``; one inside coverage that has had none
     for ``dark_delay_s`` is ``dark``; otherwise (outside coverage, or waiting) ``unknown``;
   * an AIS vessel inside coverage by at least ``edge_margin_m`` (where the detection
     probability is at least ``min_detection_probability``) that has had no radar track
     for ``not_seen_delay_s`` is ``not_seen``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import fields
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.config import ConfigError
from seatrack.config import load_toml
from seatrack.config import parse_config
from seatrack.filters.ais import AisTrackerConfig
from seatrack.filters.ais import track_reports
from seatrack.filters.ais.kernel import OutlierKind
from seatrack.filters.ais.noise import position_noise
from seatrack.filters.ais.tracks import AisTracks
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.registry import Method
from seatrack.fusion.anomalies import gap_limits
from seatrack.fusion.anomalies import reporting_gaps
from seatrack.fusion.anomalies import split_identities
from seatrack.fusion.associate import ASSOCIATIONS
from seatrack.fusion.associate import AisStates
from seatrack.fusion.associate import Assignment
from seatrack.fusion.associate import Associator
from seatrack.fusion.associate import FusionConfig
from seatrack.fusion.associate import Prediction
from seatrack.fusion.associate import predict_ais
from seatrack.fusion.associate import velocity_covariance
from seatrack.fusion.coverage import Coverage
from seatrack.fusion.measurement import AisMeasurements
from seatrack.fusion.measurement import ReportUpdater
from seatrack.fusion.measurement import check_filter
from seatrack.fusion.measurement import measurement_noise
from seatrack.geometry import cart_to_polar
from seatrack.geometry import enu_to_geodetic
from seatrack.geometry import rotation_to_beam
from seatrack.geometry import velocity_from_course
from seatrack.io.ais.reports import AisReports
from seatrack.io.multitarget import TrackerSetup
from seatrack.io.multitarget import make_filter
from seatrack.io.multitarget import run_unlabelled
from seatrack.io.radar import RadarSetup
from seatrack.io.radar import parse_radar_config
from seatrack.tracking import MultiTargetTracker
from seatrack.tracking import TrackStatus

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "AisSide",
    "Fusion",
    "Picture",
    "RadarTracks",
    "ScanResult",
    "prepare_ais",
    "ais_states",
    "STATE_FIELDS",
    "radar_tracks",
    "track_covariance",
    "ais_measurements",
    "fuse_picture",
    "CLASSES",
    "parse_fusion_config",
    "load_fusion_config",
    "with_association",
]

#: radar track classes (the ``class`` column)
CLASSES = ("unknown", "ais", "dark")


@dataclass(frozen=True)
class RadarTracks:
    """Radar track rows (one per track and scan) sorted by time: ``track`` id, ``t`` (s),
    ``status`` label, ``pos`` (n, 2) m and ``cov`` (n, 2, 2) m^2 in the radar's plane."""

    track: IntArray
    t: FloatArray
    status: NDArray[np.str_]
    pos: FloatArray
    cov: FloatArray


def radar_tracks(plots: Plots, setup: RadarSetup, source: str = "radar config") -> RadarTracks:
    """The confirmed and coasting tracks of the multi-target tracker over ``plots`` (the
    radar at the origin of their plane), configured by ``setup``: the tracker of
    :func:`~seatrack.io.multitarget.run_unlabelled` with the site's per-track method."""
    tracking = TrackerSetup(setup.sensor, setup.tracker, setup.method_table, source)
    run = run_unlabelled(plots, setup.site.method, tracking).run
    labels = np.array([s.label for s in TrackStatus])
    n = run.t.size
    c = run.columns
    pos = np.stack([c["x_m"], c["y_m"]], -1) if n else np.zeros((0, 2))
    cov = np.zeros((n, 2, 2))
    if n:
        cov = track_covariance(pos, c["std_x_m"], c["std_y_m"], setup.sensor)
    order = np.argsort(run.t, kind="stable")
    return RadarTracks(run.track[order].astype(np.int64), run.t[order],
                       labels[run.status][order], pos[order], cov[order])  # fmt: skip


def track_covariance(
    pos: FloatArray, std_x: FloatArray, std_y: FloatArray, sensor: SensorNoise
) -> FloatArray:
    """Position covariance (n, 2, 2) of radar tracks from their East and North standard
    deviations (the tracker's output has no cross term).

    A radar track's error ellipse is aligned with its line of sight, as that of its plots
    (``R = B diag(s_r^2, (r s_az)^2) B^T``, ``B`` the rotation to the beam): the covariance
    is taken as ``k R`` with ``k`` matching the trace, ``k = (std_x^2 + std_y^2) / tr R``.
    At 30 km with 0.3 deg of azimuth noise the cross-range axis is eight times the range
    axis; a diagonal covariance would miss that tilt by up to a factor of four in variance.
    """
    r, az = cart_to_polar(pos)
    r = np.maximum(np.atleast_1d(r), 1.0)
    b = rotation_to_beam(np.atleast_1d(az))
    lam = np.stack([np.full(r.shape, sensor.sigma_range**2), (r * sensor.sigma_azimuth) ** 2], -1)
    rr = np.einsum("nki,nk,nkj->nij", b, lam, b)
    k = (np.square(std_x) + np.square(std_y)) / (lam[:, 0] + lam[:, 1])
    return np.asarray(rr * k[:, None, None])


@dataclass(frozen=True)
class AisSide:
    """The AIS reports prepared for fusion, one entry per valid report (``rows`` index the
    input reports) plus the tracked states (:class:`AisStates`), per-vessel names and,
    for the measurement design, the reports as measurements."""

    rows: IntArray
    vessel: IntArray
    gap: NDArray[np.bool_]
    jump: NDArray[np.bool_]
    conflict: NDArray[np.bool_]
    states: AisStates
    vessel_mmsi: IntArray
    vessel_name: NDArray[np.str_]
    measurements: AisMeasurements | None = None


def prepare_ais(reports: AisReports, coverage: Coverage, cfg: FusionConfig) -> AisSide:
    """Split, flag and track the valid AIS reports (module docstring, step 2)."""
    rows = np.flatnonzero(reports.valid)
    r = reports.take(rows)
    xy = coverage.to_local(r.lat, r.lon)
    split = split_identities(r.mmsi, r.t, xy, r.sog_kn, r.cog_deg)
    use = split.vessel >= 0
    kept = np.flatnonzero(use)
    sub = r.take(kept)
    sub.mmsi = split.vessel[kept]  # each trajectory its own vessel
    # the forward filter (no smoother): a state uses only the reports up to its own
    tr = _scatter(track_reports(sub, AisTrackerConfig(smooth=False)), kept, r.t.size)
    bad = np.isin(
        tr.outlier_kind, [OutlierKind.IMPLAUSIBLE_JUMP, OutlierKind.IMPLAUSIBLE_AFTER_GAP]
    )
    jump = split.jump | (use & bad)
    n_v = split.vessel_mmsi.size
    limit = gap_limits(split.vessel[use], r.t[use], n_v, cfg.gap_factor, cfg.min_gap)
    gap = reporting_gaps(np.where(use, split.vessel, -1), r.t, limit)
    ok = use & ~tr.outlier & np.isfinite(tr.lat) & np.isfinite(tr.speed) & np.isfinite(tr.course)
    k = np.flatnonzero(ok)
    k = k[np.lexsort((r.t[k], split.vessel[k]))]
    cols = {f: getattr(tr, f)[k] for f in STATE_FIELDS}
    states = ais_states(coverage, split.vessel[k], r.t[k], cols, limit)
    meas = None
    if cfg.association == "measurement":
        meas = ais_measurements(states, xy[k], np.ones(k.size, bool), cfg)
    names = np.array(
        [
            str(m) if s == 0 else f"{m}#{s + 1}"
            for m, s in zip(split.vessel_mmsi, split.vessel_sub, strict=True)
        ],
        dtype=str,
    )
    return AisSide(rows, split.vessel, gap, jump, split.conflict, states, split.vessel_mmsi,
                   names if names.size else np.zeros(0, str), meas)  # fmt: skip


def ais_measurements(states: AisStates, xy: FloatArray, use: NDArray[np.bool_],
                     cfg: FusionConfig) -> AisMeasurements:  # fmt: skip
    """The reports behind ``states`` (their positions ``xy`` (n, 2) m, same rows) as
    measurements of the radar tracks, sorted by time: the noise of the AIS tracker's model
    (:func:`~seatrack.filters.ais.noise.position_noise`, from each vessel's ``use`` rows)
    with the allowances of ``cfg`` (:func:`~seatrack.fusion.measurement.measurement_noise`)."""
    noise = position_noise(states.vessel, states.t, xy, use, AisTrackerConfig(smooth=False))
    r = measurement_noise(noise[:, 0], noise[:, 1], states.vel, cfg)
    o = np.argsort(states.t, kind="stable")
    return AisMeasurements(states.vessel[o], states.t[o], xy[o], r[o])


#: the AIS tracker output columns :func:`ais_states` reads
STATE_FIELDS = ("lat", "lon", "std_x_m", "std_y_m", "speed", "course", "std_speed", "std_course")


def ais_states(coverage: Coverage, vessel: IntArray, t: FloatArray,
               cols: Mapping[str, FloatArray], limit: FloatArray) -> AisStates:  # fmt: skip
    """:class:`AisStates` of AIS tracker output rows, in the radar's plane of ``coverage``.

    ``cols`` holds the :data:`STATE_FIELDS` columns of :class:`AisTracks` (WGS84 position
    deg, speed m/s, true course rad and their sigmas) of vessels ``vessel`` at times ``t``
    (s), sorted by vessel, then time; ``limit`` per vessel (s). The position covariance is
    diagonal (East, North sigmas); the velocity covariance is
    :func:`~seatrack.fusion.associate.velocity_covariance` (unknown sigmas taken as 0)."""
    c = cols
    n = t.size
    pos = coverage.to_local(c["lat"], c["lon"]).reshape(n, 2)
    pos_cov = np.zeros((n, 2, 2))
    pos_cov[:, 0, 0], pos_cov[:, 1, 1] = c["std_x_m"] ** 2, c["std_y_m"] ** 2
    vel = velocity_from_course(c["course"], c["speed"]).reshape(n, 2)
    vel_cov = velocity_covariance(c["course"], c["speed"], np.nan_to_num(c["std_course"]) ** 2,
                                  np.nan_to_num(c["std_speed"]) ** 2)  # fmt: skip
    return AisStates(vessel, t, pos, vel, pos_cov, vel_cov, limit)


def _scatter(tr: AisTracks, rows: IntArray, n: int) -> AisTracks:
    """``tr`` of the reports ``rows`` spread over ``n`` reports (NaN / 0 elsewhere)."""
    out = {}
    for f in fields(tr):
        a = getattr(tr, f.name)
        full = np.zeros(n, a.dtype) if a.dtype.kind in "bi" else np.full(n, np.nan)
        full[rows] = a
        out[f.name] = full
    return AisTracks(**out)


@dataclass(frozen=True)
class ScanResult:
    """One scan of :meth:`Fusion.step`. Radar rows: ``ais_vessel`` (-1: none),
    ``identity_prob``, ``klass`` (index into :data:`CLASSES`), ``covered``. AIS rows (the
    vessels predicted at this time): ``vessel``, ``pos``, ``covered``, ``radar_row``
    (-1: none), ``not_seen``."""

    ais_vessel: IntArray
    identity_prob: FloatArray
    klass: NDArray[np.int8]
    covered: NDArray[np.bool_]
    vessel: IntArray
    pos: FloatArray
    vessel_covered: NDArray[np.bool_]
    radar_row: IntArray
    not_seen: NDArray[np.bool_]


class Fusion:
    """The per-scan fusion step (module docstring, step 3); state: the pair scores and
    the clocks of the classes."""

    def __init__(self, coverage: Coverage, states: AisStates, config: FusionConfig) -> None:
        self.coverage = coverage
        self.states = states
        self.config = config
        self.assoc = Associator(config)
        n = states.n_vessels
        self._vessel_clock = np.full(n, np.nan)  # last time seen, or entered coverage
        self._track_clock = np.zeros(0)  # per radar track id: last time with an AIS vessel
        self._detect_ok = coverage.site.detection_probability >= config.min_detection_probability

    def set_states(self, states: AisStates) -> None:
        """Replace the AIS states (a live process: the vessels' current states); vessel
        ids keep their meaning, new ids (up to ``states.n_vessels``) start with no clock."""
        grow = states.n_vessels - self._vessel_clock.size
        if grow < 0:
            raise ValueError("Fusion.set_states: fewer vessels than before")
        self._vessel_clock = np.r_[self._vessel_clock, np.full(grow, np.nan)]
        self.states = states

    def step(self, t: float, track: IntArray, pos: FloatArray, cov: FloatArray) -> ScanResult:
        """Fuse the radar tracks of the scan at ``t`` (ids, positions (n, 2), covariances)
        by the track design (:class:`~seatrack.fusion.associate.Associator`)."""
        pred = predict_ais(self.states, t, self.config)
        a = self.assoc.step(track, pos, cov, pred.vessel, pred.pos, pred.cov)
        return self.classify(t, track, pos, pred, a)

    def classify(self, t: float, track: IntArray, pos: FloatArray, pred: Prediction,
                 a: Assignment) -> ScanResult:  # fmt: skip
        """The classes of the radar tracks ``track`` (positions ``pos``) and of the AIS
        vessels ``pred`` predicted to ``t`` given their assignment ``a`` (either design)."""
        cfg = self.config
        has = a.ais_row >= 0
        if track.size and int(track.max()) >= self._track_clock.size:
            grow = np.full(int(track.max()) + 1 - self._track_clock.size, np.nan)
            self._track_clock = np.r_[self._track_clock, grow]
        clock = self._track_clock
        new = np.isnan(clock[track])
        clock[track[new | has]] = t
        covered = self.coverage.covered(pos[:, 0], pos[:, 1])
        dark = ~has & covered & (t - clock[track] >= cfg.dark_delay)
        klass = np.where(has, 1, np.where(dark, 2, 0)).astype(np.int8)
        vessel_of = np.full(track.size, -1, np.int64)  # (no AIS vessel predicted: none)
        vessel_of[has] = pred.vessel[a.ais_row[has]]

        m = pred.vessel.size
        radar_row = np.full(m, -1, np.int64)
        radar_row[a.ais_row[has]] = np.flatnonzero(has)
        v_cov = self.coverage.covered(pred.pos[:, 0], pred.pos[:, 1], cfg.edge_margin)
        v_cov &= self._detect_ok
        vclock = self._vessel_clock
        was_active = np.zeros(self.states.n_vessels, bool)
        was_active[np.flatnonzero(np.isfinite(vclock))] = True
        restart = ~was_active[pred.vessel] | (radar_row >= 0) | ~v_cov
        active = np.zeros(self.states.n_vessels, bool)
        active[pred.vessel] = True
        vclock[~active] = np.nan
        vclock[pred.vessel[restart]] = t
        not_seen = v_cov & (radar_row < 0) & (t - vclock[pred.vessel] >= cfg.not_seen_delay)
        return ScanResult(vessel_of, a.identity_prob, klass, covered, pred.vessel, pred.pos,
                          v_cov, radar_row, not_seen)  # fmt: skip


@dataclass(frozen=True)
class Picture:
    """Everything :func:`fuse_picture` found (arrays; :mod:`seatrack.api.fuse` makes the
    tables). Radar rows follow :class:`RadarTracks`; AIS vessel rows are one per vessel
    and scan while the vessel is predicted; report flags follow :class:`AisSide`."""

    radar: RadarTracks
    radar_vessel: IntArray
    identity_prob: FloatArray
    klass: NDArray[np.int8]
    radar_covered: NDArray[np.bool_]
    ais: AisSide
    reports: AisReports
    v_time: FloatArray
    v_vessel: IntArray
    v_pos: FloatArray
    v_covered: NDArray[np.bool_]
    v_track: IntArray
    v_not_seen: NDArray[np.bool_]
    origin_deg: tuple[float, float]
    seconds_per_scan: FloatArray

    def geodetic(self, pos: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(lat, lon) degrees of positions (n, 2) in the radar's plane."""
        if pos.shape[0] == 0:
            return np.zeros(0), np.zeros(0)
        lat, lon, _ = enu_to_geodetic(pos, *self.origin_deg)
        return lat, lon


def fuse_picture(reports: AisReports, plots: Plots, setup: RadarSetup,
                 config: FusionConfig | None = None, source: str = "radar config",
                 coverage: Coverage | None = None) -> Picture:  # fmt: skip
    """Prepare the AIS reports, track the plots and fuse them scan by scan by the design
    of ``config.association`` (docs/fusion.md)."""
    cfg = config or FusionConfig()
    flt = None
    if cfg.association == "measurement":  # a filter the design cannot update: refused first
        flt = make_filter(setup.site.method, setup.method_table, plots, source, setup.tracker)[0]
        try:
            check_filter(flt.filter)
        except ConfigError as exc:
            raise ConfigError(f"{source}: fusion: {exc}") from None
    cov = coverage or Coverage.of(setup.site, cfg.land_mask, cfg.land_cell)
    ais = prepare_ais(reports, cov, cfg)
    fusion = Fusion(cov, ais.states, cfg)
    if flt is not None:
        scans = list(_measurement_scans(plots, setup, flt, ais, fusion))
    else:
        scans = list(_track_scans(plots, setup, fusion, source))
    empty = np.zeros(0, np.int64)
    radar = RadarTracks(
        *(np.concatenate([getattr(s.radar, f.name) for s in scans]) if scans else z
          for f, z in zip(fields(RadarTracks), (empty, np.zeros(0), np.zeros(0, str),
                                                np.zeros((0, 2)), np.zeros((0, 2, 2))),
                          strict=True))
    )  # fmt: skip
    res = [s.result for s in scans]

    def cat(name: str, dtype: Any, shape: tuple[int, ...] = (0,)) -> NDArray[Any]:
        parts = [getattr(x, name) for x in res]
        return np.concatenate(parts).astype(dtype) if parts else np.zeros(shape, dtype)

    trk = [np.where(s.result.radar_row >= 0, s.radar.track[np.maximum(s.result.radar_row, 0)]
                    if s.radar.track.size else -1, -1) for s in scans]  # fmt: skip
    v_time = [np.full(s.result.vessel.size, s.radar_t) for s in scans]
    origin = (math.degrees(setup.site.lat), math.degrees(setup.site.lon))
    return Picture(
        radar, cat("ais_vessel", np.int64), cat("identity_prob", float), cat("klass", np.int8),
        cat("covered", bool), ais, reports,
        np.concatenate(v_time) if scans else np.zeros(0), cat("vessel", np.int64),
        cat("pos", float, (0, 2)).reshape(-1, 2), cat("vessel_covered", bool),
        np.concatenate(trk).astype(np.int64) if scans else empty, cat("not_seen", bool),
        origin, np.array([s.seconds for s in scans]),
    )  # fmt: skip


@dataclass(frozen=True)
class _Scan:
    """One scan of the run: its time, radar rows, fusion result and the wall time (s) of
    the fusion step."""

    radar_t: float
    radar: RadarTracks
    result: ScanResult
    seconds: float


def _track_scans(plots: Plots, setup: RadarSetup, fusion: Fusion,
                 source: str) -> Iterator[_Scan]:  # fmt: skip
    """The track design: the whole tracker run, then :meth:`Fusion.step` at each scan."""
    radar = radar_tracks(plots, setup, source)
    scan_times = np.unique(plots.t)
    bounds = np.searchsorted(radar.t, scan_times), np.searchsorted(radar.t, scan_times, "right")
    for t, a, b in zip(scan_times, *bounds, strict=True):
        rows = RadarTracks(*(getattr(radar, f.name)[a:b] for f in fields(RadarTracks)))
        tic = time.perf_counter()
        res = fusion.step(float(t), rows.track, rows.pos, rows.cov)
        yield _Scan(float(t), rows, res, time.perf_counter() - tic)


def _measurement_scans(plots: Plots, setup: RadarSetup, flt: Method, ais: AisSide,
                       fusion: Fusion) -> Iterator[_Scan]:  # fmt: skip
    """The measurement design: at each scan the AIS reports since the last one update the
    confirmed radar tracks (:class:`~seatrack.fusion.measurement.ReportUpdater`), the
    tracker (per-track filter ``flt``) takes the scan's plots and :meth:`Fusion.classify`
    the reported tracks."""
    updater = ReportUpdater(flt.filter, ais.measurements or _no_reports(), fusion.config)
    tracker = MultiTargetTracker(flt.filter, setup.sensor, setup.tracker)
    prepared = flt.prepare(plots)
    order = np.argsort(prepared.t, kind="stable")
    times, starts = np.unique(prepared.t[order], return_index=True)
    bounds = np.append(starts, order.size)
    labels = np.array([s.label for s in TrackStatus])
    for k, t in enumerate(times):
        tic = time.perf_counter()
        if tracker.state is not None:
            tr = tracker.tracks
            tracker.state = updater.update(tracker.state, tr.id, tr.confirmed, float(t))
        else:
            updater.skip(float(t))
        seconds = time.perf_counter() - tic
        res = tracker.step(float(t), prepared.take(order[bounds[k] : bounds[k + 1]]))
        tic = time.perf_counter()
        rep = np.flatnonzero(res.status != int(TrackStatus.TENTATIVE))
        st = res.state.take(rep)
        rows = RadarTracks(res.track[rep].astype(np.int64), np.full(rep.size, float(t)),
                           labels[res.status[rep]], st.x[:, :2], st.P[:, :2, :2])  # fmt: skip
        pred = predict_ais(fusion.states, float(t), fusion.config)
        updater.prune(res.track, pred.vessel)
        a = updater.assignment(rows.track, pred.vessel)
        out = fusion.classify(float(t), rows.track, rows.pos, pred, a)
        yield _Scan(float(t), rows, out, seconds + time.perf_counter() - tic)


def _no_reports() -> AisMeasurements:
    return AisMeasurements(np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 2)),
                           np.zeros((0, 2, 2)))  # fmt: skip


def parse_fusion_config(
    table: Mapping[str, Any], source: str = "radar config"
) -> tuple[RadarSetup, FusionConfig]:
    """The radar (:func:`seatrack.io.radar.parse_radar_config`) and its ``[fusion]``
    table (:class:`FusionConfig`) from one parsed ``radar.toml``."""
    rest = dict(table)
    tab = rest.pop("fusion", {})
    if not isinstance(tab, Mapping):
        raise ConfigError(f"{source}: [fusion] must be a table")
    setup = parse_radar_config(rest, source)
    return setup, parse_config(FusionConfig, tab, source=f"{source}: fusion")


def with_association(cfg: FusionConfig, association: str) -> FusionConfig:
    """``cfg`` with the association design ``association`` (one of
    :data:`~seatrack.fusion.associate.ASSOCIATIONS`; ConfigError otherwise)."""
    if association not in ASSOCIATIONS:
        raise ConfigError(f"association: {association!r} is not one of {', '.join(ASSOCIATIONS)}")
    return replace(cfg, association=association)


def load_fusion_config(path: str | Path) -> tuple[RadarSetup, FusionConfig]:
    """:func:`parse_fusion_config` of a ``radar.toml`` file (errors name the file and key)."""
    return parse_fusion_config(load_toml(path), source=str(path))
