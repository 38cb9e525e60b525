"""``seatrack navigate`` and ``seatrack survey``: own-ship position from radar echoes of
mapped landmarks (JP H03-66630, spec ``landmark_nav.md``).

``seatrack navigate --map MAP.csv --echoes ECHOES.csv [--gyro GYRO.csv]
--start "x_m,y_m,heading_deg,speed_mps" --out NAV.csv``

``seatrack survey --map MAP.csv --echoes E1.csv [--echoes E2.csv ...] [--gyro G1.csv ...]
--start "..." [--start ...] --out MAP.csv [--drop-poor]``: one passage per ``--echoes``
(with the matching ``--gyro`` and ``--start``; a single ``--start`` serves all); the map
is corrected from the passages and written.

File formats: see :mod:`seatrack.io.navigation` and :mod:`seatrack.io.landmarks`.
"""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import typer

from seatrack.errors import InputError

__all__ = ["register", "parse_start"]


def parse_start(text: str) -> list[float]:
    """``"x_m,y_m,heading_deg,speed_mps"`` -> initial state ``[X, Y, alpha, Xdot, Ydot, 0]``
    (velocity along the heading).

    Raises
    ------
    InputError
        Not four numbers, or a value out of range (``|x|, |y| <= 1e8`` m, heading in
        [-360, 720] deg, ``|speed| <=`` :data:`seatrack.api.navigate.MAX_START_SPEED_MPS`).
    """
    from seatrack.api.navigate import OPTION_NAMES
    from seatrack.api.navigate import start_state

    parts = [p.strip() for p in text.split(",")]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        vals = []
    if len(vals) != 4 or not all(math.isfinite(v) for v in vals):
        raise InputError(
            f"--start must be 'x_m,y_m,heading_deg,speed_mps' (4 numbers), got {text!r}"
        )
    return start_state(*vals, names=OPTION_NAMES)


def _origin(text: str | None) -> tuple[float, float] | None:
    from seatrack.api.navigate import OPTION_NAMES
    from seatrack.api.navigate import check_origin

    if text is None:
        return None
    try:
        lat, lon = (float(v) for v in text.split(","))
    except ValueError:
        raise InputError(f"--origin must be 'lat_deg,lon_deg', got {text!r}") from None
    return check_origin(lat, lon, names=OPTION_NAMES)


#: the navigator options of ``navigate`` and ``survey``: (parameter, type, option); the
#: first five make the :class:`NavigatorConfig` (:func:`navigator_config`, in this order)
_NAVIGATOR_OPTIONS: tuple[tuple[str, Any, Any], ...] = (
    ("antenna_period", float,
     typer.Option(2.5, "--antenna-period", help="Antenna revolution period (s).")),
    ("range_limit", float,
     typer.Option(3000.0, "--range-limit", help="Radar range used for the window (m).")),
    ("antenna_offset", float,
     typer.Option(0.0, "--antenna-offset", help="Antenna aft of the reference point (m).")),
    ("method", str, typer.Option("ekf", "--method", help="ekf (Kalman, Joseph) or srif.")),
    ("clutter_density", float,
     typer.Option(1e-5, "--clutter-density", help="False echoes per m^2 per revolution (b).")),
    ("origin", str | None,
     typer.Option(None, "--origin", help="lat_deg,lon_deg of the local frame, for maps given "
                  "in lat/lon.")),
)  # fmt: skip


def _with_navigator(command: Callable[..., None]) -> Callable[..., None]:
    """``command`` with the navigator options as its last CLI parameters: it is called with
    ``cfg``, the :class:`NavigatorConfig` made of the first five, and ``origin`` (the
    text of ``--origin``) in their place."""
    sig = inspect.signature(command)
    names = {name for name, _, _ in _NAVIGATOR_OPTIONS}
    own = [p for name, p in sig.parameters.items() if name != "cfg" and name not in names]
    extra = [
        inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=opt, annotation=tp)
        for name, tp, opt in _NAVIGATOR_OPTIONS
    ]

    @functools.wraps(command)
    def run(**kwargs: Any) -> None:
        from seatrack.api.navigate import OPTION_NAMES
        from seatrack.api.navigate import navigator_config

        values = (kwargs.pop(name) for name, _, _ in _NAVIGATOR_OPTIONS[:5])
        cfg = navigator_config(*values, names=OPTION_NAMES)
        command(cfg=cfg, **kwargs)

    run.__signature__ = sig.replace(parameters=own + extra)  # type: ignore[attr-defined]
    run.__annotations__ = command.__annotations__ | {n: tp for n, tp, _ in _NAVIGATOR_OPTIONS}
    return run


