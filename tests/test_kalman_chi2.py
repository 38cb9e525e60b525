"""The chi-square helpers of seatrack.kalman equal scipy.stats.chi2 bit for bit (the AIS
tracker's gate and trim helpers and the tracker's gate threshold use them)."""

from __future__ import annotations

import math

from scipy.stats import chi2

from seatrack.filters.ais.config import CHI2_1_MEDIAN
from seatrack.filters.ais.config import chi2_quantile
from seatrack.filters.ais.config import trim_scale
from seatrack.kalman import chi2_cdf
from seatrack.kalman import chi2_ppf
from seatrack.tracking.gating import gate_threshold


def test_chi2_helpers_equal_scipy_stats():
    for p in (1e-9, 0.0, 0.3, 0.5, 0.9, 0.95, 0.99, 0.9973, 0.9999, 1.0):
        for dof in (1, 2, 3, 4, 5):
            assert chi2_ppf(p, dof) == chi2.ppf(p, dof) == chi2_quantile(p, dof)
            if 0 < p < 1:
                assert gate_threshold(p, dof) == chi2.ppf(p, dof)
    assert math.isnan(chi2_ppf(1.5, 2))
    for x in (-1.0, 0.0, 0.1, 1.0, 5.99, 30.0):
        for dof in (1, 2, 3):
            assert chi2_cdf(x, dof) == chi2.cdf(x, dof)
    for keep in (0.5, 0.8, 0.9, 0.95, 0.99):
        assert trim_scale(keep) == chi2.cdf(chi2.ppf(keep, 1), 3) / keep
    assert trim_scale(1.0) == 1.0
    assert CHI2_1_MEDIAN == chi2.ppf(0.5, 1)
