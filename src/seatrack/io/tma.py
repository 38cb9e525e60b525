"""BEARINGS.csv / SUPPORT.csv readers and the RESULT.json writer of ``seatrack tma``.

File formats (header names exact, extra columns allowed; ``docs/formats.md``)
-----------------------------------------------------------------------------
BEARINGS.csv: ``contact`` (optional; default one contact ``"1"``), ``time_s``,
``bearing_deg`` (true, clockwise from North, in [0, 360)), ``observer_x_m``,
``observer_y_m`` (East, North), optional ``sigma_deg`` (empty cell = the default sigma).
Times strictly increasing per contact; at least 2 bearings per contact.

Optional BEARINGS.csv columns of the other measurements (a row may hold any subset;
``bearing_deg`` may then be empty on a row without a bearing): ``frequency_hz`` (received
tonal frequency, (0, 1e6] Hz), ``frequency_sigma_hz`` ((0, 1e4] Hz; empty = the default of
its tonal), ``tonal`` (tonal id, text; empty = ``"1"``), ``atb_deg`` (angle on the bow,
[-180, 360) deg, positive = the own ship on the target's starboard side), ``atb_sigma_deg``
((0, 180) deg), ``range_m`` ((0, 1e8] m) and ``range_sigma_m`` (positive, m), and the
own-ship velocity ``observer_vx_mps``, ``observer_vy_mps`` (m/s; when absent it is
differenced from the own-ship positions of the contact's rows). With any of these columns
only the bearing rows need strictly increasing times (two tonals may share a time); every
row must hold at least one measurement. See :func:`read_tma_input`.

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

import csv
import json
import math
from collections.abc import Mapping
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from dataclasses import replace
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
from seatrack.io.table import describe_header
from seatrack.io.table import read_csv_table
from seatrack.tma.bounds import ellipse
from seatrack.tma.measurements import BowAngles
from seatrack.tma.measurements import Frequencies
from seatrack.tma.measurements import observer_velocity
from seatrack.tma.problem import Bearings
from seatrack.tma.result import TMASolution
from seatrack.tma.support import KINDS
from seatrack.tma.support import SupportValue

__all__ = [
    "DEFAULT_CONTACT",
    "EXTRA_COLUMNS",
    "LIMITS",
    "MeasurementDefaults",
    "TMAInput",
    "apply_base_frequencies",
    "measurement_defaults",
    "OPTION_NAMES",
    "parse_tonal_values",
    "read_bearings",
    "read_tma_input",
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
    "frequency_hz": 1e6,
    "frequency_sigma_hz": 1e4,
}

#: optional BEARINGS.csv columns of the measurements beside bearings
EXTRA_COLUMNS = (
    "frequency_hz", "frequency_sigma_hz", "tonal", "atb_deg", "atb_sigma_deg", "range_m",
    "range_sigma_m", "observer_vx_mps", "observer_vy_mps",
)  # fmt: skip


@dataclass(frozen=True)
class MeasurementDefaults:
    """Sigmas used where BEARINGS.csv has none (SI units, radians).

    Attributes
    ----------
    bearing : rad; frequency : Hz (every tonal); frequency_by_tonal : Hz per tonal id
    (overrides ``frequency``); atb : rad; range : m.
    """

    bearing: float = math.radians(1.0)
    frequency: float = 0.1
    frequency_by_tonal: Mapping[str, float] = field(default_factory=dict)
    atb: float = math.radians(10.0)
    range: float = 100.0


@dataclass(frozen=True)
class TMAInput:
    """Contacts read from files: bearings (with frequencies and ATB) and support values
    (ranges of BEARINGS.csv become range support values)."""

    contacts: dict[str, Bearings]
    support: dict[str, list[SupportValue]]


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


def _bad_row(
    tab: Table, p: str, mask: np.ndarray, message: str, values: np.ndarray | None = None
) -> None:
    """Raise :class:`InputError` for the first row of ``mask``: ``message`` after
    ``name = value`` when ``values`` is given (``message`` starts with the column name)."""
    bad = np.flatnonzero(mask)
    if bad.size:
        i = int(bad[0])
        if values is not None:
            name, _, rule = message.partition(" ")
            message = f"{name} = {values[i]:g} {rule}"
        raise InputError(f"{p}, line {tab.lines[i]}: {message}")


def _column(tab: Table, name: str) -> np.ndarray:
    return tab[name] if name in tab else np.full(len(tab), np.nan)


def _check_extras(tab: Table, p: str) -> None:
    """Value ranges of the optional measurement columns (module docstring)."""
    f, fs = _column(tab, "frequency_hz"), _column(tab, "frequency_sigma_hz")
    a, as_ = _column(tab, "atb_deg"), _column(tab, "atb_sigma_deg")
    r, rs = _column(tab, "range_m"), _column(tab, "range_sigma_m")
    rules = [
        ((f <= 0) | (f > LIMITS["frequency_hz"]), f, "frequency_hz", "must be in (0, 1e+06] Hz"),
        ((fs <= 0) | (fs > LIMITS["frequency_sigma_hz"]), fs, "frequency_sigma_hz",
         "must be in (0, 1e+04] Hz"),
        ((a < -180) | (a >= 360), a, "atb_deg", "is outside [-180, 360)"),
        ((as_ <= 0) | (as_ >= 180), as_, "atb_sigma_deg", "must be in (0, 180) degrees"),
        ((r <= 0) | (r > LIMITS["range_m"]), r, "range_m", "must be in (0, 1e+08] m"),
        ((rs <= 0) | (rs > LIMITS["range_m"]), rs, "range_sigma_m", "must be in (0, 1e+08] m"),
    ]  # fmt: skip
    for mask, v, name, rule in rules:
        _bad_row(tab, p, mask, f"{name} {rule}", v)
    for sig, val in (("frequency_sigma_hz", f), ("atb_sigma_deg", a), ("range_sigma_m", r)):
        _bad_row(tab, p, ~np.isnan(_column(tab, sig)) & np.isnan(val),
                 f"{sig} is given without its measurement")  # fmt: skip
    vx, vy = _column(tab, "observer_vx_mps"), _column(tab, "observer_vy_mps")
    _bad_row(tab, p, np.isnan(vx) != np.isnan(vy),
             "give both observer_vx_mps and observer_vy_mps or neither")  # fmt: skip
    _bad_row(tab, p, np.hypot(vx, vy) > LIMITS["speed_mps"],
             "own-ship velocity is implausible (at most 1000 m/s)")  # fmt: skip


def _contact_extras(
    tab: Table, p: str, m: np.ndarray, defaults: MeasurementDefaults
) -> tuple[Frequencies | None, BowAngles | None, list[SupportValue]]:
    """Frequencies, ATB and range support values of the rows ``m`` of one contact."""
    t = tab["time_s"][m]
    obs = np.stack([tab["observer_x_m"][m], tab["observer_y_m"][m]], axis=1)
    f = _column(tab, "frequency_hz")[m]
    fr = None
    if np.any(~np.isnan(f)):
        vel = np.stack([_column(tab, "observer_vx_mps")[m], _column(tab, "observer_vy_mps")[m]], 1)
        diff = observer_velocity(t, obs)
        vel = np.where(np.isnan(vel), diff, vel)
        k = ~np.isnan(f)
        ton = tab["tonal"][m] if "tonal" in tab else np.full(t.size, "")
        ton = np.where(ton == "", DEFAULT_CONTACT, ton)[k]
        sig = _column(tab, "frequency_sigma_hz")[m][k]
        dflt = np.array([defaults.frequency_by_tonal.get(x, defaults.frequency) for x in ton])
        fr = Frequencies(t[k], f[k], obs[k], vel[k], np.where(np.isnan(sig), dflt, sig), ton)
    a = _column(tab, "atb_deg")[m]
    ab = None
    if np.any(~np.isnan(a)):
        k = ~np.isnan(a)
        sig = _column(tab, "atb_sigma_deg")[m][k]
        ab = BowAngles(
            t[k], np.asarray(deg2rad(a[k])), obs[k],
            np.where(np.isnan(sig), defaults.atb, np.asarray(deg2rad(sig))),
        )  # fmt: skip
    r = _column(tab, "range_m")[m]
    rs = _column(tab, "range_sigma_m")[m]
    ranges = [
        SupportValue(
            "range",
            float(t[i]),
            float(r[i]),
            defaults.range if np.isnan(rs[i]) else float(rs[i]),
            (float(obs[i, 0]), float(obs[i, 1])),
        )  # fmt: skip
        for i in np.flatnonzero(~np.isnan(r))
    ]
    return fr, ab, ranges


def _has_extras(path: str | Path) -> bool:
    """Whether the header of a CSV file names a measurement column beside the bearing."""
    try:
        with open(path, encoding="utf-8", errors="replace", newline="") as fh:
            header = next(csv.reader(fh), [])
    except OSError:
        return False  # the table reader reports the problem with the file
    names = {h.strip().lstrip("\ufeff") for h in header}
    return bool(names & {"frequency_hz", "atb_deg", "range_m"})


def read_tma_input(path: str | Path, defaults: MeasurementDefaults | None = None) -> TMAInput:
    """Read BEARINGS.csv with any of the optional measurement columns (module docstring).

    A file without those columns reads exactly as :func:`read_bearings`. Frequencies,
    ATB and own-ship velocities go into each contact's :class:`Bearings`; ranges become
    range support values.

    Raises
    ------
    InputError
        As :func:`read_bearings`; values of the optional columns out of range, a sigma
        without its measurement, a row without any measurement, a frequency or ATB before
        the contact's first bearing.
    """
    d = defaults or MeasurementDefaults()
    p = str(path)
    if not _has_extras(path):
        return TMAInput(read_bearings(path, d.bearing), {})
    tab = read_csv_table(
        path,
        required=["time_s", "observer_x_m", "observer_y_m"],
        optional=["contact", "sigma_deg", "bearing_deg", *EXTRA_COLUMNS],
        text=["contact", "tonal"],
    )
    if "bearing_deg" not in tab:
        cols = describe_header(list(tab.columns))
        raise InputError(f"{p}, line 1: missing required column bearing_deg (have {cols})")
    _check_extras(tab, p)
    b = tab["bearing_deg"]
    has_b = ~np.isnan(b)
    _bad_row(tab, p, has_b & ((b < 0) | (b >= 360)), "bearing_deg is outside [0, 360)", b)
    any_m = has_b.copy()
    for c in ("frequency_hz", "atb_deg", "range_m"):
        any_m |= ~np.isnan(_column(tab, c))
    _bad_row(tab, p, ~any_m, "the row holds no measurement (bearing, frequency, ATB or range)")
    sig = _column(tab, "sigma_deg")
    _bad_row(tab, p, (sig <= 0) | (sig >= LIMITS["sigma_deg"]),
             "sigma_deg must be in (0, 180) degrees")  # fmt: skip
    _bad_row(tab, p, ~np.isnan(sig) & ~has_b, "sigma_deg is given without a bearing")
    _check_abs(tab, p, "time_s", LIMITS["time_s"], "s")
    for c in ("observer_x_m", "observer_y_m"):
        _check_abs(tab, p, c, LIMITS["position_m"], "m")
    cid = _contacts(tab, p)
    tab.columns["contact"] = cid
    check_times(tab, "time_s", group="contact", strict=False)
    check_times(tab.subset(has_b), "time_s", group="contact", strict=True)
    contacts: dict[str, Bearings] = {}
    support: dict[str, list[SupportValue]] = {}
    for c in dict.fromkeys(cid.tolist()):
        m = cid == c
        mb = m & has_b
        if mb.sum() < 2:
            raise InputError(
                f"{p}, line {tab.lines[m][0]}: contact {c!r} has {int(mb.sum())} bearing(s); "
                "TMA needs at least 2"
            )
        first = float(tab["time_s"][mb][0])
        _bad_row(tab, p, m & (tab["time_s"] < first),
                 f"a measurement before the first bearing of contact {c!r} ({first:g} s); "
                 "the solution's reference time is the first bearing")  # fmt: skip
        fr, ab, ranges = _contact_extras(tab, p, m, d)
        s = sig[mb]
        contacts[c] = Bearings(
            tab["time_s"][mb], np.asarray(deg2rad(b[mb])),
            np.stack([tab["observer_x_m"][mb], tab["observer_y_m"][mb]], axis=1),
            np.where(np.isnan(s), d.bearing, deg2rad(s)), fr, ab,
        )  # fmt: skip
        if ranges:
            support[c] = ranges
    return TMAInput(contacts, support)


def parse_tonal_values(
    items: Sequence[str], option: str, unit: str, allow_default: bool = False
) -> tuple[float | None, dict[str, float]]:
    """Parse ``TONAL=VALUE`` options (``VALUE`` alone for every tonal when
    ``allow_default``): the value for every tonal (or None) and the values per tonal.

    Raises
    ------
    InputError
        A malformed item, a value that is not a finite positive number, a tonal given twice.
    """
    default: float | None = None
    out: dict[str, float] = {}
    for item in items:
        tonal, sep, text = item.rpartition("=")
        tonal = tonal.strip()
        if not sep and not allow_default:
            raise InputError(f"{option}: {item!r} is not TONAL={unit.upper()}")
        try:
            v = float(text)
        except ValueError:
            raise InputError(f"{option}: {text.strip()!r} is not a number of {unit}") from None
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{option}: {item!r} must be a positive number of {unit}")
        if not sep:
            default = v
        elif not tonal or tonal in out:
            raise InputError(f"{option}: {item!r} names no tonal or a tonal given twice")
        else:
            out[tonal] = v
    return default, out


#: the ``seatrack tma`` option of each value :func:`measurement_defaults` checks
OPTION_NAMES: dict[str, str] = {
    "sigma_deg": "--sigma-deg",
    "sound_speed_mps": "--sound-speed",
    "atb_sigma_deg": "--atb-sigma-deg",
    "range_sigma_m": "--range-sigma-m",
    "frequency_sigma_hz": "--frequency-sigma",
}


def measurement_defaults(
    sigma_deg: float,
    frequency_sigma: Sequence[str],
    atb_sigma_deg: float,
    range_sigma_m: float,
    sound_speed: float = 1500.0,
    names: Mapping[str, str] | None = None,
) -> MeasurementDefaults:
    """The sigmas of ``seatrack tma`` options, validated (degrees, Hz, metres in; SI and
    radians out). ``frequency_sigma`` holds ``HZ`` (every tonal) and ``TONAL=HZ`` items
    (default 0.1 Hz); ``sound_speed`` (m/s) is only checked. ``names`` maps ``sigma_deg``,
    ``sound_speed_mps``, ``atb_sigma_deg``, ``range_sigma_m`` and ``frequency_sigma_hz``
    to the name a message gives the value (default: the command-line options).

    Raises
    ------
    InputError
        A value out of range, naming its option (or its name in ``names``).
    """
    name = {**OPTION_NAMES, **(names or {})}
    checks = ((name["sigma_deg"], sigma_deg, "degrees", 0.0, 180.0),
              (name["sound_speed_mps"], sound_speed, "m/s", 100.0, 10_000.0),
              (name["atb_sigma_deg"], atb_sigma_deg, "degrees", 0.0, 180.0),
              (name["range_sigma_m"], range_sigma_m, "metres", 0.0, 1e8))  # fmt: skip
    for label, v, unit, lo, hi in checks:
        if not (math.isfinite(v) and lo < v < hi):
            raise InputError(f"{label} must be a number of {unit} in ({lo:g}, {hi:g}), got {v}")
    fdefault, fsig = parse_tonal_values(frequency_sigma, name["frequency_sigma_hz"], "Hz", True)
    return MeasurementDefaults(
        math.radians(sigma_deg), 0.1 if fdefault is None else fdefault, fsig,
        math.radians(atb_sigma_deg), float(range_sigma_m),
    )  # fmt: skip


def apply_base_frequencies(
    contacts: Mapping[str, Bearings], base: Mapping[str, float]
) -> dict[str, Bearings]:
    """Contacts with the given base frequencies (Hz, by tonal id) fixed.

    Raises
    ------
    InputError
        A tonal that no contact's frequencies name.
    """
    known = {
        k for b in contacts.values() if b.frequencies is not None for k in b.frequencies.tonals
    }
    unknown = sorted(set(base) - known)
    if unknown:
        raise InputError(
            f"--base-frequency: tonal(s) {', '.join(unknown)} not in the input "
            f"(tonals: {', '.join(sorted(known)) or 'none'})"
        )
    out = {}
    for cid, b in contacts.items():
        fr = b.frequencies
        if fr is not None:
            mine = {k: v for k, v in base.items() if k in fr.tonals}
            fr = replace(fr, base_frequency={**fr.base_frequency, **mine})
        out[cid] = replace(b, frequencies=fr)
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
    ``warnings``; ``leg_estimates`` (per leg: start, end, the time of its last bearing and
    the range, course, speed there with 1-sigma); ``base_frequencies`` (per tonal: ``f0_hz``,
    ``sigma_f0_hz``, ``given``; ``null`` when not determined); ``sound_speed_mps``;
    ``residuals`` per measurement kind (``bearing_deg``, ``support``, ``frequency_hz``,
    ``atb_deg``); ``nis`` per kind (sum of squared normalised residuals, rows, per row);
    ``determined`` (which operator values and base frequencies the data determine).
    Unless the solution is observable *and* converged every range-dependent number
    (state, covariance, operator values) is ``null``.
    """
    ok = sol.valid
    B = sol.state.reshape(-1, 2)
    L = sol.last
    zf = L.z_factor
    order = ["x_m", "y_m"] + [f"{c}{j}_mps" for j in range(B.shape[0] - 1) for c in ("vx", "vy")]

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
        **_core(sol, ok, B, order, last),
        **_extras(sol, ok),
    }


