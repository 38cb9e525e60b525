"""Constant-velocity extended Kalman filter on polar radar / sonar plots.

The reference single-model tracker of ``seatrack track --method ekf`` and the shared
plumbing every plot-driven method uses: turning a :class:`~seatrack.io.plots.PlotTrack`
into measurement vectors, the matching measurement model and noise covariance
(:func:`plot_measurements`), a two-plot initialisation (:func:`initial_state`), and the
output columns (:func:`output_columns`).

Measurements are used in their native polar form (range, azimuth, [elevation],
[range rate]) with angle-wrapped innovations; the state is Cartesian
``[x, y, (z), vx, vy, (vz)]`` (East, North, Up; m, m/s).

Configuration keys (``config`` mapping; SI unless the name says otherwise):

* ``q`` -- white-noise acceleration PSD, m^2/s^3 (default 1.0)
* ``sigma_range_m`` (default 10), ``sigma_azimuth_deg`` (0.5), ``sigma_elevation_deg`` (0.5),
  ``sigma_range_rate_mps`` (1.0)
* ``use_range_rate`` -- use the range-rate column when present (default true)
* ``initial_speed_sigma_mps`` -- velocity std of the first state (default 50)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seatrack import kalman
from seatrack.config import param
from seatrack.filters.base import (
    Plots,
    PlotStatus,
    SensorNoise,
    TrackState,
    common_columns,
    finish_update,
    measurement_model,
    measurement_noise,
)
from seatrack.geometry import spherical_to_cart
from seatrack.io.plots import PlotTrack
from seatrack.models.measurement import RangeBearing, RangeBearingElevation, RangeRate, Stacked
from seatrack.models.motion import ConstantVelocity, cv_noise, cv_transition

FloatArray = NDArray[np.float64]

__all__ = [
    "EKF",
    "EKFConfig",
    "PlotMeasurements",
    "plot_measurements",
    "initial_state",
    "output_columns",
    "run_ekf",
    "track_plots",
]


@dataclass(frozen=True)
class PlotMeasurements:
    """Plots as filter inputs.

    Attributes
    ----------
    z : (N, m) -- range (m), azimuth (rad), [elevation (rad)], [range rate (m/s)]
    R : (m, m) -- measurement-noise covariance (diagonal)
    sensor : (N, 2d) -- sensor position and velocity per plot (as ``RangeRate`` expects)
    model : measurement model for the CV state of dimension ``2d``
    d : 2 or 3 spatial dimensions
    """

    z: FloatArray
    R: FloatArray
    sensor: FloatArray
    model: Any
    d: int


def plot_measurements(
    plots: PlotTrack, config: Mapping[str, Any], n: int | None = None
) -> PlotMeasurements:
    """Measurement vectors, noise covariance and model for a CV-type state.

    ``n`` is the state dimension (default ``2d``; larger for states with extra
    components appended after the velocities, e.g. a turn rate).
    """
    d = 3 if plots.is_3d else 2
    nn = 2 * d if n is None else n
    cols = [plots.range, plots.azimuth]
    sig = [
        float(config.get("sigma_range_m", 10.0)),
        np.radians(float(config.get("sigma_azimuth_deg", 0.5))),
    ]
    if d == 3:
        assert plots.elevation is not None
        cols.append(plots.elevation)
        sig.append(np.radians(float(config.get("sigma_elevation_deg", 0.5))))
        base: Any = RangeBearingElevation(n=nn, pos=(0, 1, 2))
    else:
        base = RangeBearing(n=nn, pos=(0, 1))
    model: Any = base
    if plots.range_rate is not None and bool(config.get("use_range_rate", True)):
        cols.append(plots.range_rate)
        sig.append(float(config.get("sigma_range_rate_mps", 1.0)))
        model = Stacked([base, RangeRate(n=nn, pos=tuple(range(d)), vel=tuple(range(d, 2 * d)))])
    for s in sig:
        if not np.isfinite(s) or s <= 0:
            raise ValueError(f"measurement sigmas must be positive, got {sig}")
    z = np.stack(cols, -1)
    sensor = np.concatenate([plots.sensor[:, :d], plots.sensor_vel[:, :d]], -1)
    return PlotMeasurements(z, np.diag(np.square(sig)), sensor, model, d)


def initial_state(
    plots: PlotTrack, pm: PlotMeasurements, speed_sigma: float
) -> tuple[FloatArray, FloatArray]:
    """CV state ``(2d,)`` and covariance from the first plot (zero velocity, wide prior).

    The position covariance is the linearised polar-to-Cartesian one.
    """
    d = pm.d
    el = plots.elevation[0] if plots.elevation is not None else 0.0
    p = spherical_to_cart(plots.range[0], plots.azimuth[0], el)[:d] + plots.sensor[0, :d]
    H = pm.model.jacobian(np.concatenate([p, np.zeros(d)]), pm.sensor[0])[:d, :d]
    Hinv = np.linalg.inv(H)
    Rp = Hinv @ pm.R[:d, :d] @ Hinv.T
    x = np.concatenate([p, np.zeros(d)])
    P = np.zeros((2 * d, 2 * d))
    P[:d, :d] = kalman.symmetrize(Rp)
    P[d:, d:] = np.eye(d) * speed_sigma**2
    return x, P


def output_columns(x: FloatArray, P: FloatArray, d: int) -> dict[str, FloatArray]:
    """Common TRACK.csv columns from CV-layout states ``(N, >=2d)`` and covariances."""
    N = x.shape[0]
    zero = np.zeros(N)
    std = np.sqrt(np.maximum(np.diagonal(P, axis1=-2, axis2=-1), 0.0))
    return {
        "x_m": x[:, 0],
        "y_m": x[:, 1],
        "z_m": x[:, 2] if d == 3 else zero,
        "vx_mps": x[:, d],
        "vy_mps": x[:, d + 1],
        "vz_mps": x[:, d + 2] if d == 3 else zero,
        "std_x_m": std[:, 0],
        "std_y_m": std[:, 1],
        "std_z_m": std[:, 2] if d == 3 else zero,
    }


@dataclass(frozen=True)
class EKFRun:
    """Filtered states ``x (N, 2d)``, covariances ``P (N, 2d, 2d)``, NIS ``(N,)``."""

    x: FloatArray
    P: FloatArray
    nis: FloatArray
    d: int


def run_ekf(plots: PlotTrack, config: Mapping[str, Any]) -> EKFRun:
    """Run the CV-EKF over one track's plots (first plot initialises, later ones update)."""
    pm = plot_measurements(plots, config)
    d = pm.d
    cv = ConstantVelocity(q=float(config.get("q", 1.0)), d=d)
    x, P = initial_state(plots, pm, float(config.get("initial_speed_sigma_mps", 50.0)))
    N = len(plots)
    xs = np.empty((N, 2 * d))
    Ps = np.empty((N, 2 * d, 2 * d))
    nis = np.full(N, np.nan)
    xs[0], Ps[0] = x, P
    ang = pm.model.angular
    cache: dict[float, tuple[FloatArray, FloatArray]] = {}  # F, Q per scan interval
    for k in range(1, N):
        dt = float(plots.t[k] - plots.t[k - 1])
        FQ = cache.get(dt)
        if FQ is None:
            if len(cache) > 256:  # irregular sampling: keep the cache small
                cache.clear()
            FQ = cache.setdefault(dt, (cv.transition(x, dt)[1], cv.noise(dt)))
        x, P = kalman.predict(x, P, FQ[0], FQ[1])
        s = pm.sensor[k]
        res = kalman.extended_update(
            x, P, pm.z[k], pm.model.h(x, s), pm.model.jacobian(x, s), pm.R, ang
        )
        x, P = res.x, res.P
        xs[k], Ps[k], nis[k] = x, P, res.nis
    return EKFRun(xs, Ps, nis, d)


