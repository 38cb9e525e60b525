"""``seatrack track PLOTS.csv --method NAME [--config FILE] --out TRACK.csv``."""

from __future__ import annotations

import csv
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import typer

from seatrack.io.table import InputError


def load_config(path: Path | None) -> dict[str, Any]:
    """Read a method configuration TOML file (flat keys, SI units unless named)."""
    if path is None:
        return {}
    if not path.is_file():
        raise InputError(f"{path}: configuration file not found")
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not valid TOML ({exc})") from None


def write_track_csv(path: Path, rows: list[tuple[str, np.ndarray, dict[str, np.ndarray]]]) -> int:
    """Write TRACK.csv: ``track, time_s``, the common columns, then method-specific ones."""
    from seatrack.filters.registry import COMMON_COLUMNS

    extra: list[str] = []
    for _, _, cols in rows:
        extra += [c for c in cols if c not in COMMON_COLUMNS and c not in extra]
    header = ["track", "time_s", *COMMON_COLUMNS, *extra]
    n = 0
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for tid, t, cols in rows:
            for i in range(t.size):
                out: list[Any] = [tid, f"{t[i]:.6f}"]
                for c in header[2:]:
                    v = cols[c][i] if c in cols else ""
                    if isinstance(v, (float, np.floating)):
                        out.append("" if not np.isfinite(v) else f"{float(v):.6f}")
                    else:
                        out.append(v.item() if isinstance(v, np.generic) else v)
                w.writerow(out)
                n += 1
    return n


def register(app: typer.Typer) -> None:
    from seatrack.filters.registry import METHODS

    names = ", ".join(f"{k} ({v[2]})" for k, v in METHODS.items())

    @app.command("track")
    def track(
        plots_csv: Path = typer.Argument(
            ...,
            help="PLOTS.csv: track, time_s, range_m, azimuth_deg, "
            "[elevation_deg], [range_rate_mps], [sensor_x_m, sensor_y_m, sensor_z_m]",
        ),
        method: str = typer.Option("ekf", "--method", "-m", help=f"filter: {names}"),
        config: Path | None = typer.Option(None, "--config", help="TOML file of method parameters"),
        out: Path = typer.Option(..., "--out", "-o", help="TRACK.csv to write (one row per plot)"),
    ) -> None:
        """Run a tracking filter over recorded radar/sonar plots."""
        from seatrack.commands.options import prepare_outputs
        from seatrack.filters.registry import get_method
        from seatrack.io.atomic import atomic_path
        from seatrack.io.plots import read_plots

        runner = get_method(method)
        cfg = load_config(config)
        for k, v in cfg.items():  # the config layer checks ranges; here: no NaN / inf
            if isinstance(v, float) and not np.isfinite(v):
                raise InputError(f"{config}: {k} = {v} is not a finite number")
        prepare_outputs([out])
        tracks = read_plots(plots_csv)
        rows = []
        for pt in tracks:
            try:
                cols = runner(pt, cfg)
            except ValueError as exc:  # a configuration problem names the file it is in
                if config is not None and "key" in str(exc) and not isinstance(exc, InputError):
                    raise InputError(f"{config}: {exc}") from None
                raise
            bad = [c for c, v in cols.items() if len(v) != len(pt)]
            if bad:  # pragma: no cover - a method bug, not user input
                raise RuntimeError(f"method {method} returned wrong-length columns {bad}")
            rows.append((pt.track, pt.t, cols))
        with atomic_path(out) as tmp:
            n = write_track_csv(tmp, rows)
        typer.echo(f"{method}: {len(tracks)} track(s), {n} rows written to {out}")