def register(app: typer.Typer) -> None:
    """Add ``navigate`` and ``survey`` to the CLI."""

    @app.command("navigate")
    @_with_navigator
    def navigate_cmd(
        map_file: Path = typer.Option(
            ..., "--map", help="MAP.csv: id,kind,x_m,y_m,orientation_deg."
        ),
        echoes: Path = typer.Option(
            ..., "--echoes", help="ECHOES.csv: time_s,antenna_deg,range_m."
        ),
        gyro: Path | None = typer.Option(None, "--gyro", help="GYRO.csv: time_s,turn_rate_dps."),
        start: str = typer.Option(
            ..., "--start", help="x_m,y_m,heading_deg,speed_mps at the first echo."
        ),
        out: Path = typer.Option(..., "--out", help="NAV.csv to write."),
        origin: str | None = None,
        cfg: Any = None,
    ) -> None:
        """Own-ship position and heading from radar echoes of mapped landmarks (JP H03-66630)."""
        from seatrack.api.navigate import run_navigation
        from seatrack.api.options import prepare_outputs
        from seatrack.io.navigation import write_nav

        x0 = parse_start(start)
        org = _origin(origin)
        prepare_outputs({"--out": out}, inputs=[map_file, echoes, gyro])
        res = run_navigation(map_file, echoes, x0, cfg, gyro, org)
        write_nav(out, res)
        typer.echo(
            f"{res.t.size} filter cycles, {res.n_updates} landmark updates "
            f"({int(res.attempts.sum())} passes served) -> {out}"
        )

    @app.command("survey")
    @_with_navigator
    def survey_cmd(
        map_file: Path = typer.Option(..., "--map", help="MAP.csv to correct."),
        echoes: list[Path] = typer.Option(
            ..., "--echoes", help="ECHOES.csv of one passage (repeat)."
        ),
        gyro: list[Path] | None = typer.Option(
            None, "--gyro", help="GYRO.csv per passage (repeat)."
        ),
        start: list[str] = typer.Option(
            ..., "--start", help="x_m,y_m,heading_deg,speed_mps (repeat or one)."
        ),
        out: Path = typer.Option(..., "--out", help="Corrected MAP.csv to write."),
        drop_poor: bool = typer.Option(
            False, "--drop-poor", help="Remove poorly visible landmarks."
        ),
        min_visibility: float = typer.Option(
            0.5, "--min-visibility", help="Flag below this hit fraction."
        ),
        origin: str | None = None,
        cfg: Any = None,
    ) -> None:
        """Correct a landmark map from recorded passages; flag poorly visible landmarks."""
        from seatrack.api.options import option_in
        from seatrack.api.options import prepare_outputs
        from seatrack.io.landmarks import read_map_csv
        from seatrack.io.landmarks import write_map_csv
        from seatrack.io.navigation import read_echoes
        from seatrack.io.navigation import read_gyro
        from seatrack.io.navigation import require_navigation
        from seatrack.navigation.navigator import navigate
        from seatrack.navigation.survey import SurveyConfig
        from seatrack.navigation.survey import survey

        option_in("--min-visibility", min_visibility, 0.0, 1.0)
        x0s = [parse_start(s) for s in start]
        org = _origin(origin)
        gy = list(gyro or [])
        if gy and len(gy) != len(echoes):
            raise InputError(f"give one --gyro per --echoes ({len(echoes)}), got {len(gy)}")
        if len(start) not in (1, len(echoes)):
            raise InputError(
                f"give one --start, or one per --echoes ({len(echoes)}), got {len(start)}"
            )
        prepare_outputs({"--out": out}, inputs=[map_file, *echoes, *gy])
        lm = read_map_csv(map_file, org)
        runs = []
        for i, e in enumerate(echoes):
            x0 = x0s[i if len(start) > 1 else 0]
            ech = read_echoes(e)
            bar = require_navigation(ech, cfg.antenna_period, cfg.steps_per_rev, "seatrack survey")
            g = read_gyro(gy[i]) if gy else None
            runs.append(navigate(lm, ech, x0, cfg, gyro=g, progress=bar))
        res = survey(lm, runs, SurveyConfig(min_visibility=min_visibility, drop_poor=drop_poor))
        write_map_csv(res.corrected, out)
        for j in range(len(lm)):
            flag = "  POORLY VISIBLE" if res.poorly_visible[j] else ""
            c = res.correction[j]
            typer.echo(
                f"{lm.ids[j]}: correction ({c[0]:+.1f}, {c[1]:+.1f}) m from {res.n_records[j]} "
                f"measurements, visibility {res.visibility[j]:.2f}{flag}"
            )
        typer.echo(f"corrected map ({len(res.corrected)} landmarks) -> {out}")
