"""``seatrack.tma``: bearings-only target motion analysis of every contact, as ``seatrack
tma``; the result holds the fields of the command's RESULT.json."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from collections.abc import Mapping
from collections.abc import Sequence
from typing import Any

from seatrack.api.inputs import Source
from seatrack.api.inputs import as_file
from seatrack.api.inputs import describe_source
from seatrack.io.table import InputError

__all__ = ["tma", "TMAResult", "check_manoeuvres", "solve"]


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
        The bearings of each contact as read.
    """

    solutions: dict[str, Any]
    bearings: dict[str, Any]

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
) -> TMAResult:
    """Bearings-only target motion analysis of every contact, as ``seatrack tma``.

    Parameters
    ----------
    bearings : path, pandas.DataFrame, pyarrow.Table or dict of arrays
        The BEARINGS columns: ``time_s``, ``bearing_deg`` (clockwise from North, [0, 360)),
        ``observer_x_m``, ``observer_y_m`` (East, North); optional ``contact`` and
        ``sigma_deg``.
    sigma_deg : float, optional
        Bearing standard deviation (degrees, in (0, 180)) where the table gives none
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

    Returns
    -------
    TMAResult
        Per contact, the fields of RESULT.json; ``.to_frame()`` one row per contact.

    Raises
    ------
    InputError
        A bad table (naming it, the line or row and the problem), a sigma outside
        (0, 180) degrees, leg changes outside the bearings.

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
    return solve(bearings, sigma_deg, config, support, manoeuvres, detect)


def solve(
    bearings: Source,
    sigma_deg: float | None = None,
    config: Any = None,
    support: Source | None = None,
    manoeuvres: Sequence[float] | None = None,
    detect: bool = True,
    names: Mapping[str, str] | None = None,
) -> TMAResult:
    """:func:`tma` with the arguments named in messages as ``names`` says (the command
    line's options: ``{"sigma_deg": "--sigma-deg", "manoeuvres": "--manoeuvres"}``)."""
    name = {"sigma_deg": "sigma_deg", "manoeuvres": "manoeuvres", **(names or {})}
    from seatrack.io.tma import read_bearings
    from seatrack.io.tma import read_support
    from seatrack.tma import TMAConfig
    from seatrack.tma import solve_many

    cfg = config if config is not None else TMAConfig()
    if sigma_deg is None:
        sigma_deg = math.degrees(cfg.sigma)
    ok = isinstance(sigma_deg, (int, float)) and math.isfinite(sigma_deg)
    if not (ok and 0 < sigma_deg < 180):
        raise InputError(
            f"{name['sigma_deg']} must be a number of degrees in (0, 180), got {sigma_deg}"
        )
    sigma = math.radians(sigma_deg)
    cfg = dataclasses.replace(cfg, sigma=sigma)
    with as_file(bearings, "bearings") as path:
        contacts = read_bearings(path, default_sigma=sigma)
    sup = {}
    if support is not None:
        with as_file(support, "support") as spath:
            sup = read_support(spath)
        unknown = sorted(set(sup) - set(contacts))
        if unknown:
            raise InputError(
                f"{describe_source(support)}: support values for contact(s) "
                f"{', '.join(unknown)} not in {describe_source(bearings)}"
            )
    man: list[float] | str | None = None if not detect else "auto"
    if manoeuvres is not None:
        man = check_manoeuvres(manoeuvres, contacts, name["manoeuvres"])
    sols = solve_many(contacts, sup, man, sigma=sigma, config=cfg)
    return TMAResult(sols, contacts)
