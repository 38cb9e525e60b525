"""``seatrack.tma``: target motion analysis of every contact from bearings and, when given,
tonal frequencies, angles on the bow and ranges, as ``seatrack tma``; the result holds the
fields of the command's RESULT.json."""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Iterator
from collections.abc import Mapping
from collections.abc import Sequence
from typing import Any

from seatrack.api.inputs import Source
from seatrack.api.inputs import as_file
from seatrack.api.inputs import describe_source
from seatrack.io.table import MIN_SIGMA
from seatrack.io.table import InputError

__all__ = ["tma", "TMAResult", "check_manoeuvres", "check_sigma_deg", "solve"]


def check_sigma_deg(sigma_deg: Any, name: str = "sigma_deg") -> float:
    """The bearing sigma (degrees) when a finite number in [MIN_SIGMA, 180), else
    :class:`InputError` naming the argument ``name``."""
    ok = isinstance(sigma_deg, (int, float)) and math.isfinite(sigma_deg)
    if not (ok and MIN_SIGMA <= sigma_deg < 180):
        raise InputError(
            f"{name} must be a number of degrees in [{MIN_SIGMA:g}, 180), got {sigma_deg}"
        )
    return float(sigma_deg)


def check_manoeuvres(
    times: Sequence[float], contacts: Mapping[str, Any], name: str = "manoeuvres"
) -> list[float]:
    """The leg-change times (s) when finite, strictly increasing and strictly inside every
    contact's bearings, else :class:`InputError` naming the argument ``name``."""
    out = [float(v) for v in times]
    if not all(math.isfinite(v) for v in out):
        raise InputError(f"{name}: {out} are not all finite times")
    if any(b <= a for a, b in zip(out, out[1:], strict=False)):
        raise InputError(f"{name}: times must be strictly increasing, got {out}")
    if not out:
        return out
    for cid, b in contacts.items():
        if out[0] <= b.t[0]:
            raise InputError(
                f"{name}: {out[0]:g} s is not after the first bearing of "
                f"contact {cid} ({b.t[0]:g} s)"
            )
        if out[-1] >= b.t[-1]:
            raise InputError(
                f"{name}: {out[-1]:g} s is not before the last bearing of "
                f"contact {cid} ({b.t[-1]:g} s); a leg needs bearings"
            )
    return out


@dataclasses.dataclass(frozen=True)
class TMAResult(Mapping[str, dict[str, Any]]):
    """The TMA solution of every contact.

    A mapping contact id -> the contact's RESULT.json object (degrees and SI units,
    ``None`` where not determined): ``t0_s``, ``x_m``, ``y_m``, ``vx_mps``, ``vy_mps``
    (target at ``t0_s``, first leg), ``legs``, ``state_order``, ``covariance``, ``last``
    (time, position, range, bearing, course, speed at the last bearing with their 1-sigma
    values, confidence half-widths and ellipse), ``iterations``, ``iterations_total``,
    ``converged``, ``observable``, ``condition_number``, ``smallest_singular_value``,
    ``residual_rms_deg``, ``cost``, ``n_bearings``, ``n_support``, ``manoeuvres_s``,
    ``manoeuvres_detected``, ``warnings``.

    Attributes
    ----------
    solutions : dict of str to seatrack.tma.TMASolution
        The solver's results (SI units, radians).
    bearings : dict of str to seatrack.tma.Bearings
        The measurements of each contact as read (bearings, frequencies, ATB).
    frame : seatrack.io.rep.RepFrame or None
        The geographic frame of REP input (None for a table): what :meth:`to_rep` needs.
    """

    solutions: dict[str, Any]
    bearings: dict[str, Any]
    frame: Any = None

    def __getitem__(self, contact: str) -> dict[str, Any]:
        from seatrack.io.tma import solution_to_dict

        return solution_to_dict(self.solutions[contact])

    def __iter__(self) -> Iterator[str]:
        return iter(self.solutions)

    def __len__(self) -> int:
        return len(self.solutions)

    def to_json(self) -> str:
        """The RESULT.json text of ``seatrack tma`` (``null`` for undetermined values)."""
        from seatrack.io.tma import result_json

        return result_json(self.solutions)

    def to_rep(self) -> str:
        """The solutions as Debrief REP tracks ``TMA_<contact>`` (REP input only).

        Raises
        ------
        InputError
            The input was a table, not REP files: the solution has no geographic frame.
        """
        from seatrack.io.rep import rep_solutions_text

        if self.frame is None:
            raise InputError("REP output needs REP input (the solution needs a geographic frame)")
        return rep_solutions_text(self.solutions, self.bearings, self.frame)

    def to_dict(self) -> dict[str, Any]:
        """The RESULT.json object (``NaN`` as ``None``)."""
        import json

        out: dict[str, Any] = json.loads(self.to_json())
        return out

    def to_frame(self) -> Any:
        """One row per contact: ``contact``, the scalar fields of RESULT.json, the fields of
        ``last`` as ``last_<name>`` and its ellipse as ``last_ellipse_<name>``; the lists
        (``legs``, ``covariance``, ``manoeuvres_s``, ``warnings``, ...) as objects."""
        import pandas as pd

        rows = []
        for cid, entry in self.to_dict().items():
            row: dict[str, Any] = {"contact": cid}
            for k, v in entry.items():
                if k != "last":
                    row[k] = v
                    continue
                for lk, lv in v.items():
                    if lk == "ellipse":
                        for ek in ("semi_major_m", "semi_minor_m", "orientation_deg"):
                            row[f"last_ellipse_{ek}"] = None if lv is None else lv[ek]
                    else:
                        row[f"last_{lk}"] = lv
            rows.append(row)
        frame = pd.DataFrame(rows)
        num = [c for c in frame.columns if c.endswith(("_m", "_mps", "_deg", "_s"))]
        for c in num:
            if c not in ("manoeuvres_s",):
                frame[c] = frame[c].astype(float)
        return frame


