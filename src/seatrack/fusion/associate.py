r"""Radar tracks and AIS vessels associated scan by scan, with hysteresis.

At each radar scan time ``t``:

1. every AIS vessel's last tracked state (time ``t_k <= t``, not older than the vessel's
   gap limit) is predicted to ``t`` (:func:`predict_ais`): ``a = p_k + v_k dt`` with

   .. math:: P_a = P_k + \Sigma_v\,dt^2 + q\,\frac{dt^3}{3} I
             + \sigma_o^2 I + \sigma_\tau^2\, v_k v_k^T ,

   where :math:`\Sigma_v` is the velocity covariance from the speed and course
   variances, :math:`q` the white-acceleration density, :math:`\sigma_o` the allowance
   for the offset between the AIS antenna and the radar's centre of reflection and
   :math:`\sigma_\tau` that for the report's time-stamp latency (a shift along the
   velocity);
2. each radar track ``i`` and AIS vessel ``j`` within the gate
   :math:`d^2 = \nu^T S^{-1} \nu \le \gamma` (:math:`\nu = z_i - a_j`,
   :math:`S = P_i + P_a`) gets the log-likelihood ratio of "same vessel" against "an
   unrelated object of density :math:`\beta`" (:func:`pair_statistics`):

   .. math:: \ell_{ij} = -\tfrac12 d^2 - \tfrac12 \ln\det(2\pi S) - \ln\beta ;

3. the pair's score accumulates, :math:`s_{ij} \leftarrow \min(\max(s_{ij} + \ell_{ij},
   -s_{max}), s_{max})` (a pair leaving the gate forgets its score), so one scan cannot
   overturn a history (:class:`Associator`);
4. the assignment maximises :math:`\sum (s_{ij} + h\,[ij\ \text{assigned before}])` over
   pairs with :math:`s_{ij} > 0` (:func:`assign_pairs`: connected components of the
   candidate graph, :func:`scipy.optimize.linear_sum_assignment` on those with more than
   one pair);
5. an assigned pair's identity probability treats the scores as log odds against "no
   AIS vessel" and the competing pairs of both members (:func:`identity_probability`):
   :math:`p_{ij} = e^{s_{ij}} / (1 + \sum_{j'} e^{s_{ij'}} + \sum_{i' \ne i} e^{s_{i'j}})`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from seatrack.config import Checked
from seatrack.config import param
from seatrack.filters.ais.kernel import vessel_starts
from seatrack.fusion.anomalies import DEFAULT_GAP_FACTOR
from seatrack.fusion.anomalies import DEFAULT_MIN_GAP_S
from seatrack.tracking.gating import ball_pairs

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "FusionConfig",
    "AisStates",
    "Prediction",
    "Associator",
    "PairScores",
    "Assignment",
    "ASSOCIATIONS",
    "pair_keys",
    "gate_candidates",
    "report_allowance",
    "predict_ais",
    "pair_statistics",
    "assign_pairs",
    "identity_probability",
]

_TWO_PI = 2.0 * math.pi

#: the association designs (``association`` key): AIS tracks against radar tracks, or
#: AIS reports as measurements of the radar tracks (docs/fusion.md)
ASSOCIATIONS = ("track", "measurement")


@dataclass(frozen=True)
class FusionConfig(Checked):
    """Keys of the ``[fusion]`` table of ``radar.toml`` (docs/fusion.md)."""

    association: str = param(
        "track", choices=ASSOCIATIONS,
        doc="track: AIS tracks associated with radar tracks; measurement: AIS reports "
        "update the radar tracks they are associated with",
    )  # fmt: skip
    gate: float = param(
        16.0, doc="gate on the squared statistical distance of a radar-AIS pair (2 dof)",
        min=1.0, max=1000.0,
    )  # fmt: skip
    other_density: float = param(
        1.0, key="other_density_per_km2", unit="1/km^2",
        doc="density of unrelated objects a radar track could be confused with", min=0.0,
        exclusive_min=True, max=1e6,
    )  # fmt: skip
    sigma_antenna_offset: float = param(
        30.0, key="sigma_antenna_offset_m", unit="m",
        doc="allowance for the AIS antenna's offset from the radar's centre of reflection",
        min=0.0, max=1e4,
    )  # fmt: skip
    sigma_latency: float = param(
        2.0, key="sigma_latency_s", unit="s", doc="allowance for AIS time-stamp latency",
        min=0.0, max=600.0,
    )  # fmt: skip
    accel_density: float = param(
        0.05, key="accel_density_m2ps3", unit="m^2/s^3",
        doc="white-acceleration density q of the AIS prediction (variance grows as q dt^3/3)",
        min=0.0, max=100.0,
    )  # fmt: skip
    max_score: float = param(
        20.0, doc="bound on a pair's accumulated log-likelihood ratio", min=1.0, max=1e4
    )
    hysteresis: float = param(
        4.0, doc="bonus (log-likelihood) of the pair assigned at the previous scan", min=0.0,
        max=1e4,
    )  # fmt: skip
    dark_delay: float = param(
        4.0, key="dark_delay_s", unit="s",
        doc="a radar track without an AIS vessel this long (inside coverage) is dark",
        min=0.0, max=1e5,
    )  # fmt: skip
    not_seen_delay: float = param(
        30.0, key="not_seen_delay_s", unit="s",
        doc="an AIS vessel inside coverage without a radar track this long is not seen",
        min=0.0, max=1e5,
    )  # fmt: skip
    edge_margin: float = param(
        500.0, key="edge_margin_m", unit="m",
        doc="not seen only this far inside the edges of coverage (range, horizon, sectors, land)",
        min=0.0, max=1e5,
    )  # fmt: skip
    min_detection_probability: float = param(
        0.5, doc="not seen only where the radar's detection probability is at least this",
        min=0.0, max=1.0,
    )  # fmt: skip
    gap_factor: float = param(
        DEFAULT_GAP_FACTOR,
        doc="a gap: silent longer than this many own median reporting intervals",
        min=1.0, max=1000.0,
    )  # fmt: skip
    min_gap: float = param(
        DEFAULT_MIN_GAP_S, key="min_gap_s", unit="s", doc="shortest silence called a gap", min=0.0,
        max=1e6,
    )  # fmt: skip
    land_mask: bool = param(True, doc="land from the bundled coast shadows the radar")
    land_cell: float = param(
        100.0, key="land_cell_m", unit="m", doc="cell of the land-shadow grid", min=10.0,
        max=1e4,
    )  # fmt: skip


@dataclass(frozen=True)
class AisStates:
    """Tracked AIS states in the radar's East-North plane, sorted by (vessel, time).

    ``pos`` (N, 2) m, ``vel`` (N, 2) m/s, ``pos_cov`` and ``vel_cov`` (N, 2, 2); ``limit``
    (V,) the longest silence (s) after which a vessel's last state is no longer predicted.
    """

    vessel: IntArray
    t: FloatArray
    pos: FloatArray
    vel: FloatArray
    pos_cov: FloatArray
    vel_cov: FloatArray
    limit: FloatArray

    @property
    def n_vessels(self) -> int:
        """Number of vessels."""
        return int(self.limit.size)

    def __post_init__(self) -> None:
        order = np.lexsort((self.t, self.vessel))
        if not np.array_equal(order, np.arange(order.size)):
            raise ValueError("AisStates: rows must be sorted by vessel, then time")


def velocity_covariance(course: FloatArray, speed: FloatArray, var_course: FloatArray,
                        var_speed: FloatArray) -> FloatArray:  # fmt: skip
    """Covariance (..., 2, 2) of ``v = speed (sin c, cos c)`` from the variances of speed
    (m^2/s^2) and course (rad^2): ``J diag(var_speed, var_course) J^T`` with
    ``J = [[sin c, s cos c], [cos c, -s sin c]]``."""
    s, c = np.sin(course), np.cos(course)
    j = np.stack([np.stack([s, speed * c], -1), np.stack([c, -speed * s], -1)], -2)
    d = np.stack([var_speed, var_course], -1)
    return np.asarray(np.einsum("...ik,...k,...jk->...ij", j, d, j))


@dataclass(frozen=True)
class Prediction:
    """AIS vessels brought to one time: ``vessel`` (M,), ``pos`` (M, 2), ``cov`` (M, 2, 2),
    ``age`` (M,) seconds since the state used."""

    vessel: IntArray
    pos: FloatArray
    cov: FloatArray
    age: FloatArray


def predict_ais(states: AisStates, t: float, cfg: FusionConfig) -> Prediction:
    """Every AIS vessel with a state at or before ``t`` no older than its limit, predicted
    to ``t`` with its covariance and the offset and latency allowances (module docstring)."""
    v = np.arange(states.n_vessels)
    last = np.searchsorted(states.vessel, v, side="right") - 1  # last row of each vessel
    first = np.searchsorted(states.vessel, v)
    # last row with time <= t: binary search within each vessel's rows
    lo, hi = first.copy(), last + 1
    while True:
        open_ = lo < hi
        if not open_.any():
            break
        mid = (lo + hi) // 2
        go = open_ & (states.t[np.minimum(mid, states.t.size - 1)] <= t)
        lo = np.where(go, mid + 1, lo)
        hi = np.where(open_ & ~go, mid, hi)
    k = lo - 1
    ok = (k >= first) & (k <= last)
    k = k[ok]
    age = t - states.t[k]
    keep = age <= states.limit[v[ok]]
    k, age = k[keep], age[keep]
    vel = states.vel[k]
    pos = states.pos[k] + vel * age[:, None]
    eye = np.eye(2)
    a2 = (age * age)[:, None, None]
    cov = (
        states.pos_cov[k]
        + states.vel_cov[k] * a2
        + (cfg.accel_density * age**3 / 3.0)[:, None, None] * eye
        + report_allowance(vel, cfg.sigma_antenna_offset, cfg.sigma_latency)
    )
    return Prediction(states.vessel[k], pos, cov, age)


def report_allowance(vel: FloatArray, sigma_offset: FloatArray | float,
                     sigma_time: FloatArray | float) -> FloatArray:  # fmt: skip
    """Covariance (n, 2, 2) m^2 ``sigma_offset^2 I + sigma_time^2 v v^T`` of an AIS
    position of velocity ``vel`` (n, 2) m/s: an isotropic offset (m) and a time-stamp
    error (s) that shifts the position along the velocity."""
    so = np.broadcast_to(np.asarray(sigma_offset, float), vel.shape[:1])
    st = np.broadcast_to(np.asarray(sigma_time, float), vel.shape[:1])
    return np.asarray(
        (so * so)[:, None, None] * np.eye(2)
        + (st * st)[:, None, None] * np.einsum("ni,nj->nij", vel, vel)
    )


def pair_statistics(
    z: FloatArray, pz: FloatArray, a: FloatArray, pa: FloatArray, other_density: float
) -> tuple[FloatArray, FloatArray]:
    """Squared distance ``d2`` and log-likelihood ratio ``llr`` of paired rows.

    ``z``/``a`` (K, 2) radar and AIS positions (m), ``pz``/``pa`` (K, 2, 2) covariances
    (m^2), ``other_density`` objects per m^2. A non-positive-definite ``S`` gives
    ``d2 = inf`` and ``llr = -inf`` (never associated).
    """
    s = pz + pa
    sxx, syy, sxy = s[:, 0, 0], s[:, 1, 1], 0.5 * (s[:, 0, 1] + s[:, 1, 0])
    det = sxx * syy - sxy * sxy
    good = (det > 0) & (sxx > 0)
    det_safe = np.where(good, det, 1.0)
    nx, ny = z[:, 0] - a[:, 0], z[:, 1] - a[:, 1]
    d2 = (syy * nx * nx - 2.0 * sxy * nx * ny + sxx * ny * ny) / det_safe
    llr = -0.5 * d2 - 0.5 * np.log(_TWO_PI * _TWO_PI * det_safe) - math.log(other_density)
    return np.where(good, d2, np.inf), np.where(good, llr, -np.inf)


def assign_pairs(rows: IntArray, cols: IntArray, weight: FloatArray, n_rows: int,
                 n_cols: int) -> NDArray[np.bool_]:  # fmt: skip
    """Which candidate pairs ``(rows[k], cols[k])`` are assigned: the one-to-one choice of
    largest total ``weight`` (every weight > 0, every pair distinct).

    Components of the candidate graph with one pair take it; the others are solved by
    :func:`scipy.optimize.linear_sum_assignment` (absent pairs cost +inf-like).
    """
    k = rows.size
    chosen = np.zeros(k, bool)
    if k == 0:
        return chosen
    g = coo_matrix((np.ones(k), (rows, cols + n_rows)), shape=(n_rows + n_cols,) * 2)
    _, label = connected_components(g, directed=False)
    comp = label[rows]
    size = np.bincount(comp)
    chosen[size[comp] == 1] = True
    multi = np.flatnonzero(size[comp] > 1)
    if multi.size == 0:
        return chosen
    multi = multi[np.argsort(comp[multi], kind="stable")]
    bounds = vessel_starts(comp[multi])  # the runs of one component
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        part = multi[a:b]
        r_u, r_i = np.unique(rows[part], return_inverse=True)
        c_u, c_i = np.unique(cols[part], return_inverse=True)
        big = float(weight[part].sum()) + 1.0
        cost = np.full((r_u.size, c_u.size), big)
        cost[r_i, c_i] = -weight[part]
        ri, ci = linear_sum_assignment(cost)
        pick = np.full((r_u.size, c_u.size), -1, np.int64)
        pick[r_i, c_i] = part
        sel = pick[ri, ci]
        chosen[sel[sel >= 0]] = True
    return chosen


def identity_probability(rows: IntArray, cols: IntArray, score: FloatArray, n_rows: int,
                         n_cols: int) -> FloatArray:  # fmt: skip
    """Per candidate pair ``e^s / (1 + sum of e^s over the row + over the column - e^s)``:
    the scores read as log odds against "no AIS vessel" (module docstring)."""
    e = np.exp(score)
    row_sum = np.bincount(rows, e, minlength=n_rows)
    col_sum = np.bincount(cols, e, minlength=n_cols)
    return np.asarray(e / (1.0 + row_sum[rows] + col_sum[cols] - e))


@dataclass(frozen=True)
class Assignment:
    """Result of one :meth:`Associator.step`: per radar row the assigned AIS row (-1:
    none) and its identity probability (NaN: none)."""

    ais_row: IntArray
    identity_prob: FloatArray


class PairScores:
    """Accumulated log-likelihood ratios of (radar id, AIS id) pairs and the pairs assigned
    at the last step (module docstring, steps 3-5); shared by both association designs.

    Ids are non-negative integers below 2**31; a pair is the key ``radar_id << 31 | ais_id``.
    """

    def __init__(self, config: FusionConfig) -> None:
        self.config = config
        self.keys = np.zeros(0, np.int64)  # sorted pair keys
        self.scores = np.zeros(0)
        self.assigned = np.zeros(0, np.int64)  # sorted keys assigned at the last step

    def clear(self) -> None:
        """Forget every pair."""
        self.keys, self.scores = np.zeros(0, np.int64), np.zeros(0)
        self.assigned = np.zeros(0, np.int64)

    def accumulate(self, keys: IntArray, llr: FloatArray,
                   keep: NDArray[np.bool_] | None = None) -> FloatArray:  # fmt: skip
        """Add ``llr`` to the scores of the distinct pairs ``keys`` (bounded by
        ``max_score``) and return their new scores. Stored pairs not in ``keys`` are kept
        where ``keep`` (aligned with :attr:`keys`) is true, else forgotten (default)."""
        cap = self.config.max_score
        score = np.clip(llr + _lookup(self.keys, self.scores, keys, 0.0), -cap, cap)
        k, s = keys, score
        if keep is not None and keep.any():
            old = keep & ~np.isin(self.keys, keys)
            k, s = np.r_[keys, self.keys[old]], np.r_[score, self.scores[old]]
        order = np.argsort(k)
        self.keys, self.scores = k[order], s[order]
        self.assigned = self.assigned[np.isin(self.assigned, self.keys)]
        return np.asarray(score)

    def assign(self, rows: IntArray, cols: IntArray, keys: IntArray, score: FloatArray,
               n_rows: int, n_cols: int) -> tuple[NDArray[np.bool_], FloatArray]:  # fmt: skip
        """The pairs ``(rows, cols)`` (indices, keys ``keys``, scores ``score``) assigned
        (:func:`assign_pairs` of ``score`` plus ``hysteresis`` for a pair assigned at the
        last step, over the pairs with ``score > 0``) and their
        :func:`identity_probability`; the assigned pairs become the last step's."""
        was = np.isin(keys, self.assigned)
        weight = score + self.config.hysteresis * was
        e = np.flatnonzero(score > 0)
        chosen = np.zeros(keys.size, bool)
        chosen[e[assign_pairs(rows[e], cols[e], weight[e], n_rows, n_cols)]] = True
        prob = identity_probability(rows, cols, score, n_rows, n_cols)
        self.assigned = np.sort(keys[chosen])
        return chosen, prob


