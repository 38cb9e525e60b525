r"""AIS reports as measurements of the radar tracks (``association = "measurement"``).

The second association design of docs/fusion.md. Between two radar scans, every AIS
report ``z`` (time ``t_z``, position in the radar's plane) is

1. compared with every confirmed radar track predicted to ``t_z`` by the track's own
   filter, ``x^- = f(x, t_z)``, ``P^-``: the AIS measurement model is the position,
   ``z = H x + w`` with ``H = [I_2\ 0]`` and

   .. math:: R = (\sigma_p^2 + \sigma_o^2) I + (\sigma_t^2 + \sigma_\tau^2)\, v v^T ,

   :math:`\sigma_p, \sigma_t` the report's position and time-stamp noise estimated by the
   AIS tracker's noise model (:func:`seatrack.filters.ais.noise.position_noise`),
   :math:`\sigma_o, \sigma_\tau` the antenna-offset and latency allowances of
   ``[fusion]`` and ``v`` the vessel's tracked velocity; the pair's squared distance and
   log-likelihood ratio are :func:`~seatrack.fusion.associate.pair_statistics` of
   ``H x^-``, ``H P^- H^T`` and ``z``, ``R`` (innovation covariance ``S = H P^- H^T + R``);
2. gated (``d^2 <= gate``); the pair's score accumulates the log-likelihood ratio as in
   the track design, a pair of a vessel that reported and left the gate is forgotten,
   the pairs of vessels that did not report keep their scores
   (:class:`~seatrack.fusion.associate.PairScores`);
3. the assignment over every scored pair (hysteresis for the pairs assigned before) says
   which radar track is which vessel; a report whose pair is assigned updates that
   track: the Kalman update of :func:`seatrack.kalman.update` (Joseph form), so the radar
   track carries the AIS accuracy from then on.

The reports between two scans go in rounds, the ``k``-th report of each vessel in round
``k``, so that a vessel's reports are used in time order. A track whose state is already
later than a report (updated in an earlier round by a later report of another vessel) is
not compared with it.

The update (:func:`position_update`) works on a per-track filter whose state is ``x, y,
vx, vy, ...`` in ``x``/``P``, alone or inside the tracker's adaptive process noise
(:class:`seatrack.tracking.adaptive.NoiseLevels`, the default): there every model of the
interacting multiple model is updated with the report, its probability multiplied by its
likelihood (log space) and the track's state is the moment-matched combination
(:func:`seatrack.filters.imm.combine`), as for a radar plot. Other filters (their own
auxiliary states) are refused (:func:`check_filter`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.config import ConfigError
from seatrack.filters.ais.kernel import vessel_starts
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import TrackState
from seatrack.filters.imm import combine
from seatrack.fusion.associate import Assignment
from seatrack.fusion.associate import FusionConfig
from seatrack.fusion.associate import PairScores
from seatrack.fusion.associate import gate_candidates
from seatrack.fusion.associate import identity_probability
from seatrack.fusion.associate import pair_keys
from seatrack.fusion.associate import pair_statistics
from seatrack.fusion.associate import report_allowance
from seatrack.kalman import update
from seatrack.tracking.adaptive import MODELS
from seatrack.tracking.adaptive import MU

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "AisMeasurements",
    "measurement_noise",
    "position_matrix",
    "check_filter",
    "position_update",
    "ReportUpdater",
    "vessel_rounds",
]

_ID_MASK = (1 << 31) - 1


@dataclass(frozen=True)
class AisMeasurements:
    """AIS reports used as measurements, sorted by time: ``vessel`` (n,), ``t`` (n,) s,
    ``pos`` (n, 2) m in the radar's plane, ``cov`` (n, 2, 2) m^2 the measurement noise
    ``R`` (:func:`measurement_noise`)."""

    vessel: IntArray
    t: FloatArray
    pos: FloatArray
    cov: FloatArray

    def __post_init__(self) -> None:
        if np.any(np.diff(self.t) < 0):
            raise ValueError("AisMeasurements: rows must be sorted by time")


def measurement_noise(sigma_pos: FloatArray, sigma_time: FloatArray, vel: FloatArray,
                      cfg: FusionConfig) -> FloatArray:  # fmt: skip
    """``R`` (n, 2, 2) m^2 of AIS reports with position noise ``sigma_pos`` (m), time-stamp
    noise ``sigma_time`` (s) and velocity ``vel`` (n, 2) m/s, plus the antenna-offset and
    latency allowances of ``cfg`` (module docstring)."""
    return report_allowance(vel, np.hypot(sigma_pos, cfg.sigma_antenna_offset),
                            np.hypot(sigma_time, cfg.sigma_latency))  # fmt: skip


def position_matrix(n: int) -> FloatArray:
    """``H = [I_2 0]`` (2, n): the horizontal position of a state laid out ``x, y, ...``."""
    h = np.zeros((2, n))
    h[0, 0] = h[1, 1] = 1.0
    return h


def check_filter(flt: RecursiveFilter) -> None:
    """Raise :class:`~seatrack.config.ConfigError` unless :func:`position_update` can
    update the states of ``flt``: laid out ``x, y, vx, vy, ...``, with no auxiliary state
    but the models of the adaptive process noise and the transition matrix ``F`` of the
    last prediction (kept for a smoother; an update leaves it as it is)."""
    names = tuple(flt.state_names)
    n = len(names)
    probe = flt.initiate(np.zeros(1), np.zeros((1, n)), np.eye(n)[None])
    own = set(probe.aux) - {"F"}
    plain = not own or (own == {MODELS, MU} and not set(probe.aux[MODELS].aux) - {"F"})
    if names[:4] != ("x", "y", "vx", "vy") or not plain:
        raise ConfigError(
            'association = "measurement" needs a per-track method whose state is x, y, vx, '
            f"vy, ... with no state of its own beyond it; this method's state is "
            f"{', '.join(names)}" + (f" with {', '.join(probe.aux)}" if probe.aux else "")
        )


def position_update(state: TrackState, z: FloatArray, r: FloatArray) -> TrackState:
    """The tracks ``state`` (predicted to the reports' times) updated with position
    measurements ``z`` (B, 2) m of noise ``r`` (B, 2, 2) m^2: the Kalman update
    (:func:`seatrack.kalman.update`, Joseph form) with ``H = [I_2 0]``; for the adaptive
    process noise, of every model, the model probabilities ``mu_j ~ c_j N(y_j; 0, S_j)``
    and the moment-matched combination (module docstring)."""
    n = state.x.shape[1]
    h = position_matrix(n)
    if MODELS not in state.aux:
        out = update(state.x, state.P, z, h, r, check=False)
        return state.replace(x=out.x, P=out.P, nis=out.nis, log_likelihood=out.log_likelihood)
    models, c = state.aux[MODELS], np.asarray(state.aux[MU])
    out = update(models.x, models.P, z[:, None, :], h, r[:, None], check=False)
    ok = np.isfinite(out.log_likelihood)  # (B, M); a failed model keeps its prediction
    x = np.where(ok[..., None], out.x, models.x)
    p = np.where(ok[..., None, None], out.P, models.P)
    ll = np.where(ok, out.log_likelihood, -np.inf)
    mu, xc, pc, tot = combine(x, p, c, ll, np.arange(n))
    best = np.argmax(mu, axis=1)
    new_models = models.replace(x=x, P=p, nis=out.nis, log_likelihood=out.log_likelihood)
    return state.replace(x=xc, P=pc, nis=out.nis[np.arange(best.size), best],
                         log_likelihood=tot, aux={MODELS: new_models, MU: mu})  # fmt: skip


def vessel_rounds(vessel: IntArray, t: FloatArray) -> IntArray:
    """Round of each report: its rank in time among the reports of its vessel (0 for the
    first), so that a round holds at most one report per vessel."""
    order = np.lexsort((t, vessel))
    bounds = vessel_starts(vessel[order])
    rank = np.empty(vessel.size, np.int64)
    rank[order] = np.arange(vessel.size) - np.repeat(bounds[:-1], np.diff(bounds))
    return rank


class ReportUpdater:
    """The AIS reports applied to the radar tracks, and the identities they give
    (module docstring).

    Parameters
    ----------
    flt : the radar tracks' per-track filter (:func:`check_filter`)
    reports : the AIS reports as measurements, sorted by time
    config : the ``[fusion]`` keys

    Attributes
    ----------
    nis : normalised innovation squared (``d^2`` with the track's combined covariance) of
        every AIS update made so far, one array per round (diagnostics)
    """

    def __init__(self, flt: RecursiveFilter, reports: AisMeasurements,
                 config: FusionConfig) -> None:  # fmt: skip
        check_filter(flt)
        self.flt = flt
        self.reports = reports
        self.config = config
        self.pairs = PairScores(config)
        self.next = 0  # first report not used yet
        self.nis: list[FloatArray] = []

    def update(self, state: TrackState, ids: IntArray, eligible: NDArray[np.bool_],
               t: float) -> TrackState:  # fmt: skip
        """Apply every report not used yet with a time up to ``t`` (s) to the tracks
        ``state`` (ids ``ids``; only the ``eligible`` ones, e.g. the confirmed tracks,
        are compared); returns the updated batch."""
        stop = int(np.searchsorted(self.reports.t, t, side="right"))
        rows = np.arange(self.next, stop)
        self.next = max(stop, self.next)
        if rows.size == 0:
            return state
        rank = vessel_rounds(self.reports.vessel[rows], self.reports.t[rows])
        for k in range(int(rank.max()) + 1):
            state = self._round(state, ids, np.flatnonzero(eligible), rows[rank == k])
        return state

    def skip(self, t: float) -> None:
        """Leave unused the reports up to ``t`` (s): no radar track to compare them with."""
        self.next = max(int(np.searchsorted(self.reports.t, t, side="right")), self.next)

    def _round(self, state: TrackState, ids: IntArray, live: IntArray,
               rows: IntArray) -> TrackState:  # fmt: skip
        """One round: reports ``rows`` (one per vessel) against the tracks ``live``."""
        r = self.reports
        z, rr, tz, vz = r.pos[rows], r.cov[rows], r.t[rows], r.vessel[rows]
        i, j, pred, score_keys, llr, d2 = self._gated(state, ids, live, z, rr, tz, vz)
        vessel_of = self.pairs.keys & _ID_MASK
        self.pairs.accumulate(score_keys, llr, keep=~np.isin(vessel_of, vz))
        keys = self.pairs.keys
        if keys.size == 0:
            return state
        ru, rows_k = np.unique(keys >> 31, return_inverse=True)
        cu, cols_k = np.unique(keys & _ID_MASK, return_inverse=True)
        chosen, _ = self.pairs.assign(rows_k, cols_k, keys, self.pairs.scores, ru.size,
                                      cu.size)  # fmt: skip
        use = np.flatnonzero(np.isin(score_keys, keys[chosen]))
        if use.size == 0:
            return state
        new = position_update(pred.take(use), z[j[use]], rr[j[use]])
        ok = np.flatnonzero(np.isfinite(new.x).all(-1) & np.isfinite(new.log_likelihood))
        self.nis.append(d2[use][ok])
        return state.put(live[i[use]][ok], new.take(ok))

    def _gated(
        self, state: TrackState, ids: IntArray, live: IntArray, z: FloatArray,
        rr: FloatArray, tz: FloatArray, vz: IntArray,
    ) -> tuple[IntArray, IntArray, TrackState, IntArray, FloatArray, FloatArray]:  # fmt: skip
        """The gated pairs (track ``live[i]``, report ``j``) with the tracks predicted to
        the reports' times, the pair keys, log-likelihood ratios and squared distances."""
        cfg = self.config
        none = np.zeros(0, np.int64)
        if live.size == 0:
            return none, none, state.take(none), none, np.zeros(0), np.zeros(0)
        sub = state.take(live)
        # candidates: the tracks at the round's last time, the radius widened by the
        # farthest a track moves back to an earlier report (covariances only grow)
        t_hi = float(tz.max())
        hi = self.flt.predict(sub, np.maximum(sub.t, t_hi))
        vmax = float(np.sqrt((hi.x[:, 2:4] ** 2).sum(-1)).max())
        i, j = gate_candidates(hi.x[:, :2], hi.P[:, :2, :2], z, rr, cfg.gate,
                               vmax * (t_hi - tz))  # fmt: skip
        later = sub.t[i] > tz[j]
        i, j = i[~later], j[~later]
        pred = self.flt.predict(sub.take(i), tz[j])
        d2, llr = pair_statistics(pred.x[:, :2], pred.P[:, :2, :2], z[j], rr[j],
                                  cfg.other_density * 1e-6)  # fmt: skip
        g = np.flatnonzero(d2 <= cfg.gate)
        i, j = i[g], j[g]
        return i, j, pred.take(g), pair_keys(ids[live[i]], vz[j]), llr[g], d2[g]

    def prune(self, live_ids: IntArray, vessels: IntArray) -> None:
        """Forget the pairs of tracks not in ``live_ids`` or vessels not in ``vessels``."""
        k = self.pairs.keys
        keep = np.isin(k >> 31, live_ids) & np.isin(k & _ID_MASK, vessels)
        if not keep.all():
            self.pairs.accumulate(np.zeros(0, np.int64), np.zeros(0), keep=keep)

    def assignment(self, track: IntArray, vessel: IntArray) -> Assignment:
        """The identities of the radar tracks ``track`` at a scan: per track the row of
        its assigned vessel in ``vessel`` (the AIS vessels predicted at the scan, sorted;
        -1: none) and the identity probability
        (:func:`~seatrack.fusion.associate.identity_probability` over every scored pair)."""
        out_row = np.full(track.size, -1, np.int64)
        out_p = np.full(track.size, np.nan)
        keys, a = self.pairs.keys, self.pairs.assigned
        if a.size == 0 or track.size == 0 or vessel.size == 0:
            return Assignment(out_row, out_p)
        ru, rows_k = np.unique(keys >> 31, return_inverse=True)
        cu, cols_k = np.unique(keys & _ID_MASK, return_inverse=True)
        prob = identity_probability(rows_k, cols_k, self.pairs.scores, ru.size, cu.size)
        at = np.searchsorted(keys, a)
        a_track, a_vessel, a_prob = a >> 31, a & _ID_MASK, prob[at]
        order = np.argsort(a_track)
        k = np.searchsorted(a_track[order], track)
        k = np.minimum(k, a.size - 1)
        hit = a_track[order][k] == track
        v_row = np.searchsorted(vessel, a_vessel[order][k])
        v_row = np.minimum(v_row, vessel.size - 1)
        hit &= vessel[v_row] == a_vessel[order][k]
        out_row[hit] = v_row[hit]
        out_p[hit] = a_prob[order][k][hit]
        return Assignment(out_row, out_p)