def tma(
    bearings: Source,
    *,
    sigma_deg: float | None = None,
    config: Any = None,
    support: Source | None = None,
    manoeuvres: Sequence[float] | None = None,
    detect: bool = True,
    sound_speed_mps: float | None = None,
    base_frequency_hz: Mapping[str, float] | None = None,
    frequency_sigma_hz: float | Mapping[str, float] | None = None,
    atb_sigma_deg: float = 10.0,
    range_sigma_m: float = 100.0,
) -> TMAResult:
    """Target motion analysis of every contact, as ``seatrack tma``: bearings, and tonal
    frequencies, angles on the bow (ATB) and ranges where the input has them.

    Parameters
    ----------
    bearings : path, pandas.DataFrame, pyarrow.Table, dict of arrays, or list of paths
        The BEARINGS columns: ``time_s``, ``bearing_deg`` (clockwise from North, [0, 360)),
        ``observer_x_m``, ``observer_y_m`` (East, North); optional ``contact``,
        ``sigma_deg``, ``frequency_hz``, ``frequency_sigma_hz``, ``tonal``, ``atb_deg``,
        ``range_m`` (docs/formats.md). Or Debrief REP files (a list of paths: sensor lines
        and the host's track).
    sigma_deg : float, optional
        Bearing standard deviation (degrees, in [1e-6, 180)) where the table gives none
        (default: the sigma of ``config``, 1 degree).
    config : seatrack.tma.TMAConfig, optional
        Solver settings.
    support : path, DataFrame, pyarrow Table or dict, optional
        SUPPORT values: ``kind`` (range, speed, course), ``time_s``, ``value``, ``sigma``;
        optional ``contact``, ``observer_x_m``, ``observer_y_m``.
    manoeuvres : sequence of float, optional
        Target leg-change times (s), the same for every contact. Without them the leg
        changes are detected from the bearing residuals (``detect=False``: one leg).
    detect : bool
        Detect leg changes when ``manoeuvres`` is not given.
    sound_speed_mps : float, optional
        Speed of sound of the frequency model (m/s; default: ``config``'s, 1500).
    base_frequency_hz : mapping of str to float, optional
        Known base frequencies by tonal id (Hz); the other tonals' are estimated.
    frequency_sigma_hz : float or mapping of str to float, optional
        Frequency standard deviation (Hz) where the input gives none: one for every tonal,
        or by tonal id (default 0.1 Hz).
    atb_sigma_deg, range_sigma_m : float
        ATB (degrees) and range (m) standard deviations where the input gives none.

    Returns
    -------
    TMAResult
        Per contact, the fields of RESULT.json; ``.to_frame()`` one row per contact.

    Raises
    ------
    InputError
        A bad table (naming it, the line or row and the problem), a sigma outside
        [1e-6, 180) degrees, leg changes outside the bearings.

    Examples
    --------
    An observer on two legs and a target 10 km North, moving East at 5 m/s:

    >>> import numpy as np, seatrack
    >>> from seatrack.geometry import bearing, bearing_rad_to_deg
    >>> t = np.arange(0.0, 1201.0, 20.0)
    >>> ox = np.where(t < 600, 6.0 * t, 3600.0)
    >>> oy = np.where(t < 600, 0.0, 6.0 * (t - 600.0))
    >>> az = bearing_rad_to_deg(bearing(5.0 * t - ox, 10000.0 - oy))
    >>> res = seatrack.tma({"time_s": t, "bearing_deg": az, "observer_x_m": ox,
    ...                     "observer_y_m": oy}, sigma_deg=0.2, detect=False)
    >>> sol = res["1"]
    >>> sol["observable"], sol["converged"]
    (True, True)
    >>> bool(abs(sol["vx_mps"] - 5.0) < 0.5)
    True
    >>> list(res.to_frame()["contact"])
    ['1']
    """
    return solve(
        bearings, sigma_deg, config, support, manoeuvres, detect,
        sound_speed_mps=sound_speed_mps, base_frequency_hz=base_frequency_hz,
        frequency_sigma_hz=frequency_sigma_hz, atb_sigma_deg=atb_sigma_deg,
        range_sigma_m=range_sigma_m,
    )  # fmt: skip