def pair_keys(radar_id: IntArray, ais_id: IntArray) -> IntArray:
    """The :class:`PairScores` key of each pair: ``radar_id << 31 | ais_id``."""
    return (radar_id.astype(np.int64) << 31) | ais_id.astype(np.int64)


class Associator:
    """Pair scores carried from scan to scan (module docstring, steps 2-5).

    Radar tracks and AIS vessels are named by non-negative integer ids (below 2**31)
    that stay the same from scan to scan; a pair not gated at a scan is forgotten.
    """

    def __init__(self, config: FusionConfig) -> None:
        self.config = config
        self.pairs = PairScores(config)

    def step(
        self,
        radar_id: IntArray,
        radar_pos: FloatArray,
        radar_cov: FloatArray,
        ais_id: IntArray,
        ais_pos: FloatArray,
        ais_cov: FloatArray,
    ) -> Assignment:
        """Gate, score, assign one scan (positions (n, 2) m, covariances (n, 2, 2) m^2)."""
        cfg = self.config
        nr, na = radar_id.size, ais_id.size
        out_row = np.full(nr, -1, np.int64)
        out_p = np.full(nr, np.nan)
        if nr == 0 or na == 0:
            self.pairs.clear()
            return Assignment(out_row, out_p)
        i, j = gate_candidates(radar_pos, radar_cov, ais_pos, ais_cov, cfg.gate)
        d2, llr = pair_statistics(radar_pos[i], radar_cov[i], ais_pos[j], ais_cov[j],
                                  cfg.other_density * 1e-6)  # fmt: skip
        g = d2 <= cfg.gate
        i, j, llr = i[g], j[g], llr[g]
        keys = pair_keys(radar_id[i], ais_id[j])
        score = self.pairs.accumulate(keys, llr)
        chosen, prob = self.pairs.assign(i, j, keys, score, nr, na)
        out_row[i[chosen]] = j[chosen]
        out_p[i[chosen]] = prob[chosen]
        return Assignment(out_row, out_p)


