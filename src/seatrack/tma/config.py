"""Configuration of the TMA solver: one frozen dataclass, every numeric choice a field.

See ``docs/tma.md`` for what each field changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["TMAConfig"]


def _check(ok: bool, name: str, rule: str, value: object) -> None:
    if not ok:
        raise ValueError(f"TMAConfig.{name} must be {rule}, got {value!r}")


def _finite(x: object) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _count(x: object) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


@dataclass(frozen=True)
class TMAConfig:
    """Solver configuration (spec defaults; every [reading] choice is a field).

    Parameters
    ----------
    sigma : float
        Bearing standard deviation (rad) when the bearings carry none. Weights ``1/sigma^2``.
    max_iterations : int
        Iteration limit of the final refinement (accepted + rejected LM trials).
    position_tolerance : float
        Patent's convergence threshold on the position change at the last time, m.
    cost_tolerance : float
        Relative cost-change threshold (second convergence test).
    lm_lambda0, lm_increase, lm_decrease, lm_lambda_max : float
        Levenberg–Marquardt damping: start, factor after a rejected / accepted step, give-up
        limit. ``lm_converge_lambda`` is the largest damping at which the convergence tests
        may declare convergence (a tiny step forced by heavy damping is not convergence).
    support_residual : "linear" | "square"
        [reading] linear range/speed residuals (default) or the patent's squares.
    start_ranges : (min, max, count)
        Log-spaced range grid (m) for the two-range automatic start.
    start_iterations : int
        Most LM iterations applied to every start before the best is kept (a start that
        converges earlier stops earlier).
    start_max_bearings : int
        Bearings (evenly spaced, first and last included) used in the start search.
    start_pseudolinear : bool
        Add the pseudo-linear estimate as a start.
    min_observer_deviation : float
        Own-ship deviation (m) from a straight constant-velocity track that counts as an
        own-ship manoeuvre (smaller deviations are taken as navigation noise).
    rank_tolerance : float
        Relative tolerance on the singular values of the whitened Jacobian with columns
        scaled to unit norm (:mod:`seatrack.information`): at or below ``rank_tolerance``
        times the largest, the geometry is singular (not observable). Scale-invariant.
    max_relative_range_sigma : float
        Largest acceptable ``sigma_range / range`` at the last time. Near the unobservable
        limit (e.g. a straight own-ship track with navigation noise) the first-order
        covariance is not a meaningful description of a very non-Gaussian error, so such
        solutions are reported as not observable. ``inf`` disables the test.
    residual_test_probability : float
        A warning is given when the weighted cost exceeds this quantile of the chi-square
        distribution with ``N + M - n`` degrees of freedom (residuals too large for the
        stated sigmas: wrong sigma, outliers or a target manoeuvre not in the model).
    confidence : float
        Probability of the reported confidence values (two-sided) and ellipses.
    sound_speed : float
        Speed of sound (m/s) of the frequency (Doppler) model.
    """

    sigma: float = math.radians(1.0)
    max_iterations: int = 50
    position_tolerance: float = 0.5
    cost_tolerance: float = 1e-10
    lm_lambda0: float = 1e-3
    lm_increase: float = 10.0
    lm_decrease: float = 0.1
    lm_lambda_max: float = 1e12
    lm_converge_lambda: float = 1e-2
    support_residual: str = "linear"
    start_ranges: tuple[float, float, int] = (500.0, 60_000.0, 7)
    start_iterations: int = 6
    start_max_bearings: int = 24
    start_pseudolinear: bool = True
    min_observer_deviation: float = 10.0
    rank_tolerance: float = 1e-10
    max_relative_range_sigma: float = 0.5
    residual_test_probability: float = 0.999
    confidence: float = 0.95
    sound_speed: float = 1500.0

    def __post_init__(self) -> None:
        _check(self.support_residual in ("linear", "square"), "support_residual",
               "'linear' or 'square'", self.support_residual)  # fmt: skip
        for name in ("sigma", "position_tolerance", "lm_lambda0", "lm_converge_lambda"):
            v = getattr(self, name)
            _check(_finite(v) and v > 0, name, "a finite positive number", v)
        _check(self.sigma < math.pi, "sigma", "below pi rad", self.sigma)
        for name in ("cost_tolerance", "lm_decrease", "rank_tolerance",
                     "residual_test_probability", "confidence"):  # fmt: skip
            v = getattr(self, name)
            _check(_finite(v) and 0 < v < 1, name, "a number in (0, 1)", v)
        _check(_finite(self.lm_increase) and self.lm_increase > 1, "lm_increase",
               "a finite number > 1", self.lm_increase)  # fmt: skip
        _check(_finite(self.lm_lambda_max) and self.lm_lambda_max > self.lm_lambda0,
               "lm_lambda_max", "finite and > lm_lambda0", self.lm_lambda_max)  # fmt: skip
        _check(_count(self.max_iterations) and self.max_iterations >= 1, "max_iterations",
               "an integer >= 1", self.max_iterations)  # fmt: skip
        _check(_count(self.start_iterations) and self.start_iterations >= 0,
               "start_iterations", "an integer >= 0", self.start_iterations)  # fmt: skip
        _check(_count(self.start_max_bearings) and self.start_max_bearings >= 2,
               "start_max_bearings", "an integer >= 2", self.start_max_bearings)  # fmt: skip
        _check(_finite(self.min_observer_deviation) and self.min_observer_deviation >= 0,
               "min_observer_deviation", "a finite number >= 0 (m)",
               self.min_observer_deviation)  # fmt: skip
        c = self.sound_speed
        _check(_finite(c) and 100 < c < 10_000, "sound_speed", "in (100, 10000) m/s", c)
        r = self.max_relative_range_sigma
        rule = "a positive number (inf disables the test)"
        ok_r = isinstance(r, (int, float)) and not math.isnan(r) and r > 0
        _check(ok_r, "max_relative_range_sigma", rule, r)
        rng = self.start_ranges
        ok = (
            len(rng) == 3 and _finite(rng[0]) and _finite(rng[1]) and _count(rng[2])
            and 0 < rng[0] < rng[1] and rng[2] >= 1
        )  # fmt: skip
        _check(ok, "start_ranges", "(min > 0, max > min, integer count >= 1) in metres", rng)
