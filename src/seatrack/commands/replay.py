"""``seatrack replay FILE... --to udp://HOST:PORT [--plots-to udp://HOST:PORT]
[--speed X]``: send AIS files (NMEA logs, or CSV exports encoded as NMEA) and plot files
(PLOTS.csv or ASTERIX CAT048 ``.ast``) over UDP with their own timing times ``X``
(:mod:`seatrack.live.replay`; see docs/live.md)."""

from __future__ import annotations

from pathlib import Path

import typer

from seatrack.errors import InputError

__all__ = ["register", "udp_target"]


def udp_target(text: str, option: str) -> tuple[str, int]:
    """``udp://HOST:PORT`` -> (host, port)."""
    from seatrack.live.sources import parse_hostport

    if not text.startswith("udp://"):
        raise InputError(f"{option}: expected udp://HOST:PORT, got {text!r}")
    return parse_hostport(text[len("udp://") :], option)


def register(app: typer.Typer) -> None:
    """Add the ``replay`` sub-command to ``app``."""

    @app.command("replay")
    def replay(
        files: list[Path] = typer.Argument(..., help="AIS NMEA/CSV files, PLOTS.csv, .ast"),
        to: str = typer.Option(..., "--to", help="udp://HOST:PORT to send to"),
        plots_to: str | None = typer.Option(
            None, "--plots-to", help="udp://HOST:PORT for the plot files (default: --to)"
        ),
        speed: float = typer.Option(1.0, "--speed", help="times the files' own pace"),
    ) -> None:
        """Send recorded AIS and radar files to a live process over UDP, in their time."""
        from seatrack.commands.options import option_positive
        from seatrack.live.replay import merge_files
        from seatrack.live.replay import send_items

        option_positive("--speed", speed, 1e9)
        ais = udp_target(to, "--to")
        plots = ais if plots_to is None else udp_target(plots_to, "--plots-to")
        items = merge_files(list(files))
        span = items[-1].t - items[0].t
        typer.echo(f"replaying {len(items)} datagrams over {span / speed:.1f} s")
        n = send_items(items, {"ais": ais, "plots": plots}, speed)
        typer.echo(f"sent {n} datagrams")