def gate_candidates(
    zp: FloatArray, zc: FloatArray, ap: FloatArray, ac: FloatArray, gate: float,
    extra: FloatArray | float = 0.0,
) -> tuple[IntArray, IntArray]:  # fmt: skip
    """Pairs (radar row ``i``, AIS row ``j``) within a Euclidean radius per AIS row that
    contains each of its pairs' Mahalanobis gates ``d^2 <= gate`` (the largest eigenvalue
    of ``S = zc_i + ac_j`` is at most its trace), widened by ``extra`` (m, per AIS row)."""
    tr_z = zc[:, 0, 0] + zc[:, 1, 1]
    tr_a = ac[:, 0, 0] + ac[:, 1, 1]
    radius = np.sqrt(gate * (float(tr_z.max()) + tr_a)) + extra
    counts, i = ball_pairs(cKDTree(zp), ap, radius)
    return i, np.repeat(np.arange(ap.shape[0]), counts)


def _lookup(keys: IntArray, values: FloatArray, query: IntArray, fill: float) -> FloatArray:
    """``values`` at ``query`` in the sorted ``keys`` (``fill`` where absent)."""
    if keys.size == 0:
        return np.full(query.size, fill)
    pos = np.minimum(np.searchsorted(keys, query), keys.size - 1)
    return np.where(keys[pos] == query, values[pos], fill)
