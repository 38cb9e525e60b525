"""Robust coordinated-turn tracker for AIS position reports of many vessels at once.

Per vessel, a coordinated-turn extended Kalman filter (state ``[x, y, vx, vy, w]``, x East,
y North in the vessel's local tangent plane, turn rate ``w`` clockwise positive,
:mod:`seatrack.models.motion`) runs over the vessel's reports in time order, followed by a
Rauch-Tung-Striebel (RTS) smoother over each track segment (Bar-Shalom, Li & Kirubarajan
2001: 5.4.2 gating, 8.6 smoothing, 11.7 CT model). Measurements: the position, then (when
both are reported) SOG and COG as a velocity measurement ``[|v|, atan2(vx, vy)]``
(:func:`sogcog_model`, COG innovation wrapped to ``(-pi, pi]``, own chi-square gate).

Measurement noise. The report covariance is estimated per vessel from the vessel's own
reports (:func:`position_noise`): ``R = sigma_pos^2 I + sigma_time^2 v v^T``, white position
noise plus the error of the logged time, which displaces a moving vessel's report along its
velocity ``v`` (the predicted one). On the real files the measured cross-track noise is
0.1-1 m, while the along-track error grows with speed (timestamp sigma ~0.5 s), so a fixed
isotropic sigma of several metres over-smooths slow and manoeuvring vessels.

Timestamp offsets. That along-track error is mostly not white: the logged time of a report
is off by whole seconds (interpolation residuals of the Danish files cluster at 0, +-0.5 and
+-1 s; ~20 % of the reports are one second off, ~2 % two) while the positions themselves are
precise. A refinement pass (:func:`~seatrack.filters.ais.refine.refine_pass`, ``refine``)
estimates each report's offset ``d`` from the smoothed track (:func:`timestamp_offsets`, MAP
with a prior estimated from the file) and filters again with the offset in the measurement
model, ``h(x) = [x - vx d, y - vy d]`` (the report shows the position ``d`` seconds before
its logged time; linear, the state stays at the logged time), and the timestamp sigma
re-estimated on the corrected times. The same pass re-estimates the report noise without the
outliers and chooses per vessel between ``q_accel`` and a steadier ``q_accel_steady`` by the
prediction log-likelihood of the vessel's reports (steady ships gain from the stiffer model,
manoeuvring craft need the other).

Physical limits. After every update, and on the smoothed output, the state is projected
onto ``speed <= max_speed_kn`` and ``|w| <= min(max_turn_rate_dps, max_accel_mps2 /
speed)`` (:func:`~seatrack.filters.ais.ct.constrain`): without it a CT filter fed plausible
reports can lock onto a spurious fast spin.

Outliers. Three kinds (:data:`OUTLIER_KINDS`), each a report that is not used (the filter
predicts through it) and is flagged:

1. **implausible jump**: outside the chi-square gate (``NIS = y^T S^-1 y`` against the
   ``gate_probability`` quantile of chi-square with 2 dof) *and* physically implausible:
   the speed implied by the straight line from the last accepted report exceeds
   ``max_speed_kn``, or the acceleration implied by its distance from the prediction,
   ``2 (|y| - n_sigma sqrt(lambda_max(S))) / dt^2``, exceeds ``max_accel_mps2``.
   Intervals are lengthened by ``time_resolution_s`` (one-second timestamps can hide up
   to one second) and distances shortened by the noise allowance
   ``n_sigma sqrt(2) sigma_pos`` [reading], so only reports implausible under the most
   generous reading are flagged;
2. **stale position**: the exact position of the previous report repeated while the vessel
   moves (the reported SOG; without one, the vessel's last SOG within ``max_gap_s``; else
   the filter speed less ``n_sigma`` of its sigma: a glitch the filter followed must not
   make a vessel at rest look moving) far enough since
   the position was first reported to exceed the noise allowance -- the "frozen position"
   glitch of AIS feeds, whose catch-up report otherwise looks like a jump;
3. **implausible after gap**: after a gap longer than ``max_gap_s``, a report implying more
   than ``max_speed_kn`` from the last accepted one (e.g. two transmitters sharing an
   MMSI); it has no track estimate.

A report outside the gate that is plausible is a manoeuvre: the predicted covariance is
inflated by ``NIS / gate`` before the update (so the report sits on the gate), which lets
the track follow sharp turns and speed changes without a second model [reading]. The causal
decisions are then revisited with the future (``revisit_passes``): an outlier that is
plausible against its accepted neighbours on both sides is accepted, an accepted report
that is implausible against them is rejected (:func:`neighbour_plausibility`), and the
vessels concerned are filtered again.

Tracks are split (re-initialised) at intervals longer than ``max_gap_s`` and after
``reinit_after`` consecutive outliers (the track was lost, e.g. after a wrong first
report). A segment is initialised from one report: its position, and the velocity from
SOG/COG when both are given (else zero with a wide prior).

Scale: all vessels go through one compiled (Numba, ``nogil``) loop over reports sorted by
vessel and time; there is no Python work per report. The measurement updates are the
Joseph-form core of :mod:`seatrack.kalman` and the covariance prediction its compiled
``F P F^T + Q`` core; the CT propagation ``f(x)``, its Jacobian and ``Q`` are compiled
copies of :func:`seatrack.models.motion.ct_transition`,
:func:`~seatrack.models.motion.ct_jacobian` and :func:`~seatrack.models.motion.ct_noise`
(tested equal to them), and the RTS step is written out for 5x5 matrices (no BLAS calls).
Vessels are independent and run on all cores (``numba.prange`` over chunks of vessels); the
result does not depend on the number of threads.

Modules: :mod:`~seatrack.filters.ais.config` (configuration), :mod:`~.ct` (compiled CT model,
2-D update, limits), :mod:`~.smoother` (RTS), :mod:`~.kernel` (the compiled filter over all
vessels, its named-tuple inputs and outputs, :class:`OutlierKind`, :class:`Force`),
:mod:`~.plausibility` (two-sided test, revisit passes), :mod:`~.noise` (report noise),
:mod:`~.offsets` (timestamp offsets), :mod:`~.refine` (refinement pass), :mod:`~.tracker`
(:func:`track_vessels`), :mod:`~.tracks` (:func:`track_reports`, WGS84 output).
"""

from __future__ import annotations

from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.ct import ct_step
from seatrack.filters.ais.ct import sogcog_model
from seatrack.filters.ais.kernel import OUTLIER_KINDS
from seatrack.filters.ais.kernel import Force
from seatrack.filters.ais.kernel import KernelOutputs
from seatrack.filters.ais.kernel import OutlierKind
from seatrack.filters.ais.noise import position_noise
from seatrack.filters.ais.offsets import OffsetInputs
from seatrack.filters.ais.offsets import timestamp_offsets
from seatrack.filters.ais.plausibility import neighbour_plausibility
from seatrack.filters.ais.tracker import TrackStates
from seatrack.filters.ais.tracker import track_vessels
from seatrack.filters.ais.tracks import AisTracks
from seatrack.filters.ais.tracks import track_reports

__all__ = [
    "AisTrackerConfig",
    "AisTracks",
    "Force",
    "KernelOutputs",
    "OUTLIER_KINDS",
    "OutlierKind",
    "TrackStates",
    "ct_step",
    "neighbour_plausibility",
    "position_noise",
    "sogcog_model",
    "timestamp_offsets",
    "OffsetInputs",
    "track_reports",
    "track_vessels",
]
