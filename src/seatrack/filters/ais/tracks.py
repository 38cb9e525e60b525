"""Public entry of the AIS tracker for report tables: :func:`track_reports` (local planes,
true-North courses, WGS84 output) and its result :class:`AisTracks`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.frames import north_convergence_rows
from seatrack.filters.ais.frames import plane_to_wgs84
from seatrack.filters.ais.frames import vessel_planes
from seatrack.filters.ais.kernel import vessel_starts
from seatrack.filters.ais.tracker import TrackStates
from seatrack.filters.ais.tracker import VesselInputs
from seatrack.filters.ais.tracker import track_vessel_groups
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import bearing
from seatrack.geometry import wrap_2pi

FloatArray = NDArray[np.float64]

__all__ = [
    "AisTracks",
    "PreparedReports",
    "ReportPlanes",
    "prepare_reports",
    "track_reports",
    "tracks_from_states",
]


@dataclass(frozen=True)
class AisTracks:
    """Tracker output, one entry per row of the :class:`~seatrack.io.ais.AisReports`.

    SI units and radians (degrees/knots only when written out). Rows without an estimate
    (rejected rows, or withheld rows before a track starts) hold NaN.

    Attributes
    ----------
    x_m, y_m : local East, North (m) in the vessel's plane (origin ``lat0``, ``lon0``).
    lat, lon : smoothed WGS84 position (deg).
    course : course over ground (rad, clockwise from true North at the vessel, [0, 2pi)).
    speed : speed over ground (m/s).
    turn_rate : rad/s, clockwise (starboard) positive.
    std_x_m, std_y_m : 1-sigma East / North (m); ``std_pos_m`` = sqrt((var_x + var_y)/2).
    std_course, std_speed, std_turn_rate : 1-sigma (rad, m/s, rad/s).
    outlier : bool; outlier_kind : int (see :data:`OUTLIER_KINDS`); segment : int;
    nis : float.
    time_offset_s : estimated timestamp error of the report (s, whole seconds, logged minus
    true time; :func:`timestamp_offsets`), NaN for rows without an estimate.
    """

    x_m: FloatArray
    y_m: FloatArray
    lat: FloatArray
    lon: FloatArray
    lat0: FloatArray
    lon0: FloatArray
    course: FloatArray
    speed: FloatArray
    turn_rate: FloatArray
    std_x_m: FloatArray
    std_y_m: FloatArray
    std_pos_m: FloatArray
    std_course: FloatArray
    std_speed: FloatArray
    std_turn_rate: FloatArray
    outlier: NDArray[np.bool_]
    outlier_kind: NDArray[np.int8]
    segment: NDArray[np.int64]
    nis: FloatArray
    time_offset_s: FloatArray


def track_reports(
    reports: Any,
    config: AisTrackerConfig | None = None,
    use: ArrayLike | None = None,
) -> AisTracks:
    """Track every vessel of :class:`~seatrack.io.ais.AisReports` (rejected rows skipped).

    Positions go to one local plane per vessel (the planes of
    :func:`seatrack.geometry.local_frames`, :mod:`~seatrack.filters.ais.frames`);
    the compiled tracker runs over all vessels at once (:func:`track_vessels`); positions
    come back to WGS84 (:func:`seatrack.geometry.local_to_geodetic`) and the course is
    referred to true North at the vessel (the plane's North differs by the meridian convergence).

    Parameters
    ----------
    reports : AisReports
        Or any object with ``valid`` (bool), ``mmsi``, ``t`` (s), ``lat``, ``lon`` (deg),
        ``sog_kn`` and ``cog_deg`` arrays of one length.
    config : AisTrackerConfig
    use : array of bool (N,), optional
        False withholds a row from the filter (it still gets the track estimate at its
        time) -- for hold-out tests.
    """
    prep = prepare_reports(reports, use)
    st = track_vessel_groups([prep.inputs], config or AisTrackerConfig())[0]
    return tracks_from_states(prep.planes, st)


@dataclass(frozen=True)
class ReportPlanes:
    """Where the tracker's rows sit in a report table of ``n`` rows: ``idx`` the table row
    of each (the usable rows, sorted by (vessel, time)) and the origin ``lat0``, ``lon0``
    (deg) of its vessel's plane (the vessel's first usable row in table order)."""

    n: int
    idx: NDArray[np.int64]
    lat0: FloatArray
    lon0: FloatArray


@dataclass(frozen=True)
class PreparedReports:
    """Tracker inputs of a report table: :class:`ReportPlanes` and the
    :class:`~seatrack.filters.ais.tracker.VesselInputs` of its usable rows in the planes
    (SOG/COG too), in the order of ``planes.idx``."""

    planes: ReportPlanes
    inputs: VesselInputs


def prepare_reports(reports: Any, use: ArrayLike | None = None) -> PreparedReports:
    """Local planes per vessel and the tracker inputs of the usable rows of ``reports``
    (the planes of :func:`seatrack.geometry.local_frames`, computed by
    :func:`~seatrack.filters.ais.frames.vessel_planes`)."""
    ok = np.flatnonzero(reports.valid)
    idx = ok[np.lexsort((reports.t[ok], reports.mmsi[ok]))]
    mmsi = reports.mmsi[idx]
    en, lat0, lon0, gam0 = vessel_planes(reports.lat, reports.lon, idx, vessel_starts(mmsi))
    sog = reports.sog_kn[idx] * KNOT_MPS
    cog = np.radians(reports.cog_deg[idx])
    u = None if use is None else np.asarray(use, dtype=bool)[idx]
    # COG is referred to true North at the vessel; the plane's North differs by the
    # meridian convergence, so rotate it into the plane (also for the initial velocity)
    cog_plane = cog + gam0
    v0 = np.empty((idx.size, 2))
    v0[:, 0] = sog * np.sin(cog_plane)
    v0[:, 1] = sog * np.cos(cog_plane)
    inputs = VesselInputs(mmsi, reports.t[idx], en, u, v0, sog, cog_plane)
    return PreparedReports(ReportPlanes(len(reports), idx, lat0, lon0), inputs)


def tracks_from_states(prep: ReportPlanes, st: TrackStates) -> AisTracks:
    """:class:`AisTracks` of all rows from the states of the usable ones (in the order of
    ``prep.idx``): WGS84 positions and courses referred to true North at the vessel."""
    n, idx = prep.n, prep.idx

    def full(a: NDArray, fill: Any = np.nan, dtype: Any = float) -> NDArray:
        out = np.full((n,) + a.shape[1:], fill, dtype=dtype)
        out[idx] = a
        return out

    x, y, vx, vy = (st.state[:, j] for j in range(4))
    lat, lon = plane_to_wgs84(x, y, prep.lat0, prep.lon0)
    gam = north_convergence_rows(lat, lon, prep.lat0, prep.lon0)
    course = np.where(np.isfinite(vx), wrap_2pi(bearing(vx, vy) - gam), np.nan)
    std = st.std
    return AisTracks(
        x_m=full(x),
        y_m=full(y),
        lat=full(lat),
        lon=full(lon),
        lat0=full(prep.lat0),
        lon0=full(prep.lon0),
        course=full(course),
        speed=full(np.hypot(vx, vy)),
        turn_rate=full(st.state[:, 4]),
        std_x_m=full(std[:, 0]),
        std_y_m=full(std[:, 1]),
        std_pos_m=full(np.sqrt(0.5 * (std[:, 0] ** 2 + std[:, 1] ** 2))),
        std_course=full(std[:, 3]),
        std_speed=full(std[:, 2]),
        std_turn_rate=full(std[:, 4]),
        outlier=full(st.outlier, False, bool),
        outlier_kind=full(st.outlier_kind, 0, np.int8),
        segment=full(st.segment, -1, np.int64),
        nis=full(st.nis),
        time_offset_s=full(st.time_offset),
    )