def _tonal_items(value: Any) -> list[str]:
    """``--frequency-sigma`` items (``HZ``, ``TONAL=HZ``) of an API argument."""
    if value is None:
        return []
    if isinstance(value, Mapping):
        return [f"{k}={float(v)!r}" for k, v in value.items()]
    if isinstance(value, (list, tuple)):
        return [str(v) for v in value]
    return [repr(float(value))]


def _is_paths(data: Any) -> bool:
    return isinstance(data, (list, tuple)) and all(isinstance(p, (str, os.PathLike)) for p in data)


def solve(
    bearings: Source | Sequence[str | os.PathLike[str]],
    sigma_deg: float | None = None,
    config: Any = None,
    support: Source | None = None,
    manoeuvres: Sequence[float] | None = None,
    detect: bool = True,
    names: Mapping[str, str] | None = None,
    *,
    sound_speed_mps: float | None = None,
    base_frequency_hz: Mapping[str, float] | None = None,
    frequency_sigma_hz: Any = None,
    atb_sigma_deg: float = 10.0,
    range_sigma_m: float = 100.0,
) -> TMAResult:
    """:func:`tma` with the arguments named in messages as ``names`` says (the command
    line's options: ``{"sigma_deg": "--sigma-deg", "manoeuvres": "--manoeuvres"}``, and
    :data:`seatrack.io.tma.OPTION_NAMES`); an argument not in ``names`` is named as
    itself."""
    from seatrack.io.rep import read_tma_files
    from seatrack.io.tma import OPTION_NAMES
    from seatrack.io.tma import apply_base_frequencies
    from seatrack.io.tma import measurement_defaults
    from seatrack.io.tma import read_support
    from seatrack.tma import TMAConfig
    from seatrack.tma import solve_many

    name = {k: k for k in (*OPTION_NAMES, "manoeuvres")} | dict(names or {})
    cfg = config if config is not None else TMAConfig()
    if sigma_deg is None:
        sigma_deg = math.degrees(cfg.sigma)
    check_sigma_deg(sigma_deg, name["sigma_deg"])
    speed = cfg.sound_speed if sound_speed_mps is None else float(sound_speed_mps)
    defaults = measurement_defaults(
        sigma_deg, _tonal_items(frequency_sigma_hz), atb_sigma_deg, range_sigma_m, speed, name
    )
    sigma = defaults.bearing
    cfg = dataclasses.replace(cfg, sigma=sigma, sound_speed=speed)
    if _is_paths(bearings):
        data, frame = read_tma_files(list(bearings), defaults)  # type: ignore[arg-type]
    else:
        with as_file(bearings, "bearings") as path:  # type: ignore[arg-type]
            data, frame = read_tma_files([path], defaults)
    contacts = apply_base_frequencies(data.contacts, dict(base_frequency_hz or {}))
    sup = {k: list(v) for k, v in data.support.items()}
    if support is not None:
        with as_file(support, "support") as spath:
            for cid, values in read_support(spath).items():
                sup.setdefault(cid, []).extend(values)
        unknown = sorted(set(sup) - set(contacts))
        if unknown:
            source = bearings[0] if _is_paths(bearings) else bearings  # type: ignore[index]
            raise InputError(
                f"{describe_source(support)}: support values for contact(s) "
                f"{', '.join(unknown)} not in {describe_source(source)}"
            )
    man: list[float] | str | None = None if not detect else "auto"
    if manoeuvres is not None:
        man = check_manoeuvres(manoeuvres, contacts, name["manoeuvres"])
    sols = solve_many(contacts, sup, man, sigma=sigma, config=cfg)
    return TMAResult(sols, contacts, frame)
