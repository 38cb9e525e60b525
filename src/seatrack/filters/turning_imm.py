"""``seatrack track --method turning``: the turning-target filter as a level IMM.

The patent's filter (CN 104407337, ``docs/turning.md``; ``--method turning-spec``) raises
the process noise of a constant-velocity EKF only on the scans where a fuzzy vote on the
heading filter's turn rate sees the turn rate *change*: in a steady turn the noise returns
to nominal and the filter lags. Measured on scenarios no method was tuned on
(``benchmarks/defaults.py``), even a perfect noise schedule (the true centripetal
acceleration each scan) gains at most 20 % over the best fixed noise; what pays is to keep
one state per manoeuvre mode. The default is therefore the turn decision made as a
**mode probability**: a :class:`~seatrack.filters.levels.LevelIMM` with a steady and a
manoeuvre level from the target class (the self-tuning ladder without one), while the
patent's heading / turn-rate filter and fuzzy vote still run on the combined estimate for
the output columns (``turn_rate_dps``, ``turn_state``). Departures from the patent, with
the evidence, are in ``docs/turning.md``.

Columns: the level IMM's (``p_manoeuvre``, ``q_m2ps3``) and the patent's S6 output
(``speed_mps``, ``heading_deg``, ``turn_rate_dps``, ``turn_rate_std_dps``, ``turn_state``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import replace
from typing import Any
from typing import ClassVar

from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.config import param
from seatrack.filters.base import TrackState
from seatrack.filters.levels import LevelConfig
from seatrack.filters.levels import LevelIMM
from seatrack.filters.levels import OutlierConfig
from seatrack.filters.turning import Turning
from seatrack.filters.turning import TurningConfig
from seatrack.filters.turning import heading_columns
from seatrack.filters.turning import sigma_omega0_param
from seatrack.models.targets import TargetClass

__all__ = ["TurningLevelsConfig", "TurningLevels"]


@dataclass(frozen=True)
class TurningLevelsConfig(OutlierConfig, LevelConfig):
    """Parameters of ``--method turning``: the levels (:class:`LevelConfig`), a 1 %
    outlier prior (:class:`OutlierConfig`) and the heading filter / fuzzy vote of the
    output columns (spec S2-S4)."""

    use_range_rate: bool = param(True, doc="use the plots' range rate when they have one")
    q_heading: float = param(
        1e-4, unit="rad^2/s^3", doc="heading-filter PSD (spec 1e-6 reacts after the turn)",
        min=0, exclusive_min=True,
    )  # fmt: skip
    sigma_omega0: float = sigma_omega0_param("initial turn-rate std of the heading filter")
    turn_rate_threshold: float = param(1.0, doc="S3 threshold on d_omega", min=0)
    queue_length: int = param(5, doc="S3/S4 queue length M (> 3)", max=1000)
    delta_omega_threshold: float = param(
        math.degrees(0.02), key="delta_omega_threshold_dps", unit="deg/s",
        doc="S4 threshold on delta omega", min=0,
    )  # fmt: skip

    def __post_init__(self) -> None:
        super().__post_init__()
        self.heading_config()  # validates the heading-filter fields

    def heading_config(self) -> TurningConfig:
        """The spec filter's configuration of the heading filter and vote."""
        return TurningConfig(
            q_heading=self.q_heading,
            sigma_omega0=self.sigma_omega0,
            turn_rate_threshold=self.turn_rate_threshold,
            queue_length=self.queue_length,
            delta_omega_threshold=self.delta_omega_threshold,
        )

    @classmethod
    def for_target(cls, target: TargetClass) -> TurningLevelsConfig:
        """The levels of the class and its maximum turn rate as the initial turn-rate std."""
        base = LevelConfig.for_target(target)
        return replace(
            cls(),
            accel_levels=base.accel_levels,
            sojourn_times=base.sojourn_times,
            initial_speed_sigma=base.initial_speed_sigma,
            sigma_omega0=target.turn_rate_max,
        )


class TurningLevels(LevelIMM):
    """The default turning filter: a level IMM plus the patent's heading filter and fuzzy
    vote on its combined estimate (``aux`` of both)."""

    Config: ClassVar[type] = TurningLevelsConfig

    def _rule_setup(self) -> None:
        self.heading = Turning(self.config.heading_config(), self.sensor, self.d)

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        st = super().initiate(t, x, P)
        st = st.replace(aux=self.heading.heading_aux(len(st)))
        return st.replace(aux=self.heading.heading_logic(st))

    def _after_update(self, updated: TrackState) -> dict[str, Any]:
        return self.heading.heading_logic(updated)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        return super().columns(state) | heading_columns(state, self.d)
