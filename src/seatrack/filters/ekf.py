"""Constant-velocity extended Kalman filter on polar radar / sonar plots (``--method ekf``).

The reference implementation of the filter contract (:mod:`seatrack.filters.base`):
measurements are used in their native polar form (range, azimuth, [elevation],
[range rate]) with angle-wrapped innovations; the state is Cartesian
``[x, y, (z), vx, vy, (vz)]`` (East, North, Up; m, m/s). Parameters: :class:`EKFConfig`
(method) and :class:`~seatrack.filters.base.SensorNoise` (sensor).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.config import Checked
from seatrack.config import param
from seatrack.filters.base import CartesianState
from seatrack.filters.base import ConfiguredFilter
from seatrack.filters.base import Plots
from seatrack.filters.base import TrackState
from seatrack.filters.base import accel_sigma_param
from seatrack.filters.base import common_columns
from seatrack.filters.base import finish_update
from seatrack.filters.base import measurement_model
from seatrack.filters.base import measurement_noise
from seatrack.filters.base import predicted
from seatrack.filters.base import speed_sigma_param
from seatrack.filters.base import step_times
from seatrack.filters.base import usable
from seatrack.filters.base import wrap_angles
from seatrack.models.measurement import polar_measurement
from seatrack.models.motion import cv_matrices
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition
from seatrack.models.motion import scan_psd
from seatrack.models.targets import TargetClass

FloatArray = NDArray[np.float64]

__all__ = ["EKF", "EKFConfig", "sensor_state"]


def sensor_state(plots: Plots, d: int) -> FloatArray:
    """Sensor ``[position, velocity]`` ``(N, 2d)`` of each plot, as ``RangeRate`` expects."""
    return np.concatenate([plots.sensor[:, :d], plots.sensor_vel[:, :d]], -1)


@dataclass(frozen=True)
class EKFConfig(Checked):
    """Parameters of the constant-velocity EKF (``seatrack track --method ekf``)."""

    q: float = param(1.0, unit="m^2/s^3", doc="white-noise acceleration PSD", min=0)
    initial_speed_sigma: float = speed_sigma_param(50.0)
    use_range_rate: bool = param(True, doc="use the plots' range rate when they have one")
    sigma_accel: float = accel_sigma_param("sigma_accel_mps2", "q")

    @classmethod
    def for_target(cls, target: TargetClass) -> EKFConfig:
        """One fixed noise for a target class: the typical manoeuvre acceleration,
        ``q = a_typical^2 T`` (the upper end of Bar-Shalom et al.'s ``0.5 a_M <= sigma_a <=
        a_M``), and the class's maximum speed as the initial speed std."""
        return cls(q=0.0, sigma_accel=target.accel_typical, initial_speed_sigma=target.speed_max)


class EKF(ConfiguredFilter, CartesianState):
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
    config: EKFConfig

    def _setup(self) -> None:
        self.model = measurement_model(self.d, 2 * self.d, self.range_rate)
        self.R = measurement_noise(self.sensor, self.d, self.range_rate)
        self._angular = self.model.angular.astype(float)

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        xx = np.asarray(x, dtype=float)
        n = xx.shape[-1]
        F = np.broadcast_to(np.eye(n), (xx.shape[0], n, n)).copy()
        return TrackState.new(t, xx, P, {"F": F})

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        """Predict to ``t``; ``aux["F"]`` keeps the transition matrix (for the RTS smoother)."""
        tt, dt = step_times(state, t)
        c = self.config
        if c.sigma_accel > 0:
            F, Q = cv_transition(dt, self.d), cv_noise(dt, scan_psd(c.q, c.sigma_accel, dt), self.d)
        else:
            F, Q = cv_matrices(dt, c.q, self.d)
        x, P = kalman.predict(state.x, state.P, F, Q)
        return predicted(state, tt, x, P, {"F": np.broadcast_to(F, P.shape)})

    def _sensor(self, plots: Plots) -> FloatArray:
        return sensor_state(plots, self.d)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        hx, H = polar_measurement(state.x, self._sensor(plots), self.d, self.range_rate)
        y = plots.polar(self.range_rate) - hx
        y = wrap_angles(y, self._angular)
        S = H @ state.P @ np.swapaxes(H, -1, -2) + self.R
        return y, kalman.symmetrize(S)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        hx, H = polar_measurement(state.x, self._sensor(plots), self.d, self.range_rate)
        z, ok = usable(plots.polar(self.range_rate), hx)
        with np.errstate(all="ignore"):  # an absurd plot is rejected below, not warned about
            res = kalman.extended_update(
                state.x, state.P, z, hx, H, self.R, self._angular, check=False
            )
        return finish_update(state, res.x, res.P, res.nis, res.log_likelihood, state.t, ok=ok)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        return common_columns(state.x, state.P, self.d)