def _leg_dict(start: float, end: float | None, e: Any, ok: bool) -> dict[str, Any]:
    def v(x: float) -> float | None:
        return _num(x) if ok else None

    return {
        "start_s": start,
        "end_s": end,
        "at_s": e.time,
        "range_m": v(e.range),
        "sigma_range_m": v(e.sigma_range),
        "course_deg": v(bearing_rad_to_deg(e.course)),
        "sigma_course_deg": v(math.degrees(e.sigma_course)),
        "speed_mps": v(e.speed),
        "sigma_speed_mps": v(e.sigma_speed),
    }


def _extras(sol: TMASolution, ok: bool) -> dict[str, Any]:
    """RESULT.json fields of the measurements beside bearings (see :func:`solution_to_dict`)."""
    ends = [float(x) for x in sol.starts[1:]] + [None]
    freqs = []
    for k, tonal in enumerate(sol.tonals):
        fixed = bool(sol.base_frequency_fixed[k])
        det = fixed or sol.determined.get(f"f0:{tonal}", False)
        freqs.append(
            {
                "tonal": tonal,
                "f0_hz": _num(sol.base_frequency[k]) if det else None,
                "sigma_f0_hz": _num(sol.sigma_base_frequency[k]) if det else None,
                "given": fixed,
            }
        )
    res = {
        "bearing_deg": np.degrees(sol.residuals),
        "support": sol.support_residuals,
        "frequency_hz": sol.frequency_residuals,
        "atb_deg": np.degrees(sol.bow_angle_residuals),
    }
    kinds = {"bearing_deg": "bearing", "support": "support", "frequency_hz": "frequency",
             "atb_deg": "atb"}  # fmt: skip
    return {
        "leg_estimates": [
            _leg_dict(float(s), ends[j], e, ok)
            for j, (s, e) in enumerate(zip(sol.starts, sol.leg_estimates, strict=True))
        ],
        "base_frequencies": freqs,
        "sound_speed_mps": sol.sound_speed,
        "residuals": {k: [_num(x) for x in v] for k, v in res.items() if kinds[k] in sol.nis},
        "nis": {
            k: {"sum": _num(q), "rows": m, "per_row": _num(q / m)} for k, (q, m) in sol.nis.items()
        },
        "determined": dict(sol.determined),
    }


def _core(
    sol: TMASolution, ok: bool, B: np.ndarray, order: list[str], last: dict[str, Any]
) -> dict[str, Any]:
    def val(x: float) -> float | None:
        return _num(x) if ok else None

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
        + "".join(
            f", f0 {k} {f:.3f} +/- {sf:.3f} Hz" + (" (given)" if fixed else "")
            for k, f, sf, fixed in zip(
                s.tonals,
                s.base_frequency,
                s.sigma_base_frequency,
                s.base_frequency_fixed,
                strict=True,
            )
        )
    )
