"""``seatrack fuse``: AIS reports and radar plots fused into one picture (docs/fusion.md)."""

from __future__ import annotations

from pathlib import Path

import typer

__all__ = ["register"]


def register(app: typer.Typer) -> None:
    """Add the ``fuse`` sub-command to ``app``."""

    @app.command("fuse")
    def fuse(
        ais: list[Path] = typer.Option(
            ...,
            "--ais",
            metavar="FILE",
            help="AIS file in any format `seatrack ais` reads (repeat for several)",
        ),
        plots: Path = typer.Option(
            ..., "--plots", help="unlabelled plot CSV: time_s (Unix time), range_m, azimuth_deg"
        ),
        config: Path = typer.Option(
            ..., "--config", help="radar.toml: site, noise, coverage, [tracker], [fusion]"
        ),
        out: Path = typer.Option(
            ...,
            "--out",
            "-o",
            help="folder to write: radar_tracks.csv, ais_vessels.csv, ais_reports.csv",
        ),  # fmt: skip
        association: str | None = typer.Option(
            None,
            "--association",
            metavar="DESIGN",
            help="track (AIS tracks associated with radar tracks) or measurement (AIS "
            "reports update the radar tracks); default: [fusion] association, else track",
        ),  # fmt: skip
    ) -> None:
        """Fuse radar and AIS: identities, dark vessels, AIS not seen, gaps, shared MMSIs."""
        from seatrack.api.fuse import TABLES
        from seatrack.api.fuse import fuse as run_fuse
        from seatrack.commands.options import prepare_outputs
        from seatrack.io.atomic import atomic_files
        from seatrack.io.table import check_input_file

        files = [out / f"{name}.csv" for name in TABLES]
        prepare_outputs(files, [out])
        for p in (*ais, plots, config):
            check_input_file(p)
        tables = run_fuse(list(ais), plots, config, association=association)
        with atomic_files(files) as tmp:
            for name, path in zip(TABLES, tmp, strict=True):
                tables[name].to_csv(path, index=False, float_format="%.6f")
        r = tables["radar_tracks"]
        v = tables["ais_vessels"]
        a = tables["ais_reports"]
        typer.echo(
            f"{r['track'].nunique()} radar tracks ({(r['class'] == 'ais').sum()} rows with "
            f"AIS, {(r['class'] == 'dark').sum()} dark), {v['vessel'].nunique()} AIS vessels "
            f"({int(v['not_seen'].sum())} rows not seen), {int(a['gap'].sum())} gaps, "
            f"{int(a['jump'].sum())} jumps, {int(a['identity_conflict'].sum())} reports in "
            f"identity conflicts; written to {out}/"
        )
