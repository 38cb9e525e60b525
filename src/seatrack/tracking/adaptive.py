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

The model states live in ``aux["noise_models"]`` (a nested TrackState of shape ``(B, ...)``
per model: ``aux["noise_models"]`` holds the models stacked on a second axis) and the model
probabilities in ``aux["noise_mu"]``; the ``manoeuvre`` output column is the probability of
the high-noise model. The switching probability per scan ``p_switch`` makes the transition
matrix ``[[1 - p, p], [p, 1 - p]]``. Only the contract's state layout is used (positions
``0..d-1``, velocities ``d..2d-1``), so any filter can be wrapped.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seatrack.filters.base import Plots, PlotStatus, RecursiveFilter, TrackState
from seatrack.models.motion import cv_noise

FloatArray = NDArray[np.float64]

__all__ = ["NoiseLevels"]

MODELS, MU = "noise_models", "noise_mu"


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


class NoiseLevels:
    """An IMM over process-noise levels of one filter (see the module docstring).

    Parameters
    ----------
    flt : the filter, configured with the lowest noise level
    extra : extra white-noise acceleration PSD of each model, m^2/s^3 (first usually 0)
    p_switch : probability per scan of leaving a model
    """

    def __init__(
        self, flt: RecursiveFilter, extra: Sequence[float] = (0.0, 1.0), p_switch: float = 0.05
    ) -> None:
        ex = np.asarray(extra, dtype=float)
        if ex.ndim != 1 or ex.size < 2 or np.any(ex < 0) or not 0 < p_switch < 1:
            raise ValueError(
                f"need two or more extra noise levels >= 0 and 0 < p_switch < 1, got "
                f"{list(ex)}, {p_switch}"
            )
        self.flt = flt
        self.extra = ex
        M = ex.size
        self.transition = np.full((M, M), p_switch / (M - 1))
        np.fill_diagonal(self.transition, 1 - p_switch)
        self.d = flt.d
        self.range_rate = flt.range_rate

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.flt.state_names

    # -- helpers ------------------------------------------------------------------------
    def _outer(self, models: TrackState, mu: FloatArray, status: Any = None) -> TrackState:
        """Combined (moment-matched) state over the models, carrying them in aux."""
        x = np.einsum("bm,bmi->bi", mu, models.x)
        dx = models.x - x[:, None, :]
        P = np.einsum("bm,bmij->bij", mu, models.P + dx[..., :, None] * dx[..., None, :])
        best = np.argmax(mu, axis=1)
        dom = models.map(lambda a: a[np.arange(a.shape[0]), best])  # the dominant model
        return TrackState(
            dom.t, x, 0.5 * (P + np.swapaxes(P, -1, -2)), dom.nis, dom.log_likelihood,
            dom.status if status is None else status, {**dom.aux, MODELS: models, MU: mu},
        )  # fmt: skip

    @staticmethod
    def _parts(state: TrackState) -> tuple[TrackState, FloatArray]:
        return state.aux[MODELS], np.asarray(state.aux[MU])

    # -- the contract -------------------------------------------------------------------
    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        s = self.flt.initiate(t, x, P)
        M = self.extra.size
        models = _zip_stack([s] * M)
        mu = np.full((len(s), M), 1.0 / M)
        return self._outer(models, mu, s.status)

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        models, mu = self._parts(state)
        B, M = mu.shape
        c = mu @ self.transition  # (B, M) predicted model probabilities
        mix = mu[:, :, None] * self.transition[None] / np.maximum(c[:, None, :], 1e-300)
        x0 = np.einsum("bij,bik->bjk", mix, models.x)
        dx = models.x[:, :, None, :] - x0[:, None, :, :]  # (B, i, j, n)
        P0 = np.einsum(
            "bij,bijkl->bjkl", mix, models.P[:, :, None] + dx[..., :, None] * dx[..., None, :]
        )
        # all models of all tracks in one call of the filter: a batch of B * M states
        tt = np.repeat(np.broadcast_to(np.asarray(t, dtype=float), (B,)), M)
        flat = _flat(models.replace(x=x0, P=P0))
        s = self.flt.predict(flat, tt)
        extra = np.tile(self.extra, B)
        P = s.P.copy()
        d2 = 2 * self.d
        P[:, :d2, :d2] += cv_noise(s.t - flat.t, extra, self.d)
        return self._outer(_unflat(s.replace(P=P), B, M), c)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        models, c = self._parts(state)
        B, M = c.shape
        new = _unflat(self.flt.update(_flat(models), plots.take(np.repeat(np.arange(B), M))), B, M)
        ok = new.status == PlotStatus.UPDATED  # (B, M)
        ll = np.where(ok, new.log_likelihood, -np.inf)
        any_ok = ok.any(axis=1)
        top = np.max(ll, axis=1, keepdims=True)
        top = np.where(np.isfinite(top), top, 0.0)
        w = c * np.exp(ll - top)
        tot = w.sum(1, keepdims=True)
        mu = np.where(any_ok[:, None], w / np.maximum(tot, 1e-300), c)
        status = np.where(any_ok, PlotStatus.UPDATED, PlotStatus.REJECTED).astype(np.int8)
        outer = self._outer(new, mu, status)
        mix_ll = np.where(any_ok, top[:, 0] + np.log(np.where(any_ok, tot[:, 0], 1.0)), np.nan)
        return outer.replace(log_likelihood=mix_ll)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        base = TrackState(state.t, state.x, state.P, state.nis, state.log_likelihood,
                          state.status, {k: v for k, v in state.aux.items()
                                         if k not in (MODELS, MU)})  # fmt: skip
        return self.flt.innovation(base, plots)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        base = TrackState(state.t, state.x, state.P, state.nis, state.log_likelihood,
                          state.status, {k: v for k, v in state.aux.items()
                                         if k not in (MODELS, MU)})  # fmt: skip
        cols = self.flt.columns(base)
        cols["manoeuvre"] = np.asarray(state.aux[MU])[:, -1]
        return cols
