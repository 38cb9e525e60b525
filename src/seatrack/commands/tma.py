"""``seatrack tma BEARINGS.csv``: bearings-only target motion analysis of every contact.

Formats: see :mod:`seatrack.tma.io`. Without ``--manoeuvres`` the target leg changes are
detected from the bearing residuals (``--no-detect`` fits one leg). Without ``--out`` the
RESULT.json object is printed to standard output.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from seatrack.io.table import InputError


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
    if any(b <= a for a, b in zip(out, out[1:], strict=False)):
        raise InputError(f"--manoeuvres: times must be strictly increasing, got {text}")
    return out


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
        from seatrack.tma.io import read_bearings, read_support, solution_to_dict
        from seatrack.tma.solver import TMAConfig, solve_many

        if not (sigma_deg > 0 and math.isfinite(sigma_deg)):
            raise InputError(f"--sigma-deg must be a positive number of degrees, got {sigma_deg}")
        from seatrack.commands.options import prepare_outputs
        from seatrack.io.atomic import atomic_path, atomic_write

        sigma = math.radians(sigma_deg)
        prepare_outputs([out, plot])
        contacts = read_bearings(bearings, default_sigma=sigma)
        sup = read_support(support) if support is not None else {}
        unknown = sorted(set(sup) - set(contacts))
        if unknown:
            raise InputError(
                f"{support}: support values for contact(s) {', '.join(unknown)} not in {bearings}"
            )
        times = _parse_times(manoeuvres)
        man: list[float] | str | None
        if times is not None:
            man = times
            for cid, b in contacts.items():
                if times and times[0] <= b.t[0]:
                    raise InputError(
                        f"--manoeuvres: {times[0]:g} s is not after the first bearing of "
                        f"contact {cid} ({b.t[0]:g} s)"
                    )
                if times and times[-1] >= b.t[-1]:
                    raise InputError(
                        f"--manoeuvres: {times[-1]:g} s is not before the last bearing of "
                        f"contact {cid} ({b.t[-1]:g} s)"
                    )
        else:
            man = None if no_detect else "auto"
        sols = solve_many(contacts, sup, man, sigma=sigma, config=TMAConfig(sigma=sigma))
        result = {cid: solution_to_dict(s) for cid, s in sols.items()}
        text = json.dumps(result, indent=2)
        if out is not None:
            with atomic_write(out) as fh:
                fh.write(text + "\n")
            for cid, s in sols.items():
                L = s.last
                if s.observable:
                    state = "converged" if s.converged else "NOT converged"
                    typer.echo(
                        f"contact {cid}: range {L.range:.0f} +/- {L.sigma_range:.0f} m, "
                        f"bearing {math.degrees(L.bearing):.1f} deg, "
                        f"course {math.degrees(L.course):.1f} +/- "
                        f"{math.degrees(L.sigma_course):.1f} deg, "
                        f"speed {L.speed:.2f} +/- {L.sigma_speed:.2f} m/s "
                        f"({s.iterations} iterations, {state})"
                    )
                else:
                    typer.echo(f"contact {cid}: NOT OBSERVABLE")
                for w in s.warnings:
                    typer.echo(f"  warning: {w}")
            typer.echo(f"wrote {out}")
        else:
            typer.echo(text)
        if plot is not None:
            from seatrack.tma.plot import plot_solutions

            with atomic_path(plot, suffix=plot.suffix or ".png") as tmp:
                plot_solutions(contacts, sols, tmp)
            if out is not None:
                typer.echo(f"wrote {plot}")
