"""``seatrack tma BEARINGS.csv`` / ``seatrack tma SENSOR.rep [TRACKS.rep ...]``: target
motion analysis of every contact from bearings and, when given, tonal frequencies, angles
on the bow and ranges.

A shell over :func:`seatrack.api.tma.solve`. Formats: see :mod:`seatrack.io.tma`,
:mod:`seatrack.io.rep` and ``docs/formats.md``. Without ``--manoeuvres`` the target leg
changes are detected from the residuals (``--no-detect`` fits one leg). Without ``--out``
the RESULT.json object is printed to standard output. Output paths are checked before any
work and written atomically; RESULT.json is always valid JSON (``null`` for undetermined
values)."""

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
    if not out:
        raise InputError(
            f"--manoeuvres: no time in {text!r}; give T1,T2,... (s) or leave the option out"
        )
    if any(b <= a for a, b in zip(out, out[1:], strict=False)):
        raise InputError(f"--manoeuvres: times must be strictly increasing, got {text}")
    return out


def register(app: typer.Typer) -> None:
    @app.command("tma")
    def tma(
        bearings: list[Path] = typer.Argument(
            ...,
            help="BEARINGS.csv with columns time_s, bearing_deg, observer_x_m, observer_y_m; "
            "optional contact, sigma_deg, frequency_hz, frequency_sigma_hz, tonal, atb_deg, "
            "range_m. Or Debrief REP files: SENSOR.rep [TRACKS.rep ...].",
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
        sound_speed: float = typer.Option(
            1500.0, "--sound-speed", help="Speed of sound (m/s) of the frequency model."
        ),
        base_frequency: list[str] = typer.Option(
            [],
            "--base-frequency",
            help="Known base frequency TONAL=HZ (repeatable); the others are estimated.",
        ),  # fmt: skip
        frequency_sigma: list[str] = typer.Option(
            [],
            "--frequency-sigma",
            help="Frequency "
            "sigma HZ or TONAL=HZ (repeatable) where the input has none; default 0.1 Hz.",
        ),  # fmt: skip
        atb_sigma_deg: float = typer.Option(
            10.0, "--atb-sigma-deg", help="ATB sigma (deg) where the file has none."
        ),
        range_sigma_m: float = typer.Option(
            100.0, "--range-sigma-m", help="Range sigma (m) where the input has none."
        ),
        rep_out: Path | None = typer.Option(
            None, "--rep-out", help="Write the solutions as Debrief REP tracks (REP input)."
        ),
    ) -> None:
        """TMA (DE 3446658) from bearings, tonal frequencies, ATB and ranges: position, course,
        speed and base frequencies of every contact with 1-sigma / 95 % values, support
        values, multi-leg targets and an observability check."""
        from seatrack.api.tma import check_sigma_deg
        from seatrack.api.tma import solve
        from seatrack.commands.options import prepare_outputs
        from seatrack.io.atomic import atomic_write
        from seatrack.io.rep import is_rep
        from seatrack.io.tma import OPTION_NAMES
        from seatrack.io.tma import parse_tonal_values
        from seatrack.io.tma import solution_summary

        check_sigma_deg(sigma_deg, "--sigma-deg")  # before the outputs are checked
        outputs = {"--out": out, "--plot": plot, "--rep-out": rep_out}
        prepare_outputs(outputs, inputs=[*bearings, support], images=["--plot"])
        if rep_out is not None and not all(is_rep(p) for p in bearings):
            raise InputError("--rep-out needs REP input (the solution needs a geographic frame)")
        times = _parse_times(manoeuvres)
        _, base = parse_tonal_values(base_frequency, "--base-frequency", "Hz")
        names = {**OPTION_NAMES, "manoeuvres": "--manoeuvres"}
        res = solve(
            list(bearings), sigma_deg, None, support, times, not no_detect, names,
            sound_speed_mps=sound_speed, base_frequency_hz=base,
            frequency_sigma_hz=list(frequency_sigma), atb_sigma_deg=atb_sigma_deg,
            range_sigma_m=range_sigma_m,
        )  # fmt: skip
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
        if rep_out is not None:
            with atomic_write(rep_out) as fh:
                fh.write(res.to_rep())
            typer.echo(f"wrote {rep_out}")
        if plot is not None:
            from seatrack.report.tma import plot_solutions

            plot_solutions(res.bearings, sols, plot)
            if out is not None:
                typer.echo(f"wrote {plot}")
