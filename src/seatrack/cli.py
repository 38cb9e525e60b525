"""The ``seatrack`` command line: one command, one sub-command per job.

Sub-commands live in :mod:`seatrack.commands` (one module each, with a ``register(app)``
function) so the CLI grows without one file for everything. Heavy imports happen inside
the commands, keeping ``seatrack --help`` fast.

User errors (:class:`seatrack.io.table.InputError`, ``ValueError`` from configuration)
are printed as one ``error: ...`` line on standard error with exit status 2 -- never a
traceback.
"""

from __future__ import annotations

import importlib
import sys

import typer

from seatrack.io.atomic import OutputError
from seatrack.io.table import InputError

#: sub-command modules, in the order ``--help`` lists them
COMMAND_MODULES = [
    "seatrack.commands.demo",
    "seatrack.commands.simulate",
    "seatrack.commands.evaluate",
    "seatrack.commands.tma",
    "seatrack.commands.track",
    "seatrack.commands.navigate",
    "seatrack.commands.ais",
]

app = typer.Typer(
    name="seatrack",
    help="Maritime and radar target tracking and navigation (x East, y North; degrees and "
    "knots at the edges, SI inside).",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)


@app.callback()
def _root() -> None:
    """Maritime and radar target tracking and navigation."""


def _register() -> None:
    for name in COMMAND_MODULES:
        try:
            mod = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # command not built yet
                continue
            raise
        mod.register(app)


_register()


def main() -> None:
    """Entry point of the ``seatrack`` console script."""
    try:
        app()
    except (InputError, OutputError, ValueError, FileNotFoundError) as exc:
        typer.echo(f"error: {exc}", err=True)
        sys.exit(2)


if __name__ == "__main__":  # pragma: no cover
    main()
