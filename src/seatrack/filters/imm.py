"""Interacting Multiple Model (IMM) estimator, Blom & Bar-Shalom (1988).

Standard IMM cycle (Bar-Shalom, Li & Kirubarajan 2001, section 11.6.6):

1. mixing probabilities ``mu_{i|j} = pi_ij mu_i / c_j``, ``c_j = sum_i pi_ij mu_i``;
2. mixed initial conditions ``x0_j = sum_i mu_{i|j} x_i``,
   ``P0_j = sum_i mu_{i|j} [P_i + (x_i - x0_j)(x_i - x0_j)^T]``;
3. model-matched prediction and (extended) Kalman update with :mod:`seatrack.kalman`;
4. model probabilities ``mu_j ∝ c_j Λ_j`` computed in log space (log-sum-exp);
5. combined output ``x = sum_j mu_j x_j`` with the spread-of-means covariance.

Transition convention: ``transition[i, j] = P(model j at k | model i at k-1)``, rows
sum to one (Bar-Shalom's ``p_ij`` and FilterPy's ``M``). Note the multiple-model spec
(``multimodel.md``) writes the transpose (``pi_ab``, columns sum to one).

Models of different state size
-------------------------------
Motion models name their state components (``state_names``: ``x, y, vx, vy`` for CV,
``x, y, vx, vy, w`` for CT, ...); components are matched by name, which is the explicit
state mapping. When mixing *into* model ``j`` from a model ``i`` that lacks some of
``j``'s components (e.g. the turn rate ``w`` when mixing CV into CT), those components
are taken from model ``j``'s own previous estimate (mean and variance, no
cross-covariance) -- the "model-own augmentation" of Granström, Willett & Bar-Shalom,
"Systematic approach to IMM mixing for unequal dimension states", IEEE T-AES 51(4), 2015.
With equal models this reduces exactly to the standard IMM.

The combined output is given on the components common to all models
(``output_names``), e.g. ``x, y, vx, vy`` for a CV + CT bank.

All arrays may carry leading batch dimensions (many tracks or Monte-Carlo runs).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.filters.base import Plots
from seatrack.filters.base import TrackState
from seatrack.filters.base import common_columns
from seatrack.filters.base import finish_update
from seatrack.filters.base import predicted
from seatrack.filters.base import step_times
from seatrack.jit import gufunc
from seatrack.models.measurement import in_layout
from seatrack.models.motion import MotionModel

FloatArray = NDArray[np.float64]

__all__ = [
    "IMM",
    "IMMState",
    "IMMStep",
    "mix",
    "markov_predict_core",
    "mix_core",
    "combine",
    "combine_core",
    "check_transition",
    "uniform_transition",
    "FilterIMM",
]


@dataclass
class IMMState:
    """IMM state: per-model estimates and model probabilities.

    Model states are stored padded to the union of all models' components
    (``IMM.union_names``) and stacked, so mixing and combination run as one compiled
    kernel for any bank; ``valid[j, k]`` says whether model ``j`` has component ``k``.

    Attributes
    ----------
    X : array (..., M, n_union)
    P : array (..., M, n_union, n_union)
    mu : array (..., M) -- model probabilities
    """

    X: FloatArray
    P: FloatArray
    mu: FloatArray


@dataclass
class IMMStep:
    """Result of one IMM cycle.

    Attributes
    ----------
    state : IMMState -- posterior per-model state (carried to the next step)
    x, P : combined estimate on ``IMM.output_names`` and its covariance
    log_likelihood : (...) -- log of the mixture measurement likelihood
    model_log_likelihood : (..., M)
    nis : (..., M) -- per-model normalised innovation squared
    """

    state: IMMState
    x: FloatArray
    P: FloatArray
    log_likelihood: FloatArray
    model_log_likelihood: FloatArray
    nis: FloatArray


@njit(cache=True)
def markov_predict_core(PI, mu, out):  # pragma: no cover - compiled
    """Model probabilities one step ahead, ``out[j] = sum_i PI[i, j] mu[i]``, for the
    Markov chain ``PI[i, j] = P(model j at k | model i at k-1)`` (rows sum to one; a
    column-stochastic matrix is passed transposed)."""
    for j in range(out.shape[0]):
        s = 0.0
        for i in range(mu.shape[0]):
            s += PI[i, j] * mu[i]
        out[j] = s


@njit(cache=True, inline="always")
def mix_core(X, P, mu, PI, valid, X0, P0, c):  # pragma: no cover - compiled
    """Mixing (BLK 11.6.6 steps 1-2) with model-own augmentation of missing components."""
    M, n = X.shape
    markov_predict_core(PI, mu, c)
    for j in range(M):
        cj = c[j]
        for a in range(n):
            X0[j, a] = 0.0
            for b in range(n):
                P0[j, a, b] = 0.0
        if cj <= 0.0:
            for a in range(n):
                X0[j, a] = X[j, a]
                for b in range(n):
                    P0[j, a, b] = P[j, a, b]
            continue
        # mixed mean
        for i in range(M):
            w = PI[i, j] * mu[i] / cj
            for a in range(n):
                src = i if valid[i, a] != 0.0 else j
                X0[j, a] += w * X[src, a]
        # mixed covariance
        for i in range(M):
            w = PI[i, j] * mu[i] / cj
            if w == 0.0:
                continue
            for a in range(n):
                if valid[j, a] == 0.0:
                    continue
                ia = valid[i, a] != 0.0
                da = (X[i, a] if ia else X[j, a]) - X0[j, a]
                for b in range(a, n):
                    if valid[j, b] == 0.0:
                        continue
                    ib = valid[i, b] != 0.0
                    db = (X[i, b] if ib else X[j, b]) - X0[j, b]
                    if ia and ib:
                        pab = P[i, a, b]
                    elif not ia and not ib:
                        pab = P[j, a, b]
                    else:
                        pab = 0.0
                    v = w * (pab + da * db)
                    P0[j, a, b] += v
                    if b != a:
                        P0[j, b, a] += v


@njit(cache=True, inline="always")
def combine_core(X, P, c, ll, out, mu, x, Pc):  # pragma: no cover - compiled
    """Model probabilities ``mu_j ∝ c_j exp(ll_j)`` in log space, then moment matching on the
    components listed in ``out`` (indices as floats); returns ``log sum_j c_j exp(ll_j)``."""
    M = X.shape[0]
    k = out.shape[0]
    a = np.empty(M)
    amax = -np.inf
    for j in range(M):
        a[j] = (math.log(c[j]) if c[j] > 0.0 else -np.inf) + ll[j]
        if a[j] > amax:
            amax = a[j]
    s = 0.0
    for j in range(M):
        s += math.exp(a[j] - amax) if a[j] > -np.inf else 0.0
    lse = amax + math.log(s)
    for j in range(M):
        mu[j] = math.exp(a[j] - lse) if a[j] > -np.inf else 0.0
    for p in range(k):
        ip = int(out[p])
        v = 0.0
        for j in range(M):
            v += mu[j] * X[j, ip]
        x[p] = v
    for p in range(k):
        ip = int(out[p])
        for q in range(p, k):
            iq = int(out[q])
            v = 0.0
            for j in range(M):
                v += mu[j] * (P[j, ip, iq] + (X[j, ip] - x[p]) * (X[j, iq] - x[q]))
            Pc[p, q] = v
            Pc[q, p] = v
    return lse


@gufunc(
    "void(f8[:,:], f8[:,:,:], f8[:], f8[:,:], f8[:,:], f8[:,:], f8[:,:,:], f8[:])",
    "(M,n),(M,n,n),(M),(M,M),(M,n)->(M,n),(M,n,n),(M)",
)
def _mix_kernel(X, P, mu, PI, valid, X0, P0, c):  # pragma: no cover - compiled
    mix_core(X, P, mu, PI, valid, X0, P0, c)


@gufunc(
    "void(f8[:,:], f8[:,:,:], f8[:], f8[:], f8[:], f8[:], f8[:], f8[:,:], f8[:])",
    "(M,n),(M,n,n),(M),(M),(k)->(M),(k),(k,k),()",
)
def _combine_kernel(X, P, c, ll, out, mu, x, Pc, tot):  # pragma: no cover - compiled
    tot[0] = combine_core(X, P, c, ll, out, mu, x, Pc)


def mix(
    state: IMMState, transition: ArrayLike, valid: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """IMM interaction (mixing) step.

    Parameters
    ----------
    state : IMMState at k-1.
    transition : (M, M) or (..., M, M), ``[i, j] = P(j | i)``.
    valid : (M, n_union) 0/1 -- which components each model has.

    Returns
    -------
    X0, P0 : mixed initial conditions (padded, stacked); c : (..., M) predicted model
    probabilities ``c_j = sum_i pi_ij mu_i``.
    """
    return _mix_kernel(state.X, state.P, state.mu, transition, valid)  # type: ignore[no-any-return]


def combine(
    X: FloatArray, P: FloatArray, c: FloatArray, ll: FloatArray, out_index: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Posterior model probabilities and the moment-matched combination.

    Returns ``(mu, x, P, log_likelihood)`` where ``log_likelihood = log sum_j c_j Λ_j``.
    """
    o = np.asarray(out_index, dtype=float)
    return _combine_kernel(X, P, c, ll, o)  # type: ignore[no-any-return]


