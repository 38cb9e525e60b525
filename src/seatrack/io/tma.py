"""BEARINGS.csv / SUPPORT.csv readers and the RESULT.json writer of ``seatrack tma``.

File formats (header names exact, extra columns allowed; ``docs/formats.md``)
-----------------------------------------------------------------------------
BEARINGS.csv: ``contact`` (optional; default one contact ``"1"``), ``time_s``,
``bearing_deg`` (true, clockwise from North, in [0, 360)), ``observer_x_m``,
``observer_y_m`` (East, North), optional ``sigma_deg`` (empty cell = the default sigma).
Times strictly increasing per contact; at least 2 bearings per contact.

SUPPORT.csv: ``contact`` (optional), ``kind`` (range | speed | course), ``time_s``,
``value`` (m, m/s or deg), ``sigma`` (same unit), ``observer_x_m``, ``observer_y_m``
(required for a range; optional columns otherwise).

Values must be finite (checked by :func:`seatrack.io.table.read_csv_table`) and plausible:
``|time_s| <= 1e10`` s, ``|observer_*| <= 1e8`` m, bearing sigma in (0, 180) deg, a range in
(0, 1e8] m, a speed in (0, 1000] m/s, a course in [0, 360) deg, each support sigma positive
and at most the largest value of its kind (180 deg for a course).

RESULT.json: an object keyed by contact id; see :func:`solution_to_dict`. Always valid JSON:
numbers that are not determined are ``null`` (:func:`result_json`, never NaN or Infinity).

Every error names the file, the line (header = line 1) and the problem.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.geometry import bearing_rad_to_deg
from seatrack.geometry import deg2rad
from seatrack.io.suspect import ms_warning
from seatrack.io.suspect import warn
from seatrack.io.table import MIN_SIGMA
from seatrack.io.table import InputError
from seatrack.io.table import Table
from seatrack.io.table import check_times
from seatrack.io.table import read_csv_table
from seatrack.tma.bounds import ellipse
from seatrack.tma.problem import Bearings
from seatrack.tma.result import TMASolution
from seatrack.tma.support import KINDS
from seatrack.tma.support import SupportValue

__all__ = [
    "DEFAULT_CONTACT",
    "LIMITS",
    "read_bearings",
    "read_support",
    "result_json",
    "solution_summary",
    "solution_to_dict",
]

#: contact id used when BEARINGS.csv / SUPPORT.csv have no ``contact`` column
DEFAULT_CONTACT = "1"

#: plausibility limits of the input values (SI units; angles in degrees as in the files)
LIMITS = {
    "time_s": 1e10,
    "position_m": 1e8,
    "sigma_deg": 180.0,
    "range_m": 1e8,
    "speed_mps": 1000.0,
}

#: largest plausible value and sigma of each support kind (unit of the file)
_SUPPORT_MAX = {"range": LIMITS["range_m"], "speed": LIMITS["speed_mps"], "course": 180.0}


def _check_abs(tab: Table, path: str, column: str, limit: float, unit: str) -> None:
    if column not in tab:
        return
    v = tab[column]
    bad = np.flatnonzero(np.abs(np.where(np.isnan(v), 0.0, v)) > limit)
    if bad.size:
        i = bad[0]
        raise InputError(
            f"{path}, line {tab.lines[i]}: {column} = {v[i]:g} is implausible "
            f"(|{column}| must be at most {limit:g} {unit})"
        )


def _contacts(table: Any, path: str) -> np.ndarray:
    if "contact" not in table:
        return np.full(len(table), DEFAULT_CONTACT)
    c = table["contact"]
    empty = np.flatnonzero(c == "")
    if empty.size:
        raise InputError(f"{path}, line {table.lines[empty[0]]}: column contact is empty")
    return np.asarray(c)


def read_bearings(
    path: str | Path, default_sigma: float = math.radians(1.0)
) -> dict[str, Bearings]:
    """Read BEARINGS.csv into one :class:`Bearings` per contact (radians inside).

    Empty ``sigma_deg`` cells take ``default_sigma`` (rad); without the column the
    bearings carry no sigma (the solver's ``sigma`` applies).

    Raises
    ------
    InputError
        Missing columns, non-numeric / NaN / infinite cells, implausible values (see the
        module docstring), bearings outside [0, 360), sigma outside (0, 180) deg, unsorted
        or duplicate times, a contact with a single bearing.
    """
    p = str(path)
    tab = read_csv_table(
        path,
        required=["time_s", "bearing_deg", "observer_x_m", "observer_y_m"],
        optional=["contact", "sigma_deg"],
        text=["contact"],
    )
    cid = _contacts(tab, p)
    b = tab["bearing_deg"]
    bad = np.flatnonzero((b < 0) | (b >= 360))
    if bad.size:
        i = bad[0]
        raise InputError(f"{p}, line {tab.lines[i]}: bearing_deg = {b[i]:g} is outside [0, 360)")
    sig = tab["sigma_deg"] if "sigma_deg" in tab else np.full(len(tab), np.nan)
    bad = np.flatnonzero((sig < MIN_SIGMA) | (sig >= LIMITS["sigma_deg"]))
    if bad.size:
        i = bad[0]
        raise InputError(
            f"{p}, line {tab.lines[i]}: sigma_deg = {sig[i]:g} must be in [{MIN_SIGMA:g}, 180) "
            "degrees"
        )
    _check_abs(tab, p, "time_s", LIMITS["time_s"], "s")
    for c in ("observer_x_m", "observer_y_m"):
        _check_abs(tab, p, c, LIMITS["position_m"], "m")
    tab.columns["contact"] = cid
    check_times(tab, "time_s", group="contact", strict=True)
    warn([ms_warning(p, "time_s", tab["time_s"], cid)])
    out: dict[str, Bearings] = {}
    for c in dict.fromkeys(cid.tolist()):
        m = cid == c
        if m.sum() < 2:
            raise InputError(
                f"{p}, line {tab.lines[m][0]}: contact {c!r} has a single bearing; "
                "TMA needs at least 2"
            )
        s = sig[m]
        out[c] = Bearings(
            tab["time_s"][m],
            np.asarray(deg2rad(b[m])),
            np.stack([tab["observer_x_m"][m], tab["observer_y_m"][m]], axis=1),
            None if "sigma_deg" not in tab else np.where(np.isnan(s), default_sigma, deg2rad(s)),
        )
    return out


def _support_value(
    where: str, kind: str, t: float, val: float, sig: float, ox: float, oy: float
) -> SupportValue:
    """One validated support value (file units in, SI/radians out)."""
    top = _SUPPORT_MAX[kind]
    unit = {"range": "m", "speed": "m/s", "course": "deg"}[kind]
    if abs(t) > LIMITS["time_s"]:
        raise InputError(f"{where}: time_s = {t:g} is implausible (|time_s| <= 1e+10 s)")
    if not 0 < sig <= top:
        raise InputError(f"{where}: sigma = {sig:g} must be in (0, {top:g}] {unit}")
    obs = None
    if kind == "range":
        if not (math.isfinite(ox) and math.isfinite(oy)):
            raise InputError(f"{where}: a range support value needs observer_x_m and observer_y_m")
        if max(abs(ox), abs(oy)) > LIMITS["position_m"]:
            raise InputError(
                f"{where}: observer position ({ox:g}, {oy:g}) is implausible (|x|, |y| <= 1e+08 m)"
            )
        obs = (float(ox), float(oy))
    if kind == "course":
        if not 0 <= val < 360:
            raise InputError(f"{where}: course value = {val:g} is outside [0, 360)")
        val, sig = math.radians(val), math.radians(sig)
    elif not 0 < val <= top:
        raise InputError(f"{where}: {kind} value = {val:g} must be in (0, {top:g}] {unit}")
    return SupportValue(kind, t, val, sig, obs)


def read_support(path: str | Path) -> dict[str, list[SupportValue]]:
    """Read SUPPORT.csv into support values per contact (SI units, radians inside).

    Raises
    ------
    InputError
        Missing columns, non-numeric / NaN / infinite cells, an unknown kind, implausible
        values (module docstring), a range without the observer position.
    """
    p = str(path)
    tab = read_csv_table(
        path,
        required=["kind", "time_s", "value", "sigma"],
        optional=["contact", "observer_x_m", "observer_y_m"],
        text=["contact", "kind"],
    )
    cid = _contacts(tab, p)
    ox = tab["observer_x_m"] if "observer_x_m" in tab else np.full(len(tab), np.nan)
    oy = tab["observer_y_m"] if "observer_y_m" in tab else np.full(len(tab), np.nan)
    out: dict[str, list[SupportValue]] = {}
    for i in range(len(tab)):
        where = f"{p}, line {tab.lines[i]}"
        kind = str(tab["kind"][i]).strip().lower()
        if kind not in KINDS:
            raise InputError(
                f"{where}: kind = {str(tab['kind'][i])!r}; use one of {', '.join(KINDS)}"
            )
        v = _support_value(
            where, kind, float(tab["time_s"][i]), float(tab["value"][i]), float(tab["sigma"][i]),
            float(ox[i]), float(oy[i]),
        )  # fmt: skip
        out.setdefault(str(cid[i]), []).append(v)
    return out


def _num(x: Any) -> float | None:
    v = float(x)
    return v if math.isfinite(v) else None


def _json_safe(obj: Any) -> Any:
    """Plain JSON types: non-finite floats -> None, numpy scalars/arrays -> Python."""
    if isinstance(obj, Mapping):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return _num(obj)
    return obj


def result_json(solutions: Mapping[str, TMASolution]) -> str:
    """RESULT.json text of every contact: valid JSON (``null``, never NaN or Infinity)."""
    doc = {cid: solution_to_dict(s) for cid, s in solutions.items()}
    return json.dumps(_json_safe(doc), indent=2, allow_nan=False) + "\n"


def solution_to_dict(sol: TMASolution) -> dict[str, Any]:
    """RESULT.json entry of one contact (degrees and SI units; ``null`` = not determined).

    Fields: ``t0_s``; ``x_m, y_m, vx_mps, vy_mps`` (target at ``t0``, first leg); ``legs``
    (``start_s, vx_mps, vy_mps``); ``covariance`` with ``state_order``; ``last`` (time,
    position, range, bearing, course, speed, their 1-sigma and half-widths of the
    ``confidence`` interval, and the position ellipse); ``iterations`` (LM trials from the
    chosen start value to convergence), ``iterations_total`` (over every start tried),
    ``converged``, ``observable``, ``condition_number``, ``smallest_singular_value``,
    ``residual_rms_deg``, ``cost``, ``manoeuvres_s``, ``manoeuvres_detected``,
    ``warnings``. Unless the solution is observable *and* converged every
    range-dependent number (state, covariance, operator values) is ``null``.
    """
    ok = sol.valid
    B = sol.state.reshape(-1, 2)
    L = sol.last
    zf = L.z_factor
    order = ["x_m", "y_m"] + [f"{c}{j}_mps" for j in range(B.shape[0] - 1) for c in ("vx", "vy")]

    def val(x: float) -> float | None:
        return _num(x) if ok else None

    last: dict[str, Any] = {
        "time_s": L.time,
        "x_m": _num(L.x),
        "y_m": _num(L.y),
        "range_m": _num(L.range),
        "bearing_deg": _num(bearing_rad_to_deg(L.bearing)),
        "course_deg": _num(bearing_rad_to_deg(L.course)) if ok else None,
        "speed_mps": _num(L.speed),
        "sigma_x_m": _num(L.sigma_x),
        "sigma_y_m": _num(L.sigma_y),
        "sigma_range_m": _num(L.sigma_range),
        "sigma_bearing_deg": _num(math.degrees(L.sigma_bearing)),
        "sigma_course_deg": _num(math.degrees(L.sigma_course)),
        "sigma_speed_mps": _num(L.sigma_speed),
        "confidence": L.confidence,
        "range_m_halfwidth": _num(zf * L.sigma_range),
        "bearing_deg_halfwidth": _num(zf * math.degrees(L.sigma_bearing)),
        "course_deg_halfwidth": _num(zf * math.degrees(L.sigma_course)),
        "speed_mps_halfwidth": _num(zf * L.sigma_speed),
        "ellipse": None,
    }
    if ok:
        a, b, o = ellipse(L.position_covariance, L.confidence)
        last["ellipse"] = {"semi_major_m": a, "semi_minor_m": b, "orientation_deg": math.degrees(o)}
    return {
        "t0_s": sol.t0,
        "x_m": val(B[0, 0]),
        "y_m": val(B[0, 1]),
        "vx_mps": val(B[1, 0]),
        "vy_mps": val(B[1, 1]),
        "legs": [
            {"start_s": float(s), "vx_mps": val(B[1 + j, 0]), "vy_mps": val(B[1 + j, 1])}
            for j, s in enumerate(sol.starts)
        ],
        "state_order": order,
        "covariance": [[_num(v) for v in row] for row in sol.covariance] if ok else None,
        "last": last,
        "iterations": sol.iterations,
        "iterations_total": sol.iterations_total,
        "converged": sol.converged,
        "observable": sol.observable,
        "condition_number": _num(sol.condition_number),
        "smallest_singular_value": _num(sol.smallest_singular_value),
        "residual_rms_deg": _num(math.degrees(sol.residual_rms)),
        "cost": _num(sol.cost),
        "n_bearings": sol.n_bearings,
        "n_support": sol.n_support,
        "manoeuvres_s": [float(m) for m in sol.manoeuvres],
        "manoeuvres_detected": sol.manoeuvres_detected,
        "warnings": list(sol.warnings),
    }


def solution_summary(cid: str, s: TMASolution) -> str:
    """One console line of ``seatrack tma``; operator numbers (m, deg, m/s) only for an
    observable, converged solution."""
    if not s.observable:
        return f"contact {cid}: NOT OBSERVABLE (no range, course or speed)"
    if not s.converged:
        return (
            f"contact {cid}: NOT CONVERGED after {s.iterations} iterations "
            "(no range, course or speed)"
        )
    L = s.last
    return (
        f"contact {cid}: range {L.range:.0f} +/- {L.sigma_range:.0f} m, "
        f"bearing {math.degrees(L.bearing):.1f} deg, "
        f"course {math.degrees(L.course):.1f} +/- {math.degrees(L.sigma_course):.1f} deg, "
        f"speed {L.speed:.2f} +/- {L.sigma_speed:.2f} m/s ({s.iterations} iterations)"
    )
