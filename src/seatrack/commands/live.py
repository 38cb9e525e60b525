"""``seatrack live``: AIS and radar streams in, a tracked picture out, in real time.

``seatrack live [--ais SOURCE]... [--plots SOURCE]... [--config radar.toml]
[--http HOST:PORT] [--nmea-out udp://HOST:PORT] [--store PATH] [--window S]``,
``SOURCE = udp://HOST:PORT | tcp://HOST:PORT | FILE`` (see docs/live.md). The process runs
until SIGINT or SIGTERM (clean shutdown, ``error: interrupted``, exit 130); when every
source is a FILE and there is no ``--http``, it ends once the files are processed and
prints the counters.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from seatrack.errors import InputError

__all__ = ["register", "run_live"]


async def run_live(opts: Any, echo: Any = print, on_start: Any = None) -> bool:
    """Run the live process; True if it was stopped by a signal. ``on_start(proc)`` is
    called once the sources and the web server are up."""
    import asyncio
    import json
    import signal

    from seatrack.live.process import LiveProcess

    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    try:
        proc = LiveProcess(opts)
    except BaseException:
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(sig)
        raise
    services: list[Any] = []
    interrupted = False
    try:
        if proc.store is not None:
            echo(f"store {proc.store.path}: {proc.restored} track(s) restored "
                 f"in {proc.restore_s:.3f} s")  # fmt: skip
        files = await proc.start()
        ports = iter(proc.udp_ports)
        for kind, sources in (("ais", opts.ais), ("plots", opts.plots)):
            for src in sources:
                name = f"udp://{src.host}:{next(ports)}" if src.kind == "udp" else src.name
                echo(f"{kind}: reading {name}")
        if opts.http is not None:
            from seatrack.live.web import start_web

            services.append(await start_web(proc, *opts.http))
            echo(f"map at http://{opts.http[0]}:{proc.http_port}/")
        from seatrack.live.process import tune_garbage_collector

        tune_garbage_collector()
        if on_start is not None:
            on_start(proc)
        only_files = all(s.kind == "file" for s in [*opts.ais, *opts.plots])
        if only_files and opts.http is None:
            waiter = asyncio.create_task(stop.wait())
            both: list[asyncio.Future[Any]] = [
                asyncio.ensure_future(asyncio.gather(*files)),
                waiter,
            ]
            await asyncio.wait(both, return_when=asyncio.FIRST_COMPLETED)
            interrupted = stop.is_set()
            waiter.cancel()
        else:
            await stop.wait()
            interrupted = True
        await asyncio.wait_for(proc.drain(), timeout=10.0)
    finally:
        for s in services:
            await s.cleanup()
        await proc.stop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(sig)
    echo(json.dumps(proc.health(), sort_keys=True))
    return interrupted


def register(app: typer.Typer) -> None:
    """Add the ``live`` sub-command to ``app``."""

    @app.command("live")
    def live(
        ais: list[str] = typer.Option(
            [], "--ais", help="AIS NMEA source: udp://HOST:PORT, tcp://HOST:PORT or a file"
        ),
        plots: list[str] = typer.Option(
            [], "--plots", help="radar plot source (CSV or ASTERIX CAT048 datagrams)"
        ),
        config: Path | None = typer.Option(None, "--config", help="radar.toml (radar plots)"),
        http: str | None = typer.Option(None, "--http", help="serve the map and API: HOST:PORT"),
        nmea_out: str | None = typer.Option(
            None, "--nmea-out", help="send radar tracks as NMEA TTM/TLL to udp://HOST:PORT"
        ),
        store: Path | None = typer.Option(
            None, "--store", help="DuckDB file: every report and track point; restart from it"
        ),
        window: float = typer.Option(
            10.0, "--window", help="out-of-order window per vessel, s (older reports: late)"
        ),
    ) -> None:
        """Track live AIS (and radar) streams: a map, a JSON API and counters."""
        from seatrack.commands.options import option_in
        from seatrack.commands.replay import udp_target
        from seatrack.live.process import LiveOptions
        from seatrack.live.sources import parse_hostport
        from seatrack.live.sources import parse_source

        option_in("--window", window, 0.0, 3600.0)
        if not ais and not plots:
            raise InputError("give at least one --ais or --plots source")
        radar = fusion = None
        if any(s.startswith("tcp://") for s in plots):
            raise InputError("--plots: udp://HOST:PORT or a file (plots do not come over TCP)")
        if plots:
            if config is None:
                raise InputError("--plots needs --config radar.toml (the radar's position)")
            from seatrack.fusion.picture import load_fusion_config

            radar, fusion = load_fusion_config(config)  # the radar and its [fusion] table
        opts = LiveOptions(
            ais=[parse_source(s, "--ais") for s in ais],
            plots=[parse_source(s, "--plots") for s in plots],
            radar=radar,
            fusion=fusion,
            http=None if http is None else parse_hostport(http, "--http"),
            window_s=window,
            store=store,
            nmea_out=None if nmea_out is None else udp_target(nmea_out, "--nmea-out"),
        )
        if store is not None:
            from seatrack.commands.options import prepare_outputs

            prepare_outputs(folders=[store.parent if str(store.parent) else Path(".")])
        import asyncio

        if asyncio.run(run_live(opts, typer.echo)):
            raise typer.Abort()