def uniform_transition(M: int, p_stay: float) -> FloatArray:
    """``M x M`` transition matrix that stays with probability ``p_stay`` and leaves to each
    other model with ``(1 - p_stay) / (M - 1)`` (symmetric: rows and columns sum to one)."""
    if M == 1:
        return np.ones((1, 1))
    pi = np.full((M, M), (1.0 - p_stay) / (M - 1))
    np.fill_diagonal(pi, p_stay)
    return pi


def check_transition(transition: FloatArray, M: int) -> None:
    """Raise ValueError unless ``transition`` is an ``M x M`` matrix of rows summing to one."""
    if transition.shape != (M, M):
        raise ValueError(f"transition must be {M}x{M}, got {transition.shape}")
    if np.any(transition < 0) or not np.allclose(transition.sum(axis=1), 1.0):
        raise ValueError("transition rows must be probabilities summing to 1 ([i, j] = P(j | i))")


class IMM:
    """Interacting Multiple Model estimator over a bank of motion models.

    Parameters
    ----------
    models : sequence of MotionModel
        E.g. ``[ConstantVelocity(q=0.5), CoordinatedTurn(q=0.5, q_omega=1e-4)]``.
    transition : (M, M) array
        ``transition[i, j] = P(model j at k | model i at k-1)``; rows sum to 1.
    measurement : sequence of measurement models, one per motion model
        (each built for that model's state size, e.g. ``RangeBearing(n=4)``,
        ``RangeBearing(n=5)``), or a single model when all states have one size.
        A model with a ``matrix()`` method (linear, e.g. ``Position``) uses the linear update.
    mu0 : (M,) initial model probabilities (default uniform).

    Notes
    -----
    Configuration lives in the constructor; state is carried in :class:`IMMState`
    objects, so one IMM object can run any number of tracks (batched or not).
    """

    def __init__(
        self,
        models: Sequence[MotionModel],
        transition: ArrayLike,
        measurement: Any,
        mu0: ArrayLike | None = None,
    ) -> None:
        self.models = list(models)
        M = len(self.models)
        if M < 1:
            raise ValueError("IMM needs at least one model")
        self.transition = np.asarray(transition, dtype=float)
        check_transition(self.transition, M)
        names = [tuple(m.state_names) for m in self.models]
        union: list[str] = []
        for n in names:
            union += [c for c in n if c not in union]
        self.union_names = tuple(union)
        self.state_names = names
        self.index = [np.array([union.index(c) for c in n], dtype=np.intp) for n in names]
        self._full = [bool(np.array_equal(ix, np.arange(len(union)))) for ix in self.index]
        self.valid = np.zeros((M, len(union)))
        for j, ix in enumerate(self.index):
            self.valid[j, ix] = 1.0
        common = [c for c in names[0] if all(c in n for n in names)]
        self.output_names = tuple(common)
        self._out = np.array([union.index(c) for c in common], dtype=float)
        meas = list(measurement) if isinstance(measurement, (list, tuple)) else [measurement] * M
        if len(meas) != M:
            raise ValueError(f"need one measurement model per motion model ({M}), got {len(meas)}")
        self.measurement = meas
        self._H = [m.matrix() if hasattr(m, "matrix") else None for m in meas]
        # one layout, linear motion and linear measurement: every model-matched predict and
        # update runs as ONE batched Kalman call over the model axis
        self._fused = (
            all(self._full)
            and all(getattr(m, "is_linear", False) for m in self.models)
            and all(H is not None for H in self._H)
        )
        self.fused_H = np.stack(self._H) if self._fused else None  # type: ignore[arg-type]
        # one measurement model on the padded layout (every model's state a prefix of the
        # union, e.g. CV + CT + CV): every model-matched extended update runs as ONE batched
        # call over the model axis; the padding's Jacobian columns are zero, so each model's
        # update, likelihood and NIS are those of its own layout
        N = len(union)
        prefix = all(np.array_equal(ix, np.arange(ix.size)) for ix in self.index)
        shared = [in_layout(m, N) for m in meas] if prefix else [None]
        self._shared = shared[0] if all(m is not None and m == shared[0] for m in shared) else None
        self.mu0 = np.full(M, 1.0 / M) if mu0 is None else np.asarray(mu0, dtype=float)
        self._cache: dict[tuple[int, float], tuple[FloatArray, FloatArray]] = {}

    # ------------------------------------------------------------------
    def initial_state(
        self, x0: ArrayLike, P0: ArrayLike, extra: dict[str, tuple[float, float]] | None = None
    ) -> IMMState:
        """Initial state from an estimate on ``output_names``.

        ``extra`` gives (mean, variance) for components not in the output (e.g.
        ``{"w": (0.0, 0.05**2)}`` for a turn rate); missing ones default to (0, 1).
        """
        xo = np.asarray(x0, dtype=float)
        Po = np.asarray(P0, dtype=float)
        lead = xo.shape[:-1]
        M, n = self.valid.shape
        oi = self._out.astype(np.intp)
        x = np.zeros(lead + (n,))
        P = np.zeros(lead + (n, n))
        x[..., oi] = xo
        P[..., oi[:, None], oi[None, :]] = Po
        for k, c in enumerate(self.union_names):
            if k not in oi:
                m, v = (extra or {}).get(c, (0.0, 1.0))
                x[..., k] = m
                P[..., k, k] = v
        X = np.repeat(x[..., None, :], M, axis=-2)
        PP = np.repeat(P[..., None, :, :], M, axis=-3)
        return IMMState(X, PP, np.broadcast_to(self.mu0, lead + (M,)).copy())

    def model_state(self, state: IMMState, j: int) -> tuple[FloatArray, FloatArray]:
        """State and covariance of model ``j`` in its own layout."""
        if self._full[j]:
            return state.X[..., j, :], state.P[..., j, :, :]
        ix = self.index[j]
        return state.X[..., j, ix], state.P[..., j, ix[:, None], ix[None, :]]

    def _predict_model(
        self, j: int, x: FloatArray, P: FloatArray, dt: float
    ) -> tuple[FloatArray, FloatArray]:
        model = self.models[j]
        if getattr(model, "is_linear", False) and np.ndim(dt) == 0:
            key = (j, float(dt))
            FQ = self._cache.get(key)
            if FQ is None:
                _, F = model.transition(np.zeros(model.ndim_state), dt)
                FQ = (np.ascontiguousarray(F), np.ascontiguousarray(model.noise(dt)))
                if len(self._cache) < 64:
                    self._cache[key] = FQ
            return kalman.predict(x, P, FQ[0], FQ[1])
        if hasattr(model, "predict"):  # compiled nonlinear prediction (e.g. CoordinatedTurn)
            return model.predict(x, P, dt)  # type: ignore[no-any-return]
        fx, F = model.transition(x, dt)
        return kalman.extended_predict(fx, P, F, model.noise(dt))

    def _store(self, X: FloatArray, P: FloatArray, j: int, x: FloatArray, Pj: FloatArray) -> None:
        if self._full[j]:
            X[..., j, :] = x
            P[..., j, :, :] = Pj
        else:
            ix = self.index[j]
            X[..., j, ix] = x
            P[..., j, ix[:, None], ix[None, :]] = Pj

    def _stacked_matrices(self, dt: float) -> tuple[FloatArray, FloatArray]:
        key = (-1, float(dt))
        FQ = self._cache.get(key)
        if FQ is None:
            mats = [m.transition(np.zeros(m.ndim_state), dt)[1] for m in self.models]
            FQ = (np.stack(mats), np.stack([m.noise(dt) for m in self.models]))
            if len(self._cache) < 64:
                self._cache[key] = FQ
        return FQ

    def predict(self, state: IMMState, dt: float) -> IMMState:
        """Mixing and model-matched prediction; ``mu`` of the result holds ``c_j``."""
        X0, P0, c = mix(state, self.transition, self.valid)
        if self._fused and np.ndim(dt) == 0:
            F, Q = self._stacked_matrices(dt)
            X, P = kalman.predict(X0, P0, F, Q)
            return IMMState(X, P, c)
        X, P = X0, P0  # fresh arrays from the kernel: predicted models are written in place
        for j in range(len(self.models)):
            xj, Pj = self.model_state(IMMState(X0, P0, c), j)
            x, Pp = self._predict_model(j, np.ascontiguousarray(xj), np.ascontiguousarray(Pj), dt)
            self._store(X, P, j, x, Pp)
        return IMMState(X, P, c)

    def update(
        self,
        predicted: IMMState,
        z: ArrayLike,
        R: ArrayLike,
        sensor: ArrayLike | None = None,
        check: bool = True,
    ) -> IMMStep:
        """Model-matched updates, model probabilities (log space), combination.

        ``check=False``: a non-positive-definite innovation covariance gives NaN estimates
        for that element instead of raising (see :func:`seatrack.kalman.update`)."""
        M = len(self.models)
        if self.fused_H is not None and sensor is None:
            zz = np.asarray(z, dtype=float)[..., None, :]
            res = kalman.update(predicted.X, predicted.P, zz, self.fused_H, R, check)
            mu, x, Pc, tot = combine(res.x, res.P, predicted.mu, res.log_likelihood, self._out)
            return IMMStep(IMMState(res.x, res.P, mu), x, Pc, tot, res.log_likelihood, res.nis)
        if self._shared is not None:
            hm = self._shared
            zz = np.asarray(z, dtype=float)[..., None, :]
            ss = None if sensor is None else np.asarray(sensor, dtype=float)[..., None, :]
            RR = np.asarray(R, dtype=float)
            RR = RR[..., None, :, :] if RR.ndim == predicted.P.ndim - 1 else RR
            X, P = predicted.X, predicted.P
            res = kalman.extended_update(
                X, P, zz, hm.h(X, ss), hm.jacobian(X, ss), RR, hm.angular, check
            )
            mu, x, Pc, tot = combine(res.x, res.P, predicted.mu, res.log_likelihood, self._out)
            return IMMStep(IMMState(res.x, res.P, mu), x, Pc, tot, res.log_likelihood, res.nis)
        X = predicted.X.copy()
        P = predicted.P.copy()
        lead = X.shape[:-2]
        ll = np.empty(lead + (M,))
        nis = np.empty(lead + (M,))
        for j, hm in enumerate(self.measurement):
            x, Pj = self.model_state(predicted, j)
            x = np.ascontiguousarray(x)
            Pj = np.ascontiguousarray(Pj)
            H = self._H[j]
            if H is not None and sensor is None:
                res = kalman.update(x, Pj, z, H, R, check)
            else:
                res = kalman.extended_update(
                    x, Pj, z, hm.h(x, sensor), hm.jacobian(x, sensor), R, hm.angular, check
                )
            self._store(X, P, j, res.x, res.P)
            ll[..., j] = res.log_likelihood
            nis[..., j] = res.nis
        mu, x, Pc, tot = combine(X, P, predicted.mu, ll, self._out)
        return IMMStep(IMMState(X, P, mu), x, Pc, tot, ll, nis)

    def step(
        self,
        state: IMMState,
        z: ArrayLike,
        dt: float,
        R: ArrayLike,
        sensor: ArrayLike | None = None,
    ) -> IMMStep:
        """One full IMM cycle: mix, predict over ``dt``, update with ``z``."""
        return self.update(self.predict(state, dt), z, R, sensor)

    def combined(self, state: IMMState) -> tuple[FloatArray, FloatArray]:
        """Combined estimate of a state (e.g. a prediction) on ``output_names``."""
        zero = np.zeros(state.mu.shape)
        _, x, P, _ = combine(state.X, state.P, state.mu, zero, self._out)
        return x, P


