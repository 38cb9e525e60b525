"""Debrief REP files: track fixes and sensor lines in, a TMA solution out.

REP is the plain-text replay format of Debrief, the open-source maritime analysis tool.
One record per line, fields separated by blanks; a name with blanks is written in double
quotes; ``;;`` starts a comment. Read here (every other line type is skipped):

* **track fix** -- ``YYMMDD HHMMSS[.SSS] NAME SYMBOLOGY LAT LON COURSE SPEED DEPTH [label]``
  with ``LAT`` = ``DD MM SS.SS H`` and ``LON`` = ``DDD MM SS.SS H`` (degrees, minutes,
  seconds, hemisphere N/S, E/W; the latitude hemisphere may be joined to the longitude
  degrees, ``N000``), course in degrees true, speed in knots, depth in metres;
* ``;SENSOR: DATE TIME HOST SYMBOLOGY POS BEARING RANGE SENSOR LABEL`` -- bearing in
  degrees true (any wrap), range in yards;
* ``;SENSOR2: DATE TIME HOST SYMBOLOGY POS BEARING AMBIGUOUS_BEARING FREQUENCY RANGE
  SENSOR LABEL`` -- frequency in Hz;
* ``;SENSOR3: DATE TIME HOST SYMBOLOGY POS BEARING BEARING_ACCURACY FREQUENCY
  FREQUENCY_ACCURACY RANGE SENSOR LABEL`` -- accuracies (degrees, Hz) are used as sigmas.

``POS`` is a ``LAT LON`` pair or the single word ``NULL``: the sensor is then at its host
track's position at that time (linear interpolation between the fixes). Any value may be
``NULL``; a range of 0 means no range (as in Debrief). The date is ``YYMMDD`` (years 00-69
are 2000-2069, 70-99 are 1970-1999) or ``YYYYMMDD``; times are UTC.

Local frame: East/North metres on the tangent plane at the centre of the host tracks'
fixes (exact geodetic conversion); bearings and courses, measured from true North at the
own ship, are turned into that plane by the meridian convergence
(:func:`seatrack.geometry.north_convergence`). The ambiguous bearing of a ``;SENSOR2:``
line is not used (the first bearing is taken as the true one).

Every cut of one host track is one contact (id = the host's name); each sensor name that
reports frequencies is one tonal (id = the sensor's name).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from datetime import UTC
from datetime import datetime
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from seatrack.geometry import bearing_rad_to_deg
from seatrack.geometry import enu_to_geodetic
from seatrack.geometry import geodetic_to_enu
from seatrack.geometry import knots_to_mps
from seatrack.geometry import mps_to_knots
from seatrack.geometry import north_convergence
from seatrack.geometry import velocity_from_course
from seatrack.geometry import wrap_2pi
from seatrack.io.table import InputError
from seatrack.io.table import check_input_file
from seatrack.io.tma import MeasurementDefaults
from seatrack.io.tma import TMAInput
from seatrack.io.tma import read_tma_input
from seatrack.tma.measurements import Frequencies
from seatrack.tma.problem import Bearings
from seatrack.tma.result import TMASolution
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = [
    "YARD_M",
    "is_rep",
    "read_tma_files",
    "RepCut",
    "RepData",
    "RepFrame",
    "RepTrack",
    "read_rep",
    "rep_solutions_text",
    "rep_tma_input",
    "rep_track_text",
]

#: one yard in metres (exact)
YARD_M = 0.9144

_TOKEN = re.compile(r'"[^"]*"|\S+')
_SENSOR_KINDS = {";SENSOR:": 1, ";SENSOR2:": 2, ";SENSOR3:": 3}


@dataclass
class RepTrack:
    """Fixes of one track (SI units; times POSIX seconds UTC; angles rad from true North)."""

    name: str
    symbology: str
    time_s: list[float] = field(default_factory=list)
    lat_deg: list[float] = field(default_factory=list)
    lon_deg: list[float] = field(default_factory=list)
    course: list[float] = field(default_factory=list)
    speed_mps: list[float] = field(default_factory=list)
    depth_m: list[float] = field(default_factory=list)
    where: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class RepCut:
    """One sensor line (NaN = absent; bearing and sigmas in rad, range in m)."""

    host: str
    time_s: float
    lat_deg: float
    lon_deg: float
    bearing: float
    frequency_hz: float
    range_m: float
    bearing_sigma: float
    frequency_sigma_hz: float
    sensor: str
    where: str


@dataclass(frozen=True)
class RepData:
    """Tracks by name and sensor cuts, in file order, and the files read."""

    tracks: dict[str, RepTrack]
    cuts: list[RepCut]
    files: tuple[str, ...] = ()


@dataclass(frozen=True)
class RepFrame:
    """The local tangent plane of a REP data set: origin latitude and longitude, degrees."""

    lat0_deg: float
    lon0_deg: float

    def to_local(self, lat: FloatArray, lon: FloatArray) -> FloatArray:
        """(N, 2) East, North (m) of WGS84 points at sea level."""
        return np.asarray(geodetic_to_enu(lat, lon, 0.0, self.lat0_deg, self.lon0_deg)[..., :2])

    def convergence(self, lat: FloatArray, lon: FloatArray) -> FloatArray:
        """Bearing (rad) of true North at the points in the plane."""
        return np.asarray(north_convergence(lat, lon, self.lat0_deg, self.lon0_deg), dtype=float)


def _num(tok: str, where: str, what: str) -> float:
    """A finite number, or NaN for ``NULL``."""
    if tok.upper() == "NULL":
        return math.nan
    try:
        v = float(tok)
    except ValueError:
        raise InputError(f"{where}: {what} {tok!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"{where}: {what} {tok!r} is not a finite number")
    return v


def _time(date: str, clock: str, where: str) -> float:
    try:
        if len(date) == 6:
            yy = int(date[:2])
            year = 2000 + yy if yy < 70 else 1900 + yy
            month, day = int(date[2:4]), int(date[4:6])
        elif len(date) == 8:
            year, month, day = int(date[:4]), int(date[4:6]), int(date[6:8])
        else:
            raise ValueError(date)
        hms, _, frac = clock.partition(".")
        if len(hms) != 6 or not (frac == "" or frac.isdigit()):
            raise ValueError(clock)
        stamp = datetime(year, month, day, int(hms[:2]), int(hms[2:4]), int(hms[4:6]), tzinfo=UTC)
    except ValueError:
        raise InputError(
            f"{where}: date/time {date} {clock} is not YYMMDD (or YYYYMMDD) HHMMSS[.SSS]"
        ) from None
    return stamp.timestamp() + (float("0." + frac) if frac else 0.0)


def _position(tok: list[str], i: int, where: str) -> tuple[float, float, int]:
    """Latitude, longitude (deg) from ``DD MM SS.SS H DDD MM SS.SS H`` at ``tok[i]``; the
    index after it. Accepts the hemisphere joined to the longitude degrees (``N000``)."""
    end = i + 8
    try:
        d, m, s, h = tok[i : i + 4]
        if len(h) > 1 and h[0] in "NSns":  # "N000": hemisphere and longitude degrees joined
            tok = tok[: i + 3] + [h[0], h[1:]] + tok[i + 4 :]
            h = h[0]
            end = i + 7  # one token fewer in the caller's list
        ld, lm, ls, lh = tok[i + 4 : i + 8]
        parts = [float(x) for x in (d, m, s, ld, lm, ls)]
        if (
            not all(math.isfinite(x) and x >= 0 for x in parts)
            or max(parts[1], parts[2], parts[4], parts[5]) >= 60
        ):
            raise ValueError(tok[i])  # fmt: skip
        lat = parts[0] + parts[1] / 60 + parts[2] / 3600
        lon = parts[3] + parts[4] / 60 + parts[5] / 3600
    except (ValueError, IndexError):
        raise InputError(
            f"{where}: position is not DD MM SS.SS H DDD MM SS.SS H (or NULL)"
        ) from None
    if h.upper() not in "NS" or lh.upper() not in "EW" or lat > 90 or lon > 180:
        raise InputError(f"{where}: position {' '.join(tok[i : i + 8])} is not a valid latitude "
                         "and longitude")  # fmt: skip
    return (-lat if h.upper() == "S" else lat), (-lon if lh.upper() == "W" else lon), end


def _name(tok: str) -> str:
    return tok[1:-1] if len(tok) >= 2 and tok[0] == tok[-1] == '"' else tok


def _fix(tok: list[str], where: str, tracks: dict[str, RepTrack]) -> None:
    if len(tok) < 7:
        raise InputError(f"{where}: a track fix needs date, time, name, symbology, position, "
                         "course, speed and depth")  # fmt: skip
    t = _time(tok[0], tok[1], where)
    name = _name(tok[2])
    lat, lon, k = _position(tok, 4, where)
    if len(tok) < k + 3:
        raise InputError(f"{where}: a track fix needs course, speed and depth after the position")
    crs = _num(tok[k], where, "course")
    spd = _num(tok[k + 1], where, "speed")
    dep = _num(tok[k + 2], where, "depth")
    if math.isnan(crs) or math.isnan(spd) or spd < 0:
        raise InputError(f"{where}: course and speed must be numbers (speed >= 0 kn)")
    tr = tracks.setdefault(name, RepTrack(name, tok[3]))
    if tr.time_s and t < tr.time_s[-1]:
        raise InputError(f"{where}: fix of {name!r} is earlier than its previous fix")
    if tr.time_s and t == tr.time_s[-1]:
        return  # a repeated fix (as written by some tools): the first one is kept
    tr.time_s.append(t)
    tr.lat_deg.append(lat)
    tr.lon_deg.append(lon)
    tr.course.append(math.radians(crs))
    tr.speed_mps.append(float(knots_to_mps(spd)))
    tr.depth_m.append(dep)
    tr.where.append(where)


def _sensor(kind: int, tok: list[str], where: str) -> RepCut:
    n_vals = {1: 2, 2: 4, 3: 5}[kind]
    try:
        t = _time(tok[1], tok[2], where)
        host = _name(tok[3])
        if tok[5].upper() == "NULL":
            lat = lon = math.nan
            k = 6
        else:
            lat, lon, k = _position(tok, 5, where)
        vals = [_num(x, where, "value") for x in tok[k : k + n_vals]]
        sensor = _name(tok[k + n_vals])
    except IndexError:
        raise InputError(f"{where}: too few fields for a {tok[0]} line") from None
    nan = math.nan
    if kind == 1:
        brg, rng, fr, sb, sf = vals[0], vals[1], nan, nan, nan
    elif kind == 2:
        brg, fr, rng, sb, sf = vals[0], vals[2], vals[3], nan, nan
    else:
        brg, sb, fr, sf, rng = vals
    for v, what in ((sb, "bearing accuracy"), (sf, "frequency accuracy")):
        if not (math.isnan(v) or v > 0):
            raise InputError(f"{where}: {what} must be positive, got {v:g}")
    if not (math.isnan(fr) or 0 < fr <= 1e6):
        raise InputError(f"{where}: frequency {fr:g} Hz must be in (0, 1e+06]")
    if not (math.isnan(rng) or 0 <= rng <= 1e8):
        raise InputError(f"{where}: range {rng:g} yd must be in [0, 1e+08]")
    if math.isnan(brg) and math.isnan(fr) and not rng > 0:
        raise InputError(f"{where}: the sensor line holds no bearing, frequency or range")
    return RepCut(
        host, t, lat, lon, nan if math.isnan(brg) else float(wrap_2pi(math.radians(brg))),
        fr, rng * YARD_M if rng > 0 else nan, math.radians(sb), sf, sensor, where,
    )  # fmt: skip


def read_rep(paths: Sequence[str | Path]) -> RepData:
    """Read track fixes and sensor lines from one or several REP files (module docstring).

    Raises
    ------
    InputError
        ``FILE, line N: problem`` for a line that does not parse; a file that cannot be read.
    """
    tracks: dict[str, RepTrack] = {}
    cuts: list[RepCut] = []
    files = []
    for path in paths:
        p = check_input_file(path, "a REP file")
        files.append(str(p))
        try:
            text = p.read_text(encoding="utf-8", errors="replace")
        except OSError as exc:
            raise InputError(f"{p}: cannot read ({exc.strerror})") from None
        for n, line in enumerate(text.splitlines(), start=1):
            s = line.strip()
            if not s or s.startswith(";;"):
                continue
            where = f"{p}, line {n}"
            tok = _TOKEN.findall(s)
            if tok[0].startswith(";"):
                kind = _SENSOR_KINDS.get(tok[0].upper())
                if kind is not None:
                    cuts.append(_sensor(kind, tok, where))
                continue  # other annotation lines (;TEXT:, ;LINE:, ...) are not used
            _fix(tok, where, tracks)
    return RepData(tracks, cuts, tuple(files))


def _frame(data: RepData, hosts: Sequence[str]) -> RepFrame:
    lat = np.concatenate([data.tracks[h].lat_deg for h in hosts])
    lon = np.concatenate([data.tracks[h].lon_deg for h in hosts])
    return RepFrame(float(0.5 * (lat.min() + lat.max())), float(0.5 * (lon.min() + lon.max())))


def _host_state(tr: RepTrack, frame: RepFrame, t: FloatArray, where: list[str]) -> tuple[
    FloatArray, FloatArray
]:  # fmt: skip
    """Host position (m) and velocity (m/s) in the plane at times ``t``, interpolated."""
    ts = np.asarray(tr.time_s)
    bad = np.flatnonzero((t < ts[0]) | (t > ts[-1]))
    if bad.size:
        raise InputError(
            f"{where[bad[0]]}: the sensor time is outside the fixes of its host track "
            f"{tr.name!r} ({tr.where[0]} to {tr.where[-1]})"
        )
    lat, lon = np.asarray(tr.lat_deg), np.asarray(tr.lon_deg)
    xy = frame.to_local(lat, lon)
    course = np.asarray(tr.course) + frame.convergence(lat, lon)
    vel = velocity_from_course(course, np.asarray(tr.speed_mps))
    if ts.size == 1:
        return np.repeat(xy, t.size, axis=0), np.repeat(vel, t.size, axis=0)
    pos = np.stack([np.interp(t, ts, xy[:, k]) for k in range(2)], axis=1)
    v = np.stack([np.interp(t, ts, vel[:, k]) for k in range(2)], axis=1)
    return pos, v


def rep_tma_input(
    data: RepData, defaults: MeasurementDefaults | None = None
) -> tuple[TMAInput, RepFrame]:
    """Contacts for :func:`seatrack.tma.solve_many` from REP data: one contact per host
    track, bearings and frequencies of all its sensors (tonal = sensor name), ranges as
    range support values. Returns the contacts and the local frame.

    Raises
    ------
    InputError
        No sensor lines; a host track missing or without a fix around a sensor time; fewer
        than two bearings for a host; two bearings of one host at the same time.
    """
    d = defaults or MeasurementDefaults()
    if not data.cuts:
        names = ", ".join(data.files) or "REP input"
        raise InputError(f"{names}: no ;SENSOR:, ;SENSOR2: or ;SENSOR3: lines")
    hosts = list(dict.fromkeys(c.host for c in data.cuts))
    for h in hosts:
        if h not in data.tracks:
            first = next(c for c in data.cuts if c.host == h)
            raise InputError(f"{first.where}: host track {h!r} is not in the REP file(s); "
                             "give the file with its fixes too")  # fmt: skip
    frame = _frame(data, hosts)
    contacts: dict[str, Bearings] = {}
    support: dict[str, list[SupportValue]] = {}
    for h in hosts:
        cuts = sorted((c for c in data.cuts if c.host == h), key=lambda c: c.time_s)
        t = np.array([c.time_s for c in cuts])
        where = [c.where for c in cuts]
        pos, vel = _host_state(data.tracks[h], frame, t, where)
        lat = np.array([c.lat_deg for c in cuts])
        own = ~np.isnan(lat)
        if own.any():  # the sensor's own position
            pos[own] = frame.to_local(lat[own], np.array([c.lon_deg for c in cuts])[own])
        gam = frame.convergence(*_latlon(frame, pos))
        brg = np.array([c.bearing for c in cuts])
        fr = np.array([c.frequency_hz for c in cuts])
        b = ~np.isnan(brg)
        if b.sum() < 2:
            raise InputError(f"{where[0]}: host {h!r} has {int(b.sum())} bearing(s); TMA "
                             "needs at least 2")  # fmt: skip
        tb = t[b]
        dup = np.flatnonzero(np.diff(tb) <= 0)
        if dup.size:
            raise InputError(f"{np.asarray(where)[b][dup[0] + 1]}: a second bearing of host "
                             f"{h!r} at the same time")  # fmt: skip
        f = ~np.isnan(fr) & (t >= tb[0])
        sb = np.array([c.bearing_sigma for c in cuts])
        sf = np.array([c.frequency_sigma_hz for c in cuts])
        sensors = np.array([c.sensor for c in cuts])
        tonal_sigma = np.array([d.frequency_by_tonal.get(s, d.frequency) for s in sensors])
        freqs = None
        if f.any():
            freqs = Frequencies(
                t[f], fr[f], pos[f], vel[f], np.where(np.isnan(sf), tonal_sigma, sf)[f],
                sensors[f],
            )  # fmt: skip
        contacts[h] = Bearings(
            tb, np.asarray(wrap_2pi(brg[b] + gam[b])), pos[b],
            np.where(np.isnan(sb), d.bearing, sb)[b], freqs,
        )  # fmt: skip
        rng = np.array([c.range_m for c in cuts])
        for i in np.flatnonzero(~np.isnan(rng) & (t >= tb[0])):
            support.setdefault(h, []).append(
                SupportValue(
                    "range",
                    float(t[i]),
                    float(rng[i]),
                    d.range,
                    (float(pos[i, 0]), float(pos[i, 1])),
                )  # fmt: skip
            )
    return TMAInput(contacts, support), frame


def _latlon(frame: RepFrame, xy: FloatArray) -> tuple[FloatArray, FloatArray]:
    lat, lon, _ = enu_to_geodetic(xy, frame.lat0_deg, frame.lon0_deg)
    return np.asarray(lat), np.asarray(lon)


def _dms(value: float, pos: str, neg: str, width: int) -> str:
    h = pos if value >= 0 else neg
    a = abs(value)
    d = int(a)
    m = int((a - d) * 60)
    s = (a - d - m / 60) * 3600
    if s >= 59.995:  # rounding would print 60.00
        s, m = 0.0, m + 1
        if m == 60:
            m, d = 0, d + 1
    return f"{d:0{width}d} {m:02d} {s:05.2f} {h}"


def rep_track_text(
    solution: TMASolution,
    frame: RepFrame,
    times: Sequence[float] | FloatArray,
    name: str = "TMA",
    symbology: str = "@C",
) -> str:
    """REP track lines of a TMA solution: a fix at every leg start and end and at every
    time of ``times`` (the measurement times), sorted, with course and speed of the leg.

    Positions from the solution's legs (:meth:`TMASolution.position_at`) converted to
    WGS84; the course is turned back from the plane to true North at the fix.
    """
    ends = [float(x) for x in solution.starts[1:]]
    t = np.unique(np.concatenate([np.asarray(times, dtype=float), solution.starts, ends,
                                  [float(np.max(times))]]))  # fmt: skip
    t = t[t >= solution.t0]
    xy = solution.position_at(t)
    lat, lon = _latlon(frame, xy)
    legs = np.searchsorted(solution.starts, t, side="right") - 1
    B = solution.state.reshape(-1, 2)
    v = B[1 + legs]
    course = np.arctan2(v[:, 0], v[:, 1]) - frame.convergence(lat, lon)
    speed = mps_to_knots(np.hypot(v[:, 0], v[:, 1]))
    quoted = f'"{name}"' if " " in name else name
    lines = [";; seatrack TMA solution (Debrief REP track)"]
    for k, tk in enumerate(t):
        stamp = datetime.fromtimestamp(float(tk), tz=UTC)
        clock = stamp.strftime("%H%M%S") + f".{stamp.microsecond // 1000:03d}"
        lines.append(
            f"{stamp.strftime('%y%m%d')} {clock} {quoted} {symbology} "
            f"{_dms(float(lat[k]), 'N', 'S', 2)} {_dms(float(lon[k]), 'E', 'W', 3)} "
            f"{float(bearing_rad_to_deg(course[k])):.2f} {float(speed[k]):.2f} 0.00"
        )
    return "\n".join(lines) + "\n"


def is_rep(path: str | Path) -> bool:
    """Whether a path names a REP file (extension ``.rep``, any case)."""
    return Path(path).suffix.lower() == ".rep"


def read_tma_files(
    paths: Sequence[str | Path], defaults: MeasurementDefaults | None = None
) -> tuple[TMAInput, RepFrame | None]:
    """The input of ``seatrack tma``: one BEARINGS.csv (:func:`seatrack.io.tma.read_tma_input`)
    or one or several REP files (:func:`read_rep`, :func:`rep_tma_input`); the local frame
    of REP input (None for CSV)."""
    if not paths:
        raise InputError("no input file given")
    reps = [is_rep(p) for p in paths]
    if any(reps):
        if not all(reps):
            bad = next(p for p, r in zip(paths, reps, strict=True) if not r)
            raise InputError(f"{bad}: mix of REP and CSV input; give REP files only (or one CSV)")
        return rep_tma_input(read_rep(paths), defaults)
    if len(paths) > 1:
        raise InputError(f"{paths[1]}: one BEARINGS.csv at a time (several files: REP only)")
    return read_tma_input(paths[0], defaults), None


def rep_solutions_text(
    solutions: Mapping[str, TMASolution], contacts: Mapping[str, Bearings], frame: RepFrame
) -> str:
    """REP tracks ``TMA_<contact>`` of every solution (:func:`rep_track_text`) at every
    measurement time of its contact (bearings, frequencies, ATB)."""
    parts = []
    for cid, sol in solutions.items():
        b = contacts[cid]
        times = [b.t] + [x.t for x in (b.frequencies, b.bow_angles) if x is not None]
        parts.append(rep_track_text(sol, frame, np.concatenate(times), f"TMA_{cid}"))
    return "".join(parts)
