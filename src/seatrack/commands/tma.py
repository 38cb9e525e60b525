"""``seatrack tma BEARINGS.csv``: bearings-only target motion analysis of every contact.

Formats: see :mod:`seatrack.io.tma` and ``docs/formats.md``. Without ``--manoeuvres`` the
target leg changes are detected from the bearing residuals (``--no-detect`` fits one leg).
Without ``--out`` the RESULT.json object is printed to standard output. Output paths are
checked before any work and written atomically; RESULT.json is always valid JSON (``null``
for undetermined values)."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from seatrack.errors import InputError


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
        from seatrack.api.tma import solve
        from seatrack.io.atomic import atomic_write
        from seatrack.io.atomic import check_output_path
        from seatrack.io.tma import solution_summary

        if not (math.isfinite(sigma_deg) and 0 < sigma_deg < 180):
            raise InputError(
                f"--sigma-deg must be a number of degrees in (0, 180), got {sigma_deg}"
            )
        if out is not None and plot is not None and out.resolve() == plot.resolve():
            raise InputError(f"--out and --plot name the same file {out}")
        for path in (out, plot):
            if path is not None:
                check_output_path(path)  # before any work
        times = _parse_times(manoeuvres)
        names = {"sigma_deg": "--sigma-deg", "manoeuvres": "--manoeuvres"}
        res = solve(bearings, sigma_deg, None, support, times, not no_detect, names)
        sols = res.solutions
        text = res.to_json()
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

            plot_solutions(res.bearings, sols, plot)
            if out is not None:
                typer.echo(f"wrote {plot}")