def track_plots(plots: PlotTrack, config: Mapping[str, Any]) -> dict[str, FloatArray]:
    """``seatrack track --method ekf``: output columns, one row per plot (adds ``nis``)."""
    run = run_ekf(plots, config)
    cols = output_columns(run.x, run.P, run.d)
    cols["nis"] = run.nis
    return cols


# ---------------------------------------------------------------------------
# The filter contract (seatrack.filters.base)
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class EKFConfig:
    """Parameters of the constant-velocity EKF (``seatrack track --method ekf``)."""

    q: float = param(1.0, unit="m^2/s^3", doc="white-noise acceleration PSD", min=0)
    initial_speed_sigma: float = param(
        50.0,
        key="initial_speed_sigma_mps",
        unit="m/s",
        doc="velocity std of a new track (per axis)",
        min=0,
        exclusive_min=True,
    )
    use_range_rate: bool = param(True, doc="use the plots' range rate when they have one")


class EKF:
    """Constant-velocity extended Kalman filter on polar plots (the reference filter).

    State ``[x, y, (z), vx, vy, (vz)]`` (m, m/s); continuous white-noise acceleration with
    PSD ``q``; measurements range, azimuth, [elevation], [range rate] used in polar form
    with wrapped angle innovations; Joseph-form update. Implements
    :class:`seatrack.filters.base.RecursiveFilter` on batches of tracks.

    Parameters
    ----------
    config : EKFConfig
    sensor : SensorNoise -- measurement noise of the plots
    d : 2 or 3 -- spatial dimensions of the plots
    range_rate : whether the plots carry range rate (used if ``config.use_range_rate``)
    """

    Config = EKFConfig

    def __init__(
        self,
        config: EKFConfig | None = None,
        sensor: SensorNoise | None = None,
        d: int = 2,
        range_rate: bool = False,
    ) -> None:
        self.config = config or EKFConfig()
        self.sensor = sensor or SensorNoise()
        self.d = d
        self.range_rate = bool(range_rate and self.config.use_range_rate)
        self.model = measurement_model(d, 2 * d, self.range_rate)
        self.R = measurement_noise(self.sensor, d, self.range_rate)
        self._angular = self.model.angular.astype(float)

    @property
    def state_names(self) -> tuple[str, ...]:
        axes = ("x", "y", "z")[: self.d]
        return axes + tuple("v" + a for a in axes)

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        return TrackState.new(t, x, P)

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt = np.broadcast_to(np.asarray(t, dtype=float), state.t.shape)
        dt = tt - state.t
        if np.any(dt < 0):
            raise ValueError("predict: a track would go back in time")
        F = cv_transition(dt, self.d)
        Q = cv_noise(dt, self.config.q, self.d)
        x, P = kalman.predict(state.x, state.P, F, Q)
        nan = np.full(len(state), np.nan)
        status = np.full(len(state), PlotStatus.PREDICTED, np.int8)
        return state.replace(
            t=tt.copy(), x=x, P=P, nis=nan, log_likelihood=nan.copy(), status=status
        )

    def _sensor(self, plots: Plots) -> FloatArray:
        d = self.d
        return np.concatenate([plots.sensor[:, :d], plots.sensor_vel[:, :d]], -1)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        s = self._sensor(plots)
        H = self.model.jacobian(state.x, s)
        y = plots.polar(self.range_rate) - self.model.h(state.x, s)
        y = np.where(self._angular > 0, (y + np.pi) % (2 * np.pi) - np.pi, y)
        S = H @ state.P @ np.swapaxes(H, -1, -2) + self.R
        return y, kalman.symmetrize(S)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        s = self._sensor(plots)
        z = plots.polar(self.range_rate)
        ok = np.asarray(np.isfinite(z).all(-1) & np.isfinite(state.x).all(-1))
        z = np.where(ok[:, None], z, self.model.h(state.x, s))
        with np.errstate(all="ignore"):  # an absurd plot is rejected below, not warned about
            res = kalman.extended_update(
                state.x,
                state.P,
                z,
                self.model.h(state.x, s),
                self.model.jacobian(state.x, s),
                self.R,
                self._angular,
                check=False,
            )
        return finish_update(state, res.x, res.P, res.nis, res.log_likelihood, state.t, ok=ok)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        return common_columns(state.x, state.P, self.d)
