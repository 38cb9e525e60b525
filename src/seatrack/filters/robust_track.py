"""The robust sonar filters and their baselines on the filter contract.

``seatrack track --method robust-spec | robust-adaptive-spec | ekf-rb``: 2-D
range/bearing filters (3-D plots are tracked in the horizontal plane). ``TrackState.x`` is
the Cartesian ``[x, y, vx, vy(, ax, ay)]`` (East, North), so states mix by name with every
other filter; the robust filters keep their beam-frame internals in ``aux``. The maths is
that of :mod:`seatrack.filters.robust` (algorithms R and A, :func:`robust_update`) and
:mod:`seatrack.filters.robust_baselines` (the EKF update of ``ekf-rb``), shared with their
Monte-Carlo batch functions. The ``huber`` and ``student-t`` methods are level IMMs
(:mod:`seatrack.filters.levels`).

A new track starts from the one initiator (:func:`seatrack.filters.base.plot_gaussian`);
the robust filters project its Cartesian covariance onto the beam frame at the first update
(the beam bearing needs the sensor position of a plot). The median-of-the-first-plots start
of the paper's set-up (:func:`seatrack.filters.robust.initial_state`) remains available to
the batch function :func:`seatrack.filters.robust.robust_filter`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.config import Checked
from seatrack.config import param
from seatrack.filters.base import ConfiguredFilter
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import common_columns
from seatrack.filters.base import finish_update
from seatrack.filters.base import predicted
from seatrack.filters.base import speed_sigma_param
from seatrack.filters.base import step_times
from seatrack.filters.base import usable
from seatrack.filters.base import wrap_angles
from seatrack.filters.robust import RobustConfig
from seatrack.filters.robust import SonarModel
from seatrack.filters.robust import axis_noise
from seatrack.filters.robust import axis_transition
from seatrack.filters.robust import beam_innovations
from seatrack.filters.robust import beam_to_cartesian_cov
from seatrack.filters.robust import per_axis_to_flat
from seatrack.filters.robust import robust_update
from seatrack.filters.robust import rotate_blocks
from seatrack.filters.robust_baselines import plain_update
from seatrack.geometry import angle_diff
from seatrack.geometry import rotation_to_beam
from seatrack.models.measurement import polar_measurement
from seatrack.models.targets import TargetClass

FloatArray = NDArray[np.float64]

__all__ = [
    "SonarMotionConfig",
    "RobustTrackConfig",
    "RangeBearingEKF",
    "Robust",
    "RobustAdaptive",
]

_LOG_2PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class SonarMotionConfig(Checked):
    """Motion model and start of the sonar filters (see :class:`SonarModel`)."""

    sigma_a: float = param(0.02, unit="m/s^2", doc="constant disturbance L0 (accel. std)", min=0)
    acceleration: bool = param(False, doc="full state with acceleration (else truncated)")
    initial_speed_sigma: float = speed_sigma_param(8.0, aliases=("init_sigma_v",))
    init_sigma_acc: float = param(
        0.2, unit="m/s^2", doc="acceleration std of a new track", min=0, exclusive_min=True
    )

    @classmethod
    def for_target(cls, target: TargetClass) -> Any:
        """A target class's noise: the disturbance ``L0`` at the class's typical manoeuvre
        acceleration, its maximum speed as the initial speed std."""
        return cls(sigma_a=target.accel_typical, initial_speed_sigma=target.speed_max)

    def sonar_model(self, sensor: SensorNoise) -> SonarModel:
        return SonarModel(
            sigma_range=sensor.sigma_range,
            sigma_bearing=sensor.sigma_azimuth,
            sigma_a=self.sigma_a,
            acceleration=self.acceleration,
            init_sigma_v=self.initial_speed_sigma,
            init_sigma_acc=self.init_sigma_acc,
        )


@dataclass(frozen=True)
class RobustTrackConfig(RobustConfig, SonarMotionConfig):
    """Parameters of ``--method robust-spec`` / ``robust-adaptive-spec`` (thresholds of
    :class:`RobustConfig` plus the motion model)."""


def _per_axis(x: FloatArray, k: int) -> FloatArray:
    """Flat ``(B, 2k)`` ``[x, y, vx, vy, ...]`` to per-axis ``(B, 2, k)`` (rows E, N)."""
    return np.swapaxes(x.reshape(x.shape[0], k, 2), -1, -2)


def _flat(X: FloatArray) -> FloatArray:
    return np.swapaxes(X, -1, -2).reshape(X.shape[0], -1)


def _beam_blocks(P: FloatArray, psi: FloatArray) -> FloatArray:
    """Diagonal blocks ``(B, 2, k, k)`` of a Cartesian covariance in the beam frame ``psi``."""
    B, n = P.shape[0], P.shape[-1]
    k = n // 2
    R = rotation_to_beam(psi)
    return np.einsum("bca,bcd,biajd->bcij", R, R, P.reshape(B, k, 2, k, 2))


class _Sonar(ConfiguredFilter):
    """Shared shell of the 2-D sonar filters: layout, initiation, columns (no range rate:
    the configurations have no ``use_range_rate``)."""

    Config: ClassVar[type] = SonarMotionConfig
    dims: ClassVar[tuple[int, ...]] = (2,)

    def _setup(self) -> None:
        self.model = self.config.sonar_model(self.sensor)
        self.k = self.model.order
        self.r_nom = np.array([self.sensor.sigma_range**2, self.sensor.sigma_azimuth**2])

    @property
    def state_names(self) -> tuple[str, ...]:
        return ("x", "y", "vx", "vy", "ax", "ay")[: 2 * self.k]

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        xx = np.asarray(x, dtype=float)
        B, n = xx.shape[0], 2 * self.k
        x0 = np.zeros((B, n))
        P0 = np.zeros((B, n, n))
        x0[:, :4] = xx
        P0[:, :4, :4] = np.asarray(P, dtype=float)
        if self.k == 3:
            P0[:, 4, 4] = P0[:, 5, 5] = self.model.init_sigma_acc**2
        flags = np.zeros((B, 2), dtype=bool)
        return TrackState.new(t, x0, P0, self._initial_aux(x0, P0) | {"outlier": flags})

    def _initial_aux(self, x: FloatArray, P: FloatArray) -> dict[str, Any]:
        return {"adapting": np.zeros((x.shape[0], 2), dtype=bool)}

    def _matrices(self, dt: FloatArray, noise: bool = True) -> tuple[FloatArray, FloatArray]:
        Phi = axis_transition(dt, self.k)
        L0 = axis_noise(dt, self.model.sigma_a, self.k) if noise else np.zeros_like(Phi)
        return Phi, L0

    def _measurement(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        s = np.concatenate([plots.sensor[:, :2], plots.sensor_vel[:, :2]], -1)
        return polar_measurement(state.x, s, 2, False)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        hx, H = self._measurement(state, plots)
        y = wrap_angles(plots.polar(False) - hx, np.array([0.0, 1.0]))
        S = H @ state.P @ np.swapaxes(H, -1, -2) + np.diag(self.r_nom)
        return y, kalman.symmetrize(S)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        cols: dict[str, NDArray[Any]] = dict(common_columns(state.x, state.P, 2))
        a = state.aux
        cols["outlier_range"] = a["outlier"][:, 0].astype(np.int64)
        cols["outlier_bearing"] = a["outlier"][:, 1].astype(np.int64)
        cols["adapting"] = a["adapting"].any(-1).astype(np.int64)
        return cols


class RangeBearingEKF(_Sonar):
    """``--method ekf-rb``: the baseline range/bearing CV EKF (``outlier_*`` diagnostic:
    normalised innovation > 6.63)."""

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt, dt = step_times(state, t)
        Phi, L0 = self._matrices(dt)
        x, P = kalman.predict(state.x, state.P, per_axis_to_flat(Phi), per_axis_to_flat(L0))
        return predicted(state, tt, x, P)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        hx, H = self._measurement(state, plots)
        z, ok = usable(plots.polar(False), hx)
        with np.errstate(all="ignore"):
            R = np.diag(self.r_nom)
            res, flags = plain_update(state.x, state.P, z, hx, H, R, check=False)
        aux = {"outlier": flags & ok[:, None]}
        return finish_update(state, res.x, res.P, res.nis, res.log_likelihood, state.t, aux, ok)


class Robust(_Sonar):
    """``--method robust-spec``: Ramazanov's algorithm R on the contract.

    ``aux``: the beam-frame channel blocks ``Pc (B, 2, k, k)`` (after :meth:`predict`: the
    predicted ones, in the frame of the last update ``psi``), the previous blocks
    ``Pc_prev`` (algorithm A injects ``Pc_prev / l_factor``), ``psi (B,)``, the J window
    ``jwin (B, 2, n)``, ``fresh`` (no update yet: blocks from the Cartesian covariance at
    the first update), ``P_prev`` and the flags ``outlier``, ``adapting`` of the last update.
    """

    Config: ClassVar[type] = RobustTrackConfig
    adaptive: ClassVar[bool] = False

    def _initial_aux(self, x: FloatArray, P: FloatArray) -> dict[str, Any]:
        B, k = x.shape[0], self.k
        blocks = np.zeros((B, 2, k, k))
        return {
            "Pc": blocks, "Pc_prev": blocks, "psi": np.zeros(B), "P_prev": P,
            "jwin": np.zeros((B, 2, self.config.window)), "fresh": np.ones(B, dtype=bool),
            "adapting": np.zeros((B, 2), dtype=bool),
        }  # fmt: skip

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt, dt = step_times(state, t)
        a = state.aux
        use_base = (not self.adaptive) or self.config.base_noise
        Phi, L0 = self._matrices(dt, use_base)
        x, Pcart = kalman.predict(state.x, state.P, per_axis_to_flat(Phi), per_axis_to_flat(L0))
        Pc = np.einsum("bij,bcjk,blk->bcil", Phi, a["Pc"], Phi) + L0[:, None]
        fresh = a["fresh"]
        P = Pcart
        if not fresh.all():  # tracks with beam blocks: their Cartesian covariance
            P = np.where(fresh[:, None, None], Pcart, beam_to_cartesian_cov(Pc, a["psi"]))
        aux = {"Pc": Pc, "Pc_prev": a["Pc"], "P_prev": state.P}
        return predicted(state, tt, x, kalman.symmetrize(P), aux)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        a, c, k = state.aux, self.config, self.k
        z = plots.polar(False)
        ok = np.asarray(np.isfinite(z).all(-1))
        Xp = _per_axis(state.x, k)
        with np.errstate(all="ignore"):
            psi, r_pred, innov = beam_innovations(Xp[..., 0], plots.sensor[:, :2], z[:, 0], z[:, 1])
            Pc, Pc_prev = a["Pc"], a["Pc_prev"]
            if c.rotate_covariance:
                turn = angle_diff(psi, a["psi"])
                Pc, Pc_prev = rotate_blocks(Pc, turn), rotate_blocks(Pc_prev, turn)
            P0 = Pc
            if a["fresh"].any():  # first update: blocks of the initiator's covariance
                fresh = a["fresh"][:, None, None, None]
                P0 = np.where(fresh, _beam_blocks(state.P, psi), Pc)
                Pc_prev = np.where(fresh, _beam_blocks(a["P_prev"], psi), Pc_prev)
            beam, info = robust_update(
                Xp, P0, Pc_prev, psi, r_pred, innov, a["jwin"], self.model, c, self.adaptive
            )
            S0 = info.P_pred[..., 0, 0] + info.q0
            nis = np.sum(info.innov**2 / S0, -1)
            ll = -0.5 * np.sum(info.innov**2 / S0 + np.log(S0) + _LOG_2PI, -1)
            P = beam_to_cartesian_cov(beam.Pc, psi)
        aux = {
            "Pc": beam.Pc, "psi": psi, "jwin": beam.jwin, "fresh": np.zeros_like(ok),
            "outlier": info.outlier, "adapting": info.adapting,
        }  # fmt: skip
        return finish_update(state, _flat(beam.X), P, nis, ll, state.t, aux, ok)


class RobustAdaptive(Robust):
    """``--method robust-adaptive-spec``: algorithm A (``adapting`` = 1 while noise is injected
    into either beam channel)."""

    adaptive: ClassVar[bool] = True
