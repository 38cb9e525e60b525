"""Batch bearings-only target motion analysis: the iterative filter of DE 3446658.

Spec and equations: ``docs/tma.md``. The entry points are :func:`solve` (one contact) and
:func:`solve_many` (every contact, batched by state size). The pieces live in:

* :mod:`seatrack.tma.problem` -- bearings, residuals and Jacobians (spec step 2);
* :mod:`seatrack.tma.lm` -- the damped Gauss–Newton iteration (steps 3-5);
* :mod:`seatrack.tma.start` -- the automatic start (step 1, beyond the patent);
* :mod:`seatrack.tma.result` -- covariance, the observability verdict, operator values;
* :mod:`seatrack.tma.group` -- one batch: start, refine, finalise;
* :mod:`seatrack.tma.detect` -- leg-change detection (``manoeuvres="auto"``).
"""

from __future__ import annotations

from collections.abc import Mapping
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.tma.config import TMAConfig
from seatrack.tma.detect import detect_legs
from seatrack.tma.group import Item
from seatrack.tma.group import solve_group
from seatrack.tma.legs import leg_starts
from seatrack.tma.problem import Bearings
from seatrack.tma.problem import bearing_residuals
from seatrack.tma.result import LastEstimate
from seatrack.tma.result import TMASolution
from seatrack.tma.result import observer_deviation
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = [
    "Bearings",
    "LastEstimate",
    "TMAConfig",
    "TMASolution",
    "bearing_residuals",
    "observer_deviation",
    "solve",
    "solve_many",
]


def _starts(bearings: Bearings, manoeuvres: Sequence[float] | None) -> FloatArray:
    """Leg start times; every leg must begin before the last bearing (a leg without
    bearings has an undetermined velocity -- spec: future manoeuvre limits are infinite)."""
    starts = leg_starts(float(bearings.t[0]), manoeuvres if manoeuvres is not None else ())
    if starts.size > 1 and starts[-1] >= bearings.t[-1]:
        raise ValueError(
            f"manoeuvre time {starts[-1]:g} s is not before the last bearing "
            f"({bearings.t[-1]:g} s); a leg needs bearings"
        )
    return starts


def _as_initial(initial: ArrayLike, n: int) -> FloatArray:
    b = np.asarray(initial, dtype=float).reshape(-1)
    if b.size == 4 and n > 4:  # one velocity for every leg
        b = np.concatenate([b[:2]] + [b[2:4]] * ((n - 2) // 2))
    if b.size != n:
        raise ValueError(f"initial state has {b.size} components; the model has {n}")
    if not np.all(np.isfinite(b)):
        raise ValueError("initial state must be finite")
    return b


def _sigma(sigma: float | None, cfg: TMAConfig) -> float:
    if sigma is None:
        return cfg.sigma
    if not (np.isfinite(sigma) and 0 < sigma < np.pi):
        raise ValueError(f"sigma must be a finite bearing sigma in (0, pi) rad, got {sigma}")
    return float(sigma)


def solve(
    bearings: Bearings,
    support: Sequence[SupportValue] | None = None,
    manoeuvres: Sequence[float] | str | None = None,
    sigma: float | None = None,
    initial: ArrayLike | None = None,
    config: TMAConfig | None = None,
) -> TMASolution:
    """Solve the TMA problem of one contact (spec "Algorithm").

    Parameters
    ----------
    bearings : :class:`Bearings` (radians, seconds, metres).
    support : support values (:class:`~seatrack.tma.support.SupportValue`), any number.
    manoeuvres : leg start times after the first bearing (s); ``None`` = one leg;
        ``"auto"`` = detect leg changes from the bearing residuals
        (:func:`seatrack.tma.detect.detect_legs`).
    sigma : bearing standard deviation, rad (overrides ``config.sigma``; per-bearing
        ``bearings.sigma`` takes precedence).
    initial : optional start ``(X0, Y0, Vx, Vy[, Vx1, Vy1, ...])`` at the first bearing
        time; without it the automatic start is used.
    config : :class:`TMAConfig`.
    """
    cfg = config or TMAConfig()
    sup = list(support or [])
    sig = _sigma(sigma, cfg)
    if isinstance(manoeuvres, str):
        if manoeuvres != "auto":
            raise ValueError(
                f"manoeuvres must be a list of times, None or 'auto', got {manoeuvres!r}"
            )
        return detect_legs(bearings, sup, sigma=sig, config=cfg).solution
    starts = _starts(bearings, manoeuvres)
    n = 2 + 2 * starts.size
    init = None if initial is None else _as_initial(initial, n)
    return solve_group([Item(bearings, sup, starts, init)], cfg, sig)[0]


def solve_many(
    contacts: Mapping[str, Bearings],
    support: Mapping[str, Sequence[SupportValue]] | None = None,
    manoeuvres: Sequence[float] | str | Mapping[str, Sequence[float] | str | None] | None = None,
    sigma: float | None = None,
    initial: Mapping[str, ArrayLike] | None = None,
    config: TMAConfig | None = None,
) -> dict[str, TMASolution]:
    """Solve every contact in one call; contacts with equal state size are solved as one
    vectorised batch (starts and refinement), ``"auto"`` manoeuvres contact by contact.

    ``manoeuvres`` is one value for all contacts or a mapping contact -> value (same
    meaning as in :func:`solve`).
    """
    cfg = config or TMAConfig()
    sig = _sigma(sigma, cfg)
    sup = support or {}
    unknown = set(sup) - set(contacts)
    if unknown:
        raise ValueError(f"support values for unknown contact(s): {', '.join(sorted(unknown))}")
    out: dict[str, TMASolution] = {}
    groups: dict[int, list[tuple[str, Item]]] = {}
    for cid, b in contacts.items():
        man = manoeuvres.get(cid) if isinstance(manoeuvres, Mapping) else manoeuvres
        s = list(sup.get(cid, []))
        if isinstance(man, str):
            out[cid] = solve(b, s, man, sig, None, cfg)
            continue
        try:
            starts = _starts(b, man)
        except ValueError as exc:
            raise ValueError(f"contact {cid}: {exc}") from None
        n = 2 + 2 * starts.size
        init = None if initial is None or cid not in initial else _as_initial(initial[cid], n)
        groups.setdefault(n, []).append((cid, Item(b, s, starts, init)))
    for items in groups.values():
        sols = solve_group([it for _, it in items], cfg, sig)
        for (cid, _), sol in zip(items, sols, strict=True):
            out[cid] = sol
    return {cid: out[cid] for cid in contacts}