class FilterIMM:
    """An IMM whose models are any filters honouring the contract.

    Mixing is by component name (:attr:`RecursiveFilter.state_names`, model-own
    augmentation for components a model lacks, as :class:`IMM`); each model's own ``aux``
    (e.g. a heading filter) follows the model, unmixed; the model likelihoods are the
    ``log_likelihood`` of each model's :meth:`update`. A plot rejected by any model is
    rejected by the IMM (the track keeps its prediction). ``TrackState.aux`` holds the model
    states ``m0, m1, ...`` (nested TrackStates) and the model probabilities ``mu (B, M)``.

    Parameters
    ----------
    models : filters built for the same plots (same ``d``).
    transition : (M, M), ``[i, j] = P(model j at k | model i at k-1)``.
    mu0 : (M,) initial model probabilities (default uniform).
    names : model names for the ``p_<name>`` columns (default ``m0, m1, ...``).
    """

    def __init__(
        self,
        models: Sequence[Any],
        transition: ArrayLike,
        mu0: ArrayLike | None = None,
        names: Sequence[str] | None = None,
    ) -> None:
        self.models = list(models)
        M = len(self.models)
        self.d = self.models[0].d
        self.range_rate = self.models[0].range_rate
        self.transition = np.asarray(transition, dtype=float)
        check_transition(self.transition, M)
        names_j = [tuple(m.state_names) for m in self.models]
        union: list[str] = []
        for n in names_j:
            union += [c for c in n if c not in union]
        self.index = [np.array([union.index(c) for c in n], dtype=np.intp) for n in names_j]
        self.valid = np.zeros((M, len(union)))
        for j, ix in enumerate(self.index):
            self.valid[j, ix] = 1.0
        common = [c for c in names_j[0] if all(c in n for n in names_j)]
        self._names = tuple(common)
        self._out = np.array([union.index(c) for c in common], dtype=float)
        self.mu0 = np.full(M, 1.0 / M) if mu0 is None else np.asarray(mu0, dtype=float)
        self.names = tuple(names) if names is not None else tuple(f"m{j}" for j in range(M))
        self.sensor = getattr(self.models[0], "sensor", None)

    @property
    def state_names(self) -> tuple[str, ...]:
        return self._names

    def _stack(self, states: Sequence[TrackState]) -> tuple[FloatArray, FloatArray]:
        B = len(states[0])
        n = self.valid.shape[1]
        X = np.zeros((B, len(states), n))
        P = np.zeros((B, len(states), n, n))
        for j, (s, ix) in enumerate(zip(states, self.index, strict=True)):
            X[:, j, ix] = s.x
            P[:, j, ix[:, None], ix[None, :]] = s.P
        return X, P

    def _models(self, state: TrackState) -> list[TrackState]:
        return [state.aux[f"m{j}"] for j in range(len(self.models))]

    def _combine(
        self, states: Sequence[TrackState], c: FloatArray, ll: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        X, P = self._stack(states)
        return combine(X, P, c, ll, self._out)  # type: ignore[no-any-return]

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        states = [m.initiate(t, x, P) for m in self.models]
        B = len(states[0])
        mu = np.broadcast_to(self.mu0, (B, len(self.models))).copy()
        _, xc, Pc, _ = self._combine(states, mu, np.zeros_like(mu))
        aux: dict[str, Any] = {f"m{j}": s for j, s in enumerate(states)} | {"mu": mu}
        return TrackState.new(states[0].t, xc, Pc, aux)

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt, _ = step_times(state, t)
        states = self._models(state)
        X, P = self._stack(states)
        X0, P0, c = _mix_kernel(X, P, state.aux["mu"], self.transition, self.valid)
        out = []
        for j, (m, s, ix) in enumerate(zip(self.models, states, self.index, strict=True)):
            mixed = s.replace(x=X0[:, j, ix], P=P0[:, j, ix[:, None], ix[None, :]])
            out.append(m.predict(mixed, tt))
        _, xc, Pc, _ = self._combine(out, c, np.zeros_like(c))
        aux: dict[str, Any] = {f"m{j}": s for j, s in enumerate(out)} | {"mu": c}
        return predicted(state, tt, xc, Pc, aux)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        """Moment-matched mixture of the models' innovations (weights: ``mu``)."""
        mu = state.aux["mu"]
        parts = [
            m.innovation(s, plots) for m, s in zip(self.models, self._models(state), strict=True)
        ]
        y = sum(mu[:, j, None] * p[0] for j, p in enumerate(parts))
        S = sum(
            mu[:, j, None, None] * (p[1] + (p[0] - y)[:, :, None] * (p[0] - y)[:, None, :])
            for j, p in enumerate(parts)
        )
        return np.asarray(y), np.asarray(S)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        y, S = self.innovation(state, plots)
        states = [m.update(s, plots) for m, s in zip(self.models, self._models(state), strict=True)]
        ll = np.stack([s.log_likelihood for s in states], -1)
        ok = np.isfinite(ll).all(-1)
        ll = np.where(ok[:, None], ll, 0.0)
        mu, xc, Pc, tot = self._combine(states, state.aux["mu"], ll)
        aux: dict[str, Any] = {f"m{j}": s for j, s in enumerate(states)} | {"mu": mu}
        return finish_update(state, xc, Pc, kalman.mahalanobis(y, S), tot, state.t, aux, ok)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        cols = common_columns(state.x, state.P, self.d)
        for j, name in enumerate(self.names):
            cols[f"p_{name}"] = state.aux["mu"][:, j]
        return cols
