"""The reference IMM methods on the filter contract: ``--method imm`` (CV + coordinated turn
on converted plots) and ``--method mm-rangerate`` (CV, coordinated turn and an agile CV with
the range rate in the update).

Both run the motion-model bank of :class:`seatrack.filters.imm.IMM` over all tracks of a
file at once. Measurements are the converted plot positions (linear update), or, with
``use_range_rate``, the positions stacked with the range rate (extended update, the
range-rate model of :mod:`seatrack.models.measurement`). Units: SI and radians inside;
the configuration keys name their units (``docs/multimodel.md``, ``docs/defaults.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import replace
from typing import Any
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.config import Checked
from seatrack.config import param
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import accel_sigma_param
from seatrack.filters.base import common_columns
from seatrack.filters.base import conversion_param
from seatrack.filters.base import converted_positions
from seatrack.filters.base import finish_update
from seatrack.filters.base import predicted
from seatrack.filters.base import speed_sigma_param
from seatrack.filters.base import step_times
from seatrack.filters.imm import IMM
from seatrack.filters.imm import IMMState
from seatrack.filters.imm import uniform_transition
from seatrack.models.measurement import Position
from seatrack.models.measurement import RangeRate
from seatrack.models.measurement import Stacked
from seatrack.models.targets import TargetClass

FloatArray = NDArray[np.float64]

__all__ = ["CVCTIMM", "CVCTIMMConfig", "RangeRateIMM", "RangeRateIMMConfig"]


# ---------------------------------------------------------------------------
# The filter contract
# ---------------------------------------------------------------------------
def _common_dt(dt: FloatArray) -> Any:
    """A scalar interval when every track of the batch has the same one (cached, fused
    matrices), else the per-track array."""
    return float(dt[0]) if dt.size and np.all(dt == dt[0]) else dt


@dataclass(frozen=True)
class CVCTIMMConfig(Checked):
    """Parameters of ``--method imm``: CV + coordinated turn on converted plots (the noise
    defaults were chosen on the tuning seeds of ``benchmarks/multimodel.py``, 2 s scans)."""

    q_cv: float = param(0.01, unit="m^2/s^3", doc="CV white-noise acceleration PSD", min=0)
    q_ct: float = param(100.0, unit="m^2/s^3", doc="CT white-noise acceleration PSD", min=0)
    q_omega: float = param(1e-3, unit="rad^2/s^3", doc="CT turn-rate PSD", min=0)
    p_stay: float = param(0.95, doc="IMM transition diagonal", min=0, max=1)
    conversion: str = conversion_param()
    initial_speed_sigma: float = speed_sigma_param(300.0, aliases=("initial_velocity_std_mps",))
    initial_turn_rate_sigma: float = param(
        5.0,
        key="initial_turn_rate_std_dps",
        unit="deg/s",
        doc="turn-rate std of a new track",
        min=1e-6,
        max=1e4,
    )
    use_range_rate: bool = param(False, doc="stack the range rate with the converted position")
    sigma_accel_cv: float = accel_sigma_param("sigma_accel_cv_mps2", "q_cv")
    sigma_accel_ct: float = accel_sigma_param("sigma_accel_ct_mps2", "q_ct")
    q_agile: float = param(
        0.0, unit="m^2/s^3", min=0,
        doc="a third model, an agile CV with this PSD, when > 0 (or sigma_accel_agile > 0): "
        "manoeuvres no constant turn rate fits (weaving, jinking)",
    )  # fmt: skip
    sigma_accel_agile: float = accel_sigma_param("sigma_accel_agile_mps2", "q_agile")

    @property
    def agile(self) -> bool:
        """Whether the IMM has the third, agile CV model."""
        return self.q_agile > 0 or self.sigma_accel_agile > 0

    @classmethod
    def for_target(cls, target: TargetClass) -> Any:
        """A target class's noise: the CV model at the straight-leg acceleration, the CT
        model at the tangential acceleration plus the mismatch of a constant turn rate over
        a scan (half the typical manoeuvre acceleration), the turn rate wandering by its
        typical value over a manoeuvre time; the class's maximum speed and turn rate as
        the initial stds."""
        return cls(
            q_cv=0.0,
            q_ct=0.0,
            sigma_accel_cv=target.accel_steady,
            sigma_accel_ct=math.hypot(target.accel_tangential, 0.5 * target.accel_typical),
            q_omega=target.q_turn_rate,
            initial_speed_sigma=target.speed_max,
            initial_turn_rate_sigma=target.turn_rate_max,
        )


class CVCTIMM:
    """The reference IMM (CV + coordinated turn) on the filter contract (``--method imm``).

    Measurements are the converted plot positions (linear update), or, with
    ``use_range_rate``, positions stacked with the range rate (extended update).
    ``TrackState.x``/``P`` hold the combined estimate on ``x, y, [z], vx, vy, [vz]``;
    ``aux`` the padded model states ``X (B, M, n)``, ``PP (B, M, n, n)`` and the model
    probabilities ``mu (B, M)`` (after :meth:`predict`: the predicted ``c_j``).
    """

    Config = CVCTIMMConfig
    dims: ClassVar[tuple[int, ...]] = (2, 3)

    def __init__(
        self,
        config: CVCTIMMConfig | None = None,
        sensor: SensorNoise | None = None,
        d: int = 2,
        range_rate: bool = False,
    ) -> None:
        from seatrack.models.motion import ConstantVelocity
        from seatrack.models.motion import CoordinatedTurn

        self.config = c = config or CVCTIMMConfig()
        self.sensor = sensor or SensorNoise()
        self.d = d
        self.range_rate = bool(range_rate and c.use_range_rate)
        models: list[Any] = [
            ConstantVelocity(q=c.q_cv, d=d, accel=c.sigma_accel_cv),
            CoordinatedTurn(q=c.q_ct, q_omega=c.q_omega, d=d, accel=c.sigma_accel_ct),
        ]
        if c.agile:
            models.append(ConstantVelocity(q=c.q_agile, d=d, accel=c.sigma_accel_agile))
        pos = tuple(range(d))
        meas: list[Any] = []
        for m in models:
            n = m.ndim_state
            p = Position(n=n, pos=pos)
            rr = RangeRate(n=n, pos=pos, vel=tuple(range(d, 2 * d)))
            meas.append(Stacked([p, rr]) if self.range_rate else p)
        self.imm = IMM(models, uniform_transition(len(models), c.p_stay), meas)
        self._w = self.imm.union_names.index("w")

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(self.imm.output_names)

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        sw = self.config.initial_turn_rate_sigma
        st = self.imm.initial_state(x, P, extra={"w": (0.0, sw**2)})
        return TrackState.new(t, x, P, {"X": st.X, "PP": st.P, "mu": st.mu})

    @staticmethod
    def _engine(state: TrackState) -> IMMState:
        a = state.aux
        return IMMState(a["X"], a["PP"], a["mu"])

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt, dt = step_times(state, t)
        pr = self.imm.predict(self._engine(state), _common_dt(dt))
        x, P = self.imm.combined(pr)
        return predicted(state, tt, x, P, {"X": pr.X, "PP": pr.P, "mu": pr.mu})

    def derive(self, plots: Plots) -> dict[str, FloatArray]:
        """The converted positions and covariances of all plots at once (they do not depend
        on the state): ``z``, ``R`` and the range-rate model's ``sensor`` of
        :meth:`_measurement`, which then only takes them."""
        z, R, sensor = self._measurement(plots)
        out = {"z": z, "R": R}
        return out if sensor is None else out | {"sensor": sensor}

    def _measurement(self, plots: Plots) -> tuple[FloatArray, FloatArray, Any]:
        """Converted positions (with range rate when used), their covariances, the sensor
        state of the range-rate model (None without range rate); from ``plots.derived``
        when :meth:`derive` filled it."""
        got = plots.derived
        if "z" in got:
            return got["z"], got["R"], got.get("sensor")
        sn, d = self.sensor, self.d
        z, R = converted_positions(plots, sn, self.config.conversion)
        if not self.range_rate or plots.range_rate is None:
            return z, R, None
        # Position.h subtracts the sensor position given with the range-rate sensor state
        zr = np.concatenate([z - plots.sensor[:, :d], plots.range_rate[:, None]], -1)
        Rr = np.zeros((len(plots), d + 1, d + 1))
        Rr[:, :d, :d] = R
        Rr[:, d, d] = sn.sigma_range_rate**2
        sensor = np.concatenate([plots.sensor[:, :d], plots.sensor_vel[:, :d]], -1)
        return zr, Rr, sensor

    def _innovation(
        self, state: TrackState, z: FloatArray, R: FloatArray, sensor: Any
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Predicted measurement of the combined state, innovation and its covariance."""
        m = self.imm.measurement[0]  # output components come first in every model
        with np.errstate(all="ignore"):
            hx = m.h(state.x, sensor)
            H = m.jacobian(state.x, sensor)
            S = H @ state.P @ np.swapaxes(H, -1, -2) + R
        return hx, z - hx, S

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        z, R, sensor = self._measurement(plots)
        _, y, S = self._innovation(state, z, R, sensor)
        return y, S

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        z, R, sensor = self._measurement(plots)
        hx, y, S = self._innovation(state, z, R, sensor)
        ok = np.asarray(
            np.isfinite(z).all(-1) & np.isfinite(R).all((-1, -2)) & np.isfinite(hx).all(-1),
            dtype=bool,
        )
        z = np.where(ok[:, None], z, np.where(np.isfinite(hx), hx, 0.0))
        R = np.where(ok[:, None, None], R, np.eye(R.shape[-1]))
        Rk = R[:, None] if self.imm.fused_H is not None and sensor is None else R
        with np.errstate(all="ignore"):
            res = self.imm.update(self._engine(state), z, Rk, sensor, check=False)
        nis = kalman.mahalanobis(y, S)
        aux = {"X": res.state.X, "PP": res.state.P, "mu": res.state.mu}
        return finish_update(state, res.x, res.P, nis, res.log_likelihood, state.t, aux, ok)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        cols = common_columns(state.x, state.P, self.d)
        cols["p_cv"] = state.aux["mu"][:, 0]
        cols["p_ct"] = state.aux["mu"][:, 1]
        if self.config.agile:
            cols["p_agile"] = state.aux["mu"][:, 2]
        cols["turn_rate_dps"] = np.degrees(state.aux["X"][:, 1, self._w])
        return cols


