"""Evaluation: error metrics, NEES/NIS consistency, Cramér–Rao bounds, Monte-Carlo runner."""

from seatrack.evaluate.bounds import fisher_crb
from seatrack.evaluate.bounds import fisher_information
from seatrack.evaluate.bounds import pcrb
from seatrack.evaluate.bounds import pcrb_linear
from seatrack.evaluate.metrics import anees
from seatrack.evaluate.metrics import anis
from seatrack.evaluate.metrics import chi2_interval
from seatrack.evaluate.metrics import error_norm
from seatrack.evaluate.metrics import fraction_inside
from seatrack.evaluate.metrics import nees
from seatrack.evaluate.metrics import nis
from seatrack.evaluate.metrics import peak_error
from seatrack.evaluate.metrics import position_error
from seatrack.evaluate.metrics import rms_over_time
from seatrack.evaluate.metrics import rmse
from seatrack.evaluate.metrics import velocity_error
from seatrack.evaluate.montecarlo import Column
from seatrack.evaluate.montecarlo import MonteCarloResult
from seatrack.evaluate.montecarlo import format_table
from seatrack.evaluate.montecarlo import monte_carlo
from seatrack.evaluate.montecarlo import rich_table
from seatrack.evaluate.montecarlo import run_seeds

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
