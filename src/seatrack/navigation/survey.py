"""Map survey: landmark corrections from recorded passages (spec "Map preparation").

While sailing the route the navigator records, for every landmark measurement it uses,
the correction the landmark needs along the measurement direction (measured minus
predicted offset: range along the line of sight and cross-range across it for point
reflectors, the normal offset for contour elements; see
:class:`seatrack.navigation.navigator.SurveyRecords`). The survey combines them per landmark
by weighted least squares:

``delta = argmin sum_k (z_k - d_k . delta)^2 / var_k``

a 2-D correction for a point reflector (solved only in the directions the passages
observed: directions with too little information are left uncorrected) and a correction
along the normal for a contour element (its position along the line is not observable and
does not matter). Landmarks served but rarely giving an update (``visibility`` below a
threshold) or never served are flagged as poorly visible. As in the patent, the corrected
map is reloaded and the route sailed again until it is accurate: the corrections are
measured against an own-ship estimate that the erroneous landmarks themselves pulled, so
each pass removes only part of the error. [reading] Without an independent position
reference (GNSS during the survey) a correction common to all landmarks (a translation or
rotation of the whole map) is not observable from the radar alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.navigation.landmarks import LandmarkMap
from seatrack.navigation.navigator import NavResult

FloatArray = NDArray[np.float64]

__all__ = ["SurveyConfig", "SurveyResult", "survey"]


@dataclass(frozen=True)
class SurveyConfig:
    """Survey settings.

    Attributes
    ----------
    min_visibility : flag a landmark whose fraction of passes giving an update is below.
    min_records : fewer scalar measurements than this: no correction.
    skip_s : s, ignore records from the first ``skip_s`` seconds of each passage
        (filter convergence).
    min_information : 1/m^2, smallest eigenvalue of a point's information matrix for a
        direction to be corrected.
    drop_poor : remove poorly visible landmarks from the corrected map.
    """

    min_visibility: float = 0.5
    min_records: int = 5
    skip_s: float = 60.0
    min_information: float = 1e-3
    drop_poor: bool = False


@dataclass(frozen=True)
class SurveyResult:
    """Survey output.

    Attributes
    ----------
    corrected : LandmarkMap (poorly visible ones removed if ``drop_poor``)
    correction : (N, 2) m, correction applied to each landmark of the input map
    n_records : (N,) scalar measurements used
    visibility : (N,) hits / attempts over all passages (NaN if never served)
    poorly_visible : (N,) bool
    """

    corrected: LandmarkMap
    correction: FloatArray
    n_records: NDArray[np.int64]
    visibility: FloatArray
    poorly_visible: NDArray[np.bool_]


def survey(
    landmarks: LandmarkMap, passages: Sequence[NavResult], config: SurveyConfig | None = None
) -> SurveyResult:
    """Estimate landmark corrections from navigator runs over the same map (see module doc)."""
    cfg = config or SurveyConfig()
    N = len(landmarks)
    A = np.zeros((N, 2, 2))
    b = np.zeros((N, 2))
    n_rec = np.zeros(N, np.int64)
    attempts = np.zeros(N, np.int64)
    hits = np.zeros(N, np.int64)
    for res in passages:
        attempts += res.attempts
        hits += res.hits
        rec = res.records
        if rec.t.size == 0:
            continue
        use = rec.t >= res.t[0] + cfg.skip_s if res.t.size else np.ones(rec.t.size, bool)
        lm, d, z, v = rec.landmark[use], rec.direction[use], rec.z[use], rec.var[use]
        np.add.at(A, lm, d[:, :, None] * d[:, None, :] / v[:, None, None])
        np.add.at(b, lm, d * (z / v)[:, None])
        n_rec += np.bincount(lm, minlength=N)
    corr = np.zeros((N, 2))
    for j in range(N):
        if n_rec[j] < cfg.min_records:
            continue
        if landmarks.is_contour[j]:
            n = np.array([np.sin(landmarks.normal[j]), np.cos(landmarks.normal[j])])
            info = n @ A[j] @ n
            if info > cfg.min_information:
                corr[j] = n * (n @ b[j]) / info
            continue
        w, V = np.linalg.eigh(A[j])
        good = w > cfg.min_information
        corr[j] = V[:, good] @ ((V[:, good].T @ b[j]) / w[good])
    with np.errstate(invalid="ignore", divide="ignore"):
        vis = np.where(attempts > 0, hits / np.maximum(attempts, 1), np.nan)
    poor = ~(vis >= cfg.min_visibility)
    new = landmarks.with_xy(landmarks.xy + corr)
    if cfg.drop_poor:
        new = new.subset(~poor)
    return SurveyResult(new, corr, n_rec, vis, poor)
