"""``seatrack tma BEARINGS.csv``: bearings-only target motion analysis of every contact.

Formats: see :mod:`seatrack.io.tma` and ``docs/formats.md``. Without ``--manoeuvres`` the
target leg changes are detected from the bearing residuals (``--no-detect`` fits one leg).
Without ``--out`` the RESULT.json object is printed to standard output. Output paths are
checked before any work and written atomically; RESULT.json is always valid JSON (``null``
for undetermined values)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from seatrack.io.table import MIN_SIGMA
from seatrack.io.table import InputError

if TYPE_CHECKING:
    from seatrack.tma import Bearings


def _parse_times(text: str | None) -> list[float] | None:
    if text is None:
        return None
    out = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            v = float(part)
        except ValueError:
            raise InputError(
                f"--manoeuvres: {part!r} is not a time in seconds (use T1,T2,...)"
            ) from None
        if not math.isfinite(v):
            raise InputError(f"--manoeuvres: {part!r} is not a finite time")
        out.append(v)
    if not out:
        raise InputError(
            f"--manoeuvres: no time in {text!r}; give T1,T2,... (s) or leave the option out"
        )
    if any(b <= a for a, b in zip(out, out[1:], strict=False)):
        raise InputError(f"--manoeuvres: times must be strictly increasing, got {text}")
    return out


def _check_manoeuvres(times: list[float], contacts: Mapping[str, Bearings]) -> None:
    """Every given leg change must fall strictly inside every contact's bearings."""
    if not times:
        return
    for cid, b in contacts.items():
        if times[0] <= b.t[0]:
            raise InputError(
                f"--manoeuvres: {times[0]:g} s is not after the first bearing of "
                f"contact {cid} ({b.t[0]:g} s)"
            )
        if times[-1] >= b.t[-1]:
            raise InputError(
                f"--manoeuvres: {times[-1]:g} s is not before the last bearing of "
                f"contact {cid} ({b.t[-1]:g} s); a leg needs bearings"
            )


def register(app: typer.Typer) -> None:
    @app.command("tma")
    def tma(
        bearings: Path = typer.Argument(
            ...,
            help="BEARINGS.csv with columns time_s, bearing_deg, observer_x_m, observer_y_m; "
            "optional contact, sigma_deg.",
        ),
        support: Path | None = typer.Option(
            None,
            "--support",
            help="SUPPORT.csv with columns kind (range, speed, course), time_s, value, sigma; "
            "optional contact; observer_x_m, observer_y_m for a range.",
        ),
        manoeuvres: str | None = typer.Option(
            None,
            "--manoeuvres",
            help="Target leg-change times T1,T2,... (s); applied to every contact.",
        ),
        sigma_deg: float = typer.Option(
            1.0, "--sigma-deg", help="Bearing sigma (deg) where the file has none."
        ),
        out: Path | None = typer.Option(
            None, "--out", "-o", help="RESULT.json to write (default: stdout)."
        ),
        plot: Path | None = typer.Option(
            None, "--plot", help="PNG with tracks, ellipses and residuals."
        ),
        no_detect: bool = typer.Option(
            False, "--no-detect", help="Without --manoeuvres: fit one leg, no detection."
        ),
    ) -> None:
        """Bearings-only TMA (DE 3446658): position, course and speed of every contact with
        1-sigma / 95 % values, support values, multi-leg targets and an observability check."""
        from seatrack.commands.options import prepare_outputs
        from seatrack.io.atomic import atomic_write
        from seatrack.io.tma import read_bearings
        from seatrack.io.tma import read_support
        from seatrack.io.tma import result_json
        from seatrack.io.tma import solution_summary
        from seatrack.tma import TMAConfig
        from seatrack.tma import solve_many

        if not (math.isfinite(sigma_deg) and MIN_SIGMA <= sigma_deg < 180):
            raise InputError(
                f"--sigma-deg must be a number of degrees in [{MIN_SIGMA:g}, 180), got {sigma_deg}"
            )
        outputs = {"--out": out, "--plot": plot}
        prepare_outputs(outputs, inputs=[bearings, support], images=["--plot"])
        sigma = math.radians(sigma_deg)
        contacts = read_bearings(bearings, default_sigma=sigma)
        sup = read_support(support) if support is not None else {}
        unknown = sorted(set(sup) - set(contacts))
        if unknown:
            raise InputError(
                f"{support}: support values for contact(s) {', '.join(unknown)} not in {bearings}"
            )
        times = _parse_times(manoeuvres)
        if times is not None:
            _check_manoeuvres(times, contacts)
        man: list[float] | str | None = (
            times if times is not None else (None if no_detect else "auto")
        )
        sols = solve_many(contacts, sup, man, sigma=sigma, config=TMAConfig(sigma=sigma))
        text = result_json(sols)
        if out is not None:
            with atomic_write(out) as fh:
                fh.write(text)
            for cid, s in sols.items():
                typer.echo(solution_summary(cid, s))
                for w in s.warnings:
                    typer.echo(f"  warning: {w}")
            typer.echo(f"wrote {out}")
        else:
            typer.echo(text, nl=False)
        if plot is not None:
            from seatrack.report.tma import plot_solutions

            plot_solutions(contacts, sols, plot)
            if out is not None:
                typer.echo(f"wrote {plot}")