@dataclass(frozen=True)
class RangeRateIMMConfig(CVCTIMMConfig):
    """Parameters of ``--method mm-rangerate``: the IMM of CV, coordinated turn and an agile
    CV with the range rate in the update. ``q_ct = 1000`` was chosen on the tuning seeds of
    the fighter family (``benchmarks/defaults.py``; the IMM's own ``q_ct = 100`` makes range
    rate a loss there); the agile CV (``q_agile = 1500``), ``q_omega = 3e-3`` and
    ``p_stay = 0.98`` on the tuning seeds of the three range-rate families (fighter turns,
    weaving fighters, real ship tracks under a Doppler radar) and of
    ``benchmarks/multimodel.py`` (see ``docs/defaults.md``)."""

    q_ct: float = param(1000.0, unit="m^2/s^3", doc="CT white-noise acceleration PSD", min=0)
    q_omega: float = param(3e-3, unit="rad^2/s^3", doc="CT turn-rate PSD", min=0)
    p_stay: float = param(0.98, doc="IMM transition diagonal", min=0, max=1)
    use_range_rate: bool = param(True, doc="stack the range rate with the converted position")
    q_agile: float = param(
        1500.0, unit="m^2/s^3", min=0,
        doc="the third model, an agile CV with this PSD (0 and sigma_accel_agile 0: none)",
    )  # fmt: skip

    @classmethod
    def for_target(cls, target: TargetClass) -> Any:
        """The CV + CT IMM's class noise (:meth:`CVCTIMMConfig.for_target`) and an agile CV
        at the class's typical manoeuvre acceleration (``sigma_accel_agile = accel_typical``,
        ``q_agile = 0``)."""
        base = super().for_target(target)
        return replace(base, q_agile=0.0, sigma_accel_agile=target.accel_typical)


class RangeRateIMM(CVCTIMM):
    """``--method mm-rangerate``: the multiple-model filter with range rate where it helps,
    in the state update of an IMM (CV + coordinated turn) -- see ``docs/multimodel.md``."""

    Config = RangeRateIMMConfig
    needs_range_rate: ClassVar[bool] = True
