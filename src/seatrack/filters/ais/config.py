"""Configuration of the AIS tracker (:class:`AisTrackerConfig`) and its chi-square helpers."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from seatrack.config import require
from seatrack.kalman import chi2_cdf
from seatrack.kalman import chi2_ppf

__all__ = ["AisTrackerConfig", "NX", "chi2_quantile", "trim_scale", "CHI2_1_MEDIAN"]

NX = 5  # [x, y, vx, vy, w]
#: median of chi-square with 1 dof (0.4549)
CHI2_1_MEDIAN = chi2_ppf(0.5, 1)


@lru_cache(maxsize=64)
def chi2_quantile(p: float, dof: int) -> float:
    """Chi-square quantile (cached)."""
    return chi2_ppf(p, dof)


@lru_cache(maxsize=64)
def trim_scale(keep: float) -> float:
    """``E[X | X <= chi2_1(keep)]`` for ``X ~ chi2_1``: ``F_3(chi2_1(keep)) / keep``."""
    return chi2_cdf(chi2_ppf(keep, 1), 3) / keep if keep < 1.0 else 1.0


@dataclass(frozen=True)
class AisTrackerConfig:
    """Configuration of the AIS tracker (SI inside; knots/degrees only where named so).

    Parameters
    ----------
    sigma_pos_m : float
        1-sigma AIS position error per axis, m [reading: GNSS noise plus the 1e-4 deg
        quantisation of some feeds]. The generous value behind the noise allowance of the
        plausibility tests (outliers); the filter's measurement noise is this value only
        with ``estimate_noise=False`` (else it is the upper bound of the estimate).
    q_accel : float
        White-noise acceleration PSD of the CT model, m^2/s^3.
    q_turn : float
        Turn-rate random-walk PSD, rad^2/s^3.
    gate_probability : float
        Chi-square (2 dof) gate probability.
    max_speed_kn : float
        Largest plausible speed over ground, knots [reading].
    max_accel_mps2 : float
        Largest plausible acceleration (incl. centripetal), m/s^2 [reading].
    n_sigma : float
        Noise allowance (in sigmas) in the plausibility tests.
    time_resolution_s : float
        Timestamp resolution; implied rates use ``dt + time_resolution_s``.
    max_gap_s : float
        Longer intervals split the track.
    reinit_after : int
        Consecutive outliers after which the track is re-initialised at the last one.
    smooth : bool
        Run the RTS smoother (else output the forward filter).
    revisit_passes : int
        Passes revisiting the causal decisions with the two-sided neighbour test
        (:func:`neighbour_plausibility`, neighbours = the reports accepted so far): an
        outlier (kinds 1, 3) that is plausible on both sides is accepted and an accepted
        report that is implausible is rejected (kind 1); each report's decision is revised
        at most once. Each pass re-runs the filter on the vessels concerned; 0 = causal
        decisions only. Of adjacent accepted reports rejected together, only the one with the
        largest implausibility score (implied speed / ``max_speed_kn``, implied acceleration
        / ``max_accel_mps2``) is rejected in a pass.
    init_speed_std_mps : float
        Prior velocity sigma per axis when SOG/COG are not both known.
    init_sogcog_std_mps : float
        Prior velocity sigma per axis when the velocity comes from SOG/COG.
    init_turn_std_dps : float
        Prior turn-rate sigma, deg/s.
    use_sog_cog : bool
        Also update with the reported SOG and COG (velocity measurements, see
        :func:`sogcog_model`) after an accepted position, when both are known; only when
        the reported and the predicted speed
        exceed ``min_speed_kn`` (COG is noise, and the speed Jacobian singular, near rest).
        A SOG/COG pair outside the chi-square gate is not used (the position still is).
    use_sog_alone : bool
        Also use SOG when COG is missing (a 1-D speed update). Off by default: on the
        Danish files without COG it made the hold-out error worse (their SOG lags the
        positions during speed changes) [reading].
    sigma_sog_kn, sigma_cog_deg : float
        1-sigma of the reported SOG (kn) and COG (deg) [reading: 0.1 kn / 0.1 deg
        resolution plus GNSS velocity noise and the lag of its smoothing].
    min_speed_kn : float
        Speed below which SOG/COG are not used, kn.
    estimate_noise : bool
        Estimate each vessel's position measurement noise from its own reports
        (:func:`position_noise`): ``R = sigma_pos^2 I + sigma_time^2 v v^T`` (white position
        noise plus a timestamp error along the velocity). False: ``R = sigma_pos_m^2 I``.
    sigma_pos_min_m : float
        Floor of the estimated position sigma, m [reading: the 1e-6 deg rounding of the
        files is ~0.03 m; 0.1 m keeps R well conditioned].
    sigma_time_min_s, noise_max_time_s : float
        Floor and cap of the estimated timestamp sigma, s [reading: the floor is the
        rounding of 1-s timestamps, 1/sqrt(12) s; chosen over 0 on the every-5th hold-out
        withholding the 2nd of each 5 reports, not the 5th that the tests withhold].
    noise_max_dt_s : float
        Only residuals with both neighbour intervals at most this long (s) enter the
        estimate (longer chords see the vessel's manoeuvres, not the noise).
    noise_min_reports : int
        Fewest residuals for an estimate (else ``sigma_pos_m`` and the timestamp floor).
    noise_trim : float
        Fraction of the smallest cross-track residuals kept for the position sigma.
    noise_min_speed_mps : float
        Chord speed (m/s) from which a residual informs the timestamp sigma.
    max_time_offset_s : int
        Largest whole-second timestamp error estimated per report
        (:func:`timestamp_offsets`, in the refinement pass); 0 = no offsets.
    sigma_time_fine_s : float
        Timestamp sigma (s) left once whole-second offsets are modelled: the scoring noise of
        :func:`timestamp_offsets` and the floor of the re-estimated sigma [reading: the
        interpolation residuals of the Danish files cluster within +-0.1 s of whole
        seconds; 0.15 rather than 0.07 or 0.1 on the hold-outs withholding the 1st to 4th of
        each five reports -- not the 5th that the tests withhold -- where it lost the 95th
        percentile to interpolation least often (2 of 20 file-folds against 7)].
    q_accel_steady : float
        Second, steadier acceleration PSD (m^2/s^3) of the refinement pass: each vessel
        keeps the track (``q_accel`` or this) whose reports have the larger prediction
        log-likelihood; 0 = ``q_accel`` only. [reading: ``q_accel`` 0.1 and this 0.003
        were chosen on the every-5th hold-out withholding the 2nd of each 5 reports (0.1
        and 0.2 both beat 0.05 there), not the 5th that the tests withhold.]
    offset_passes : int
        Re-estimations of the offsets from the steady track.
    refine : bool
        Run the refinement pass (:func:`seatrack.filters.ais.refine.refine_pass`:
        timestamp offsets, noise without the outliers, steady or manoeuvring process
        noise per vessel); False is 1.35-1.8 times faster (benchmarks/ais.py, 1 M
        synthetic reports, two runs).
    steady_nis_ratio : float
        The ``q_accel`` track is tried only for vessels whose mean NIS on the steady track
        exceeds this ratio times its 2 dof [reading: on the real files every vessel whose
        ``q_accel`` track had the larger likelihood had a steady mean NIS of 3.4 or more].
    min_offset_share : float
        Smallest estimated share of reports with a non-zero offset for offsets to be used
        at all (below it, the winners are noise: :func:`timestamp_offsets`).
    max_turn_rate_dps : float
        Largest turn-rate magnitude of the state, deg/s (also at most ``max_accel_mps2 /
        speed``); the state is projected onto it, and the speed onto ``max_speed_kn``,
        after every update [reading: the largest AIS rate of turn, 708 deg/min].
    """

    sigma_pos_m: float = 5.0
    q_accel: float = 0.1
    q_turn: float = 2e-6
    gate_probability: float = 0.9999
    max_speed_kn: float = 50.0
    max_accel_mps2: float = 2.0
    n_sigma: float = 3.0
    time_resolution_s: float = 1.0
    max_gap_s: float = 600.0
    reinit_after: int = 3
    smooth: bool = True
    revisit_passes: int = 4
    init_speed_std_mps: float = 8.0
    init_sogcog_std_mps: float = 1.0
    init_turn_std_dps: float = 1.0
    use_sog_cog: bool = True
    use_sog_alone: bool = False
    sigma_sog_kn: float = 0.3
    sigma_cog_deg: float = 3.0
    min_speed_kn: float = 2.0
    estimate_noise: bool = True
    sigma_pos_min_m: float = 0.1
    noise_max_dt_s: float = 60.0
    noise_min_reports: int = 10
    noise_trim: float = 0.9
    noise_min_speed_mps: float = 1.0
    noise_max_time_s: float = 5.0
    sigma_time_min_s: float = 0.2887
    max_time_offset_s: int = 2
    sigma_time_fine_s: float = 0.15
    q_accel_steady: float = 0.003
    offset_passes: int = 1
    refine: bool = True
    steady_nis_ratio: float = 1.5
    min_offset_share: float = 0.05
    max_turn_rate_dps: float = 12.0

    def __post_init__(self) -> None:
        own = "AisTrackerConfig."
        positive = ("sigma_pos_m", "q_accel", "q_turn", "max_speed_kn", "max_accel_mps2")
        require(self, positive, lambda v: v > 0, "> 0", prefix=own)
        require(self, ("gate_probability",), lambda p: 0.0 < p < 1.0, "in (0, 1)")
        require(self, ("reinit_after",), lambda n: n >= 1, ">= 1")
        if not 0.0 < self.sigma_pos_min_m <= self.sigma_pos_m:
            raise ValueError(
                f"need 0 < sigma_pos_min_m <= sigma_pos_m, got {self.sigma_pos_min_m}, "
                f"{self.sigma_pos_m}"
            )
        if not 0.0 <= self.sigma_time_min_s <= self.noise_max_time_s:
            raise ValueError(
                f"need 0 <= sigma_time_min_s <= noise_max_time_s, got {self.sigma_time_min_s}, "
                f"{self.noise_max_time_s}"
            )
        require(self, ("noise_trim",), lambda p: 0.0 < p <= 1.0, "in (0, 1]")
        require(
            self,
            ("sigma_time_fine_s", "steady_nis_ratio", "max_turn_rate_dps"),
            lambda v: v > 0,
            "> 0",
            prefix=own,
        )
        non_negative = ("max_time_offset_s", "offset_passes", "q_accel_steady")
        require(self, non_negative, lambda v: v >= 0, ">= 0", prefix=own)
        require(self, ("min_offset_share",), lambda p: 0.0 <= p < 1.0, "in [0, 1)")

    @property
    def gate(self) -> float:
        """Chi-square (2 dof) threshold of the gate."""
        return chi2_quantile(self.gate_probability, 2)
