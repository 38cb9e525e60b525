"""Evaluation: error metrics, NEES/NIS consistency, Cramér–Rao bounds, Monte-Carlo runner."""

from seatrack.evaluate.bounds import fisher_crb, fisher_information, pcrb, pcrb_linear
from seatrack.evaluate.metrics import (
    anees,
    anis,
    chi2_interval,
    error_norm,
    fraction_inside,
    nees,
    nis,
    peak_error,
    position_error,
    rms_over_time,
    rmse,
    velocity_error,
)
from seatrack.evaluate.montecarlo import (
    Column,
    MonteCarloResult,
    format_table,
    monte_carlo,
    rich_table,
    run_seeds,
)

__all__ = [
    "Column",
    "MonteCarloResult",
    "anees",
    "anis",
    "chi2_interval",
    "error_norm",
    "fisher_crb",
    "fisher_information",
    "format_table",
    "fraction_inside",
    "monte_carlo",
    "nees",
    "nis",
    "pcrb",
    "pcrb_linear",
    "peak_error",
    "position_error",
    "rich_table",
    "rms_over_time",
    "rmse",
    "run_seeds",
    "velocity_error",
]
