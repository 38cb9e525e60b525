"""Adaptive process noise for any per-track filter: an IMM over noise levels (a wrapper).

Ships sail straight most of the time and turn now and then. A constant-velocity filter
with low process noise is accurate on the straight legs and lags -- or loses the track --
in a turn; high noise keeps the track but is noisy everywhere. :class:`NoiseLevels` wraps
any :class:`~seatrack.filters.base.RecursiveFilter` (configured with the *low*, straight-leg
noise) into an interacting multiple model estimator (Blom & Bar-Shalom 1988; Bar-Shalom,
Li & Kirubarajan 2001, section 11.6) whose models are the same filter with extra
white-noise acceleration of PSD ``extra[j]`` (m^2/s^3; 0 for the first model) added to
its prediction -- the two-level process noise IMM of BLK section 11.7:

1. mixing: ``c_j = sum_i p_ij mu_i``, ``mu_i|j = p_ij mu_i / c_j``, mixed means and
   covariances per model (moment matching; the filter's own ``aux`` from model ``j``);
2. each model predicts with the filter and adds ``extra[j] Q1(dt)`` to the
   position-velocity block (``Q1`` the white-noise-acceleration matrix of unit PSD);
3. each model updates with the filter; ``mu_j ~ c_j exp(log_likelihood_j)`` (log-sum-exp);
4. the outer state -- what gating, association and output see -- is the moment-matched
   combination, with the predicted model probabilities ``c_j`` before the update.

Mixing and combination are the compiled kernels of the IMM engine
(:func:`seatrack.filters.imm.mix`, :func:`~seatrack.filters.imm.combine`); every model of
every track goes through the wrapped filter in one batched call.

Optional coordinated-turn models (``turn_rates``, rad/s clockwise positive, usually
``(w, -w)``) follow the
``L`` levels: the filter's prediction with extra PSD ``turn_noise``, then the linear map
``G = F_ct(w, T) F_cv(T)^-1 = [[I, S - T I], [0, R(w T)]]`` on the x-y positions and
velocities (``S`` the turn's position-from-velocity block, ``R`` the rotation), so the
model turns a constant-velocity prediction into a coordinated turn in the same state
(``x <- G x``, ``P <- G P G^T``; a compiled kernel). The structure is variable: a track
evaluates its turn models only while ``1 - mu_0`` (off the first level) exceeds
``turn_threshold``; the others run the levels alone -- their turn probabilities set to zero
(the levels renormalised) and the levels' own chain -- and their turn models are not
computed: the needed models of all tracks are indexed out, predicted or updated in one call
of the filter and put back, a model not computed holding a copy of the track's last level
(a finite placeholder of probability zero). With ``turn_threshold`` 0 every track runs every
model. A model of predicted probability zero is skipped in the update alike.

The model states live in ``aux["noise_models"]`` (one nested TrackState whose arrays are
``(B, M, ...)``: the models stacked on a second axis) and the model probabilities in
``aux["noise_mu"]``; the ``manoeuvre`` output column is the probability of the high-noise
level and the turn models. The switching probability per scan ``p_switch`` makes the
transition matrix ``[[1 - p, p], [p, 1 - p]]`` (``M`` models: stay ``1 - p``, any other
``p / (M - 1)``). A new track starts in the first (lowest) model with
probability ``start`` (the rest shared evenly by the others; default: all models alike).
Only the contract's state layout is used (positions
``0..d-1``, velocities ``d..2d-1``), so any filter can be wrapped -- as long as its
``update`` starts from the state ``predict`` gave (``x``, ``P``); a filter that keeps its
own prediction in ``aux`` ignores the extra noise. :meth:`NoiseLevels.merge` reduces JPDA
hypotheses model by model (the mixture of IMM states, weighted by association and model
probabilities).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import TrackState
from seatrack.filters.base import predicted
from seatrack.filters.base import step_times
from seatrack.filters.imm import IMMState
from seatrack.filters.imm import combine
from seatrack.filters.imm import mix
from seatrack.models.motion import along_track_core
from seatrack.models.motion import cv_noise
from seatrack.tracking.merge import moment_match

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

__all__ = ["NoiseLevels"]

MODELS, MU = "noise_models", "noise_mu"
_UPDATED, _REJECTED = int(PlotStatus.UPDATED), int(PlotStatus.REJECTED)


def _zip_stack(states: Sequence[TrackState]) -> TrackState:
    """Model states ``(B, ...)`` stacked into one nested state ``(B, M, ...)``."""
    first = states[0]
    aux: dict[str, Any] = {}
    for k, v in first.aux.items():
        parts = [s.aux[k] for s in states]
        aux[k] = _zip_stack(parts) if isinstance(v, TrackState) else np.stack(parts, axis=1)
    st = lambda f: np.stack([getattr(s, f) for s in states], axis=1)  # noqa: E731
    return TrackState(st("t"), st("x"), st("P"), st("nis"), st("log_likelihood"), st("status"), aux)


def _flat(stacked: TrackState) -> TrackState:
    """``(B, M, ...)`` model states as one batch of ``B * M`` (track-major)."""
    return stacked.map(lambda a: a.reshape((-1,) + a.shape[2:]))


def _unflat(flat: TrackState, B: int, M: int) -> TrackState:
    return flat.map(lambda a: a.reshape((B, M) + a.shape[1:]))


def _uniform(M: int, p_switch: float) -> FloatArray:
    """Transition matrix of ``M`` models: stay with ``1 - p_switch``, else any other alike."""
    out = np.full((M, M), p_switch / (M - 1))
    np.fill_diagonal(out, 1 - p_switch)
    return out


@functools.lru_cache(maxsize=64)
def _unit_cv_noise(dt: float, d: int) -> FloatArray:
    """White-noise-acceleration CV noise of unit PSD for one interval (read-only, cached)."""
    q = cv_noise(dt, 1.0, d)
    q.flags.writeable = False
    return q


def _pick(aux: Any, rows: IntArray, cols: IntArray) -> dict[str, Any]:
    """The ``aux`` entries of model ``cols[b]`` of each track ``rows[b]``."""
    out: dict[str, Any] = {}
    for k, v in aux.items():
        out[k] = v.map(lambda a: a[rows, cols]) if isinstance(v, TrackState) else v[rows, cols]
    return out


@njit(cache=True)
def _add_shaped_noise(P, extra, T, v, Pv, ratio):  # pragma: no cover - compiled
    """Add to the model covariances ``P (B * M, n, n)`` (track-major) the CV noise of PSD
    ``extra[j]`` over ``T[b]`` shaped by the velocity ``v[b]`` of track ``b``:
    ``extra[j] [[T^3/3, T^2/2], [T^2/2, T]] (x) A_b`` on the position-velocity block
    (``A_b`` of :func:`seatrack.models.motion.along_track_core`)."""
    M = extra.size
    d = v.shape[1]
    A = np.empty((d, d))
    for b in range(v.shape[0]):
        along_track_core(v[b], Pv[b], ratio, A)
        t = T[b]
        b00, b01, b11 = t**3 / 3.0, t**2 / 2.0, t
        for j in range(M):
            r = b * M + j
            for k in range(d):
                for m in range(d):
                    a = extra[j] * A[k, m]
                    P[r, k, m] += a * b00
                    P[r, k, d + m] += a * b01
                    P[r, d + k, m] += a * b01
                    P[r, d + k, d + m] += a * b11


@njit(cache=True)
def _turn_map(X, P, rows, first, omega, T, d):  # pragma: no cover - compiled
    """In place, for each track ``b`` in ``rows`` and turn model ``k``: the model ``first + k``
    of ``X (B, M, n)``, ``P (B, M, n, n)`` -- predicted at constant velocity over ``T[b]`` s --
    mapped to a coordinated turn at ``omega[k]`` rad/s (clockwise positive) in the x-y plane,
    ``G = F_ct(omega, T) F_cv(T)^-1 = [[I, S - T I], [0, R(omega T)]]`` on positions
    ``0, 1`` and velocities ``d, d + 1`` (identity elsewhere); ``x <- G x``,
    ``P <- G P G^T`` (symmetrised)."""
    n = X.shape[2]
    G = np.zeros((n, n))
    GP = np.empty((n, n))
    x = np.empty(n)
    for b in rows:
        t = T[b]
        for k in range(omega.size):
            w = omega[k]
            if abs(w * t) < 1e-12:
                continue
            sn, cs = np.sin(w * t), np.cos(w * t)
            G[:, :] = 0.0
            for a in range(n):
                G[a, a] = 1.0
            # clockwise-positive turn rate, as models.motion.ct_transition
            G[0, d], G[0, d + 1] = sn / w - t, (1.0 - cs) / w
            G[1, d], G[1, d + 1] = -(1.0 - cs) / w, sn / w - t
            G[d, d], G[d, d + 1], G[d + 1, d], G[d + 1, d + 1] = cs, sn, -sn, cs
            j = first + k
            for a in range(n):
                v = 0.0
                for c in range(n):
                    v += G[a, c] * X[b, j, c]
                x[a] = v
                for m in range(n):
                    v = 0.0
                    for c in range(n):
                        v += G[a, c] * P[b, j, c, m]
                    GP[a, m] = v
            for a in range(n):
                X[b, j, a] = x[a]
                for m in range(a, n):
                    v = 0.0
                    for c in range(n):
                        v += GP[a, c] * G[m, c]
                    P[b, j, a, m] = v
                    P[b, j, m, a] = v


class NoiseLevels:
    """An IMM over process-noise levels of one filter (see the module docstring).

    Parameters
    ----------
    flt : the filter, configured with the lowest noise level
    extra : extra white-noise acceleration PSD of each level, m^2/s^3 (first usually 0)
    p_switch : probability per scan of leaving a model
    along_track_ratio : PSD of the extra acceleration along the track's velocity over its
        PSD across it (1: isotropic; see :func:`seatrack.models.motion.along_track_shape`)
    start : probability of the first model at initiation, the other levels sharing the
        rest evenly (none: ``1 / L`` each); the turn models start at zero
    turn_rates : turn rate of each coordinated-turn model, rad/s (none: no turn models)
    turn_noise : extra white-noise acceleration PSD of the turn models, m^2/s^3
    turn_threshold : a track evaluates its turn models only while the probability that it
        is not in the first level exceeds this; the others run the levels alone, their
        turn models' probabilities held at zero (0: every track, every scan)
    """

    def __init__(
        self,
        flt: RecursiveFilter,
        extra: Sequence[float] = (0.0, 1.0),
        p_switch: float = 0.05,
        along_track_ratio: float = 1.0,
        start: float | None = None,
        turn_rates: Sequence[float] = (),
        turn_noise: float = 0.0,
        turn_threshold: float = 0.0,
    ) -> None:
        ex = np.asarray(extra, dtype=float)
        if ex.ndim != 1 or ex.size < 2 or np.any(ex < 0) or not 0 < p_switch < 1:
            raise ValueError(
                f"need two or more extra noise levels >= 0 and 0 < p_switch < 1, got "
                f"{list(ex)}, {p_switch}"
            )
        if not 0 < along_track_ratio <= 1:
            raise ValueError(f"along_track_ratio must be in (0, 1], got {along_track_ratio}")
        if start is not None and not 0 < start < 1:
            raise ValueError(f"start must be in (0, 1), got {start}")
        if turn_noise < 0 or not 0 <= turn_threshold < 1:
            raise ValueError(
                f"need turn_noise >= 0 and 0 <= turn_threshold < 1, got {turn_noise}, "
                f"{turn_threshold}"
            )
        self.omega = np.asarray(turn_rates, dtype=float).reshape(-1)
        if self.omega.size and flt.d < 2:
            raise ValueError(f"turn models need a horizontal plane: d >= 2, got {flt.d}")
        self.flt = flt
        self.extra = ex
        self.along_track_ratio = float(along_track_ratio)
        self.turn_threshold = float(turn_threshold)
        L, K = ex.size, self.omega.size
        M = L + K
        self._extra_all = np.concatenate([ex, np.full(K, float(turn_noise))])
        self.transition = _uniform(M, p_switch)
        # tracks not evaluating their turn models: the levels' chain alone, no way into a turn
        self._levels_only = self.transition.copy()
        self._levels_only[:L] = 0.0
        self._levels_only[:L, :L] = _uniform(L, p_switch)
        first = 1.0 / L if start is None else float(start)
        self.start = np.zeros(M)
        self.start[:L] = (1.0 - first) / (L - 1)
        self.start[0] = first
        self.d = flt.d
        self.range_rate = flt.range_rate
        n = len(flt.state_names)
        self._valid = np.ones((M, n))
        self._out = np.arange(n)

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.flt.state_names

    @property
    def sensor(self) -> Any:
        """The wrapped filter's nominal sensor noise (None when it has none)."""
        return getattr(self.flt, "sensor", None)

    # -- helpers ------------------------------------------------------------------------
    @staticmethod
    def _parts(state: TrackState) -> tuple[TrackState, FloatArray]:
        return state.aux[MODELS], np.asarray(state.aux[MU])

    def _base(self, state: TrackState) -> TrackState:
        """The outer state with the filter's own ``aux`` of each track's most probable
        model (what the filter's ``innovation`` and ``columns`` read)."""
        models, mu = self._parts(state)
        best = np.argmax(mu, axis=1)
        aux = _pick(models.aux, np.arange(best.size), best)
        return TrackState(state.t, state.x, state.P, state.nis, state.log_likelihood,
                          state.status, aux)  # fmt: skip

    def _extra_noise(self, P: FloatArray, dt: FloatArray, outer: TrackState) -> FloatArray:
        """``P`` (``B * M`` model covariances, track-major) plus ``extra[j] Q1(dt[b])`` on
        position-velocity (``dt`` one interval a track, s); with ``along_track_ratio < 1``
        the unit acceleration is shaped along / across the velocity of each track's
        combined estimate ``outer`` (``Q1 = blk (x) A``)."""
        d, d2 = self.d, 2 * self.d
        extra = self._extra_all
        out = P.copy()
        if self.along_track_ratio < 1.0:
            c = np.ascontiguousarray
            v, Pv = c(outer.x[:, d:d2]), c(outer.P[:, d:d2, d:d2])
            _add_shaped_noise(out, extra, c(dt), v, Pv, self.along_track_ratio)
        elif dt.size and np.all(dt == dt[0]):  # one scan interval: one unit-PSD matrix
            tiled = np.tile(extra, dt.size)
            out[:, :d2, :d2] += tiled[:, None, None] * _unit_cv_noise(float(dt[0]), self.d)
        else:
            out[:, :d2, :d2] += cv_noise(np.repeat(dt, extra.size), np.tile(extra, dt.size), d)
        return out

    def _turning(self, mu: FloatArray) -> BoolArray:
        """Tracks that evaluate their turn models: off the first level with a probability
        above the threshold."""
        return 1.0 - mu[:, 0] > self.turn_threshold  # type: ignore[no-any-return]

    def _rows(self, needed: BoolArray) -> tuple[IntArray, IntArray] | None:
        """For ``(B, M)`` models of which ``needed`` are evaluated: the flat indices of the
        needed ones, and for every model the row of the evaluated batch that fills it (one
        not evaluated gets its track's last level: a finite placeholder of probability
        zero); none when all are needed."""
        if needed.all():
            return None
        flat = needed.ravel()
        pos = (np.cumsum(flat) - 1).reshape(needed.shape)
        L = self.extra.size
        src = np.where(needed, pos, pos[:, L - 1 : L])
        return np.flatnonzero(flat), src.ravel()

    # -- the contract -------------------------------------------------------------------
    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        s = self.flt.initiate(t, x, P)
        models = _zip_stack([s] * self.start.size)
        mu = np.tile(self.start, (len(s), 1))
        return TrackState(s.t, s.x, s.P, s.nis, s.log_likelihood, s.status,
                          {MODELS: models, MU: mu})  # fmt: skip

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        models, mu = self._parts(state)
        B, M = mu.shape
        L = self.extra.size
        tt, dt = step_times(state, t)
        trans, rows, turning = self.transition, None, np.zeros(0, np.int64)
        if M > L:
            on = self._turning(mu)
            turning = np.flatnonzero(on)
            if turning.size < B:  # the others: turn probabilities to zero, levels' chain
                lv = mu[:, :L] / mu[:, :L].sum(axis=1, keepdims=True)
                mu = np.where(on[:, None], mu, np.pad(lv, ((0, 0), (0, M - L))))
                trans = np.where(on[:, None, None], self.transition, self._levels_only)
                needed = np.ones((B, M), bool)
                needed[:, L:] = on[:, None]
                rows = self._rows(needed)
        X0, P0, c = mix(IMMState(models.x, models.P, mu), trans, self._valid)
        flat = _flat(models.replace(x=X0, P=P0))
        if rows is None:  # every model of every track in one call of the filter
            s = self.flt.predict(flat, np.repeat(tt, M))
        else:  # the needed models in one call, the others filled with a placeholder
            idx, src = rows
            s = self.flt.predict(flat.take(idx), tt[idx // M]).take(src)
        new = _unflat(s.replace(P=self._extra_noise(s.P, dt, state)), B, M)
        if turning.size:
            _turn_map(new.x, new.P, turning, L, self.omega, dt, self.d)
        _, x, P, _ = combine(new.x, new.P, c, np.zeros_like(c), self._out)
        return predicted(state, tt, x, P, {MODELS: new, MU: c})

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        models, c = self._parts(state)
        B, M = c.shape
        L = self.extra.size
        needed = np.ones((B, M), bool)
        rows = None
        if M > L:  # a turn model of predicted probability zero is not evaluated
            needed[:, L:] = c[:, L:] > 0
            rows = self._rows(needed)
        if rows is None:
            s = self.flt.update(_flat(models), plots.take(np.repeat(np.arange(B), M)))
        else:
            idx, src = rows
            s = self.flt.update(_flat(models).take(idx), plots.take(idx // M)).take(src)
        new = _unflat(s, B, M)
        ok = new.status == _UPDATED  # (B, M)
        if rows is not None:
            ok &= needed
        any_ok = ok.any(axis=1)
        ll = np.where(ok, new.log_likelihood, -np.inf)
        ll = np.where(any_ok[:, None], ll, 0.0)  # no usable model: keep the prediction
        mu, x, P, tot = combine(new.x, new.P, c, ll, self._out)
        best = np.argmax(mu, axis=1)
        rows_b = np.arange(B)
        status = np.where(any_ok, _UPDATED, _REJECTED).astype(np.int8)
        nis = np.where(any_ok, new.nis[rows_b, best], np.nan)
        return TrackState(state.t, x, P, nis, np.where(any_ok, tot, np.nan), status,
                          {MODELS: new, MU: mu})  # fmt: skip

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        return self.flt.innovation(self._base(state), plots)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        """The filter's columns, and ``manoeuvre``: the probability of the highest level
        and the turn models."""
        cols = self.flt.columns(self._base(state))
        cols["manoeuvre"] = np.asarray(state.aux[MU])[:, self.extra.size - 1 :].sum(axis=1)
        return cols

    def merge(self, states: TrackState, weights: FloatArray, owner: IntArray, n: int) -> TrackState:
        """Reduce hypotheses (JPDA) model by model: model ``j`` of track ``i`` is the
        moment-matched mixture of its hypotheses' model ``j`` with weights ``w_h mu_hj``,
        its probability ``sum_h w_h mu_hj``; the rest of each model from the track's
        dominant hypothesis (see :func:`seatrack.tracking.merge.merge_hypotheses`)."""
        models, mu = self._parts(states)
        H, M = mu.shape
        w = np.asarray(weights, dtype=float)
        tot = np.bincount(owner, w, minlength=n)
        wn = w / np.where(tot > 0, tot, 1.0)[owner]
        wm = np.maximum(wn[:, None] * mu, 1e-300)  # (H, M)
        mu_new = np.zeros((n, M))
        np.add.at(mu_new, owner, wm)
        dom = np.zeros(n, np.int64)
        order = np.lexsort((-wn, owner))
        first = np.ones(order.size, bool)
        first[1:] = owner[order][1:] != owner[order][:-1]
        dom[owner[order][first]] = order[first]
        X = np.empty((n, M) + models.x.shape[2:])
        PP = np.empty((n, M) + models.P.shape[2:])
        for j in range(M):
            X[:, j], PP[:, j] = moment_match(models.x[:, j], models.P[:, j], wm[:, j], owner, n)
        mu_new /= mu_new.sum(1, keepdims=True)
        new_models = models.take(dom).replace(x=X, P=PP)
        _, x, P, _ = combine(X, PP, mu_new, np.zeros_like(mu_new), self._out)
        return states.take(dom).replace(x=x, P=P, aux={MODELS: new_models, MU: mu_new})
