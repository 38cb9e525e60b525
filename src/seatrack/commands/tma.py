"""``seatrack tma BEARINGS.csv`` / ``seatrack tma SENSOR.rep [TRACKS.rep ...]``: target
motion analysis of every contact from bearings and, when given, tonal frequencies, angles
on the bow and ranges.

Formats: see :mod:`seatrack.io.tma`, :mod:`seatrack.io.rep` and ``docs/formats.md``.
Without ``--manoeuvres`` the target leg changes are detected from the residuals
(``--no-detect`` fits one leg).
Without ``--out`` the RESULT.json object is printed to standard output. Output paths are
checked before any work and written atomically; RESULT.json is always valid JSON (``null``
for undetermined values)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import typer

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


def _check_outputs(named: Mapping[str, Path | None]) -> None:
    """Output paths differ from each other and are writable (checked before any work)."""
    from seatrack.io.atomic import check_output_path

    given = [(n, p) for n, p in named.items() if p is not None]
    for i, (n1, p1) in enumerate(given):
        for n2, p2 in given[i + 1 :]:
            if p1.resolve() == p2.resolve():
                raise InputError(f"{n1} and {n2} name the same file {p1}")
    for _, path in given:
        check_output_path(path)


def register(app: typer.Typer) -> None:
    @app.command("tma")
    def tma(
        bearings: list[Path] = typer.Argument(
            ...,
            help="BEARINGS.csv with columns time_s, bearing_deg, observer_x_m, observer_y_m; "
            "optional contact, sigma_deg, frequency_hz, frequency_sigma_hz, tonal, atb_deg, "
            "atb_sigma_deg, range_m, range_sigma_m, observer_vx_mps, observer_vy_mps. Or one "
            "or several Debrief REP files (sensor lines and the host tracks' fixes).",
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
        speed and base frequencies of every contact with 1-sigma / 95 % values."""
        from seatrack.io.atomic import atomic_write
        from seatrack.io.rep import read_tma_files
        from seatrack.io.rep import rep_solutions_text
        from seatrack.io.tma import apply_base_frequencies
        from seatrack.io.tma import measurement_defaults
        from seatrack.io.tma import parse_tonal_values
        from seatrack.io.tma import read_support
        from seatrack.io.tma import result_json
        from seatrack.io.tma import solution_summary
        from seatrack.tma import TMAConfig
        from seatrack.tma import solve_many

        named = {"--out": out, "--plot": plot, "--rep-out": rep_out}
        _check_outputs(named)  # before any work
        defaults = measurement_defaults(
            sigma_deg, frequency_sigma, atb_sigma_deg, range_sigma_m, sound_speed
        )
        sigma = defaults.bearing
        _, base = parse_tonal_values(base_frequency, "--base-frequency", "Hz")
        data, frame = read_tma_files(bearings, defaults)
        if rep_out is not None and frame is None:
            raise InputError("--rep-out needs REP input (the solution needs a geographic frame)")
        contacts = apply_base_frequencies(data.contacts, base)
        sup = {k: list(v) for k, v in data.support.items()}
        for cid, values in (read_support(support) if support is not None else {}).items():
            sup.setdefault(cid, []).extend(values)
        unknown = sorted(set(sup) - set(contacts))
        if unknown:
            raise InputError(
                f"{support}: support values for contact(s) {', '.join(unknown)} not in "
                f"{bearings[0]}"
            )
        times = _parse_times(manoeuvres)
        if times is not None:
            _check_manoeuvres(times, contacts)
        man: list[float] | str | None = (
            times if times is not None else (None if no_detect else "auto")
        )
        cfg = TMAConfig(sigma=sigma, sound_speed=sound_speed)  # checked by measurement_defaults
        sols = solve_many(contacts, sup, man, sigma=sigma, config=cfg)
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
        if rep_out is not None and frame is not None:
            with atomic_write(rep_out) as fh:
                fh.write(rep_solutions_text(sols, contacts, frame))
            typer.echo(f"wrote {rep_out}")
        if plot is not None:
            from seatrack.report.tma import plot_solutions

            plot_solutions(contacts, sols, plot)
            if out is not None:
                typer.echo(f"wrote {plot}")
