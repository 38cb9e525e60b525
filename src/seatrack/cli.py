r"""The ``seatrack`` command line: one command, one sub-command per job.

Sub-commands live in :mod:`seatrack.commands` (one module each, with a ``register(app)``
function) so the CLI grows without one file for everything. Heavy imports happen inside
the commands, keeping ``seatrack --help`` fast.

:func:`main` is the only place that turns exceptions into exit statuses:

* user errors -- :class:`seatrack.errors.UserError`: a bad input file or value
  (:class:`seatrack.io.table.InputError`), a bad configuration
  (:class:`seatrack.config.ConfigError`), an output that cannot be written
  (:class:`seatrack.io.atomic.OutputError`); any other ``OSError`` (a missing or unreadable
  file); a bad command line (click's usage errors) -- print one ``error: ...`` line on
  standard error, exit 2;
* an interrupt -- SIGINT (Ctrl-C) or SIGTERM -- prints ``error: interrupted``, exit 130;
* anything else is a bug, a ``ValueError`` that is not a ``UserError`` included: one
  ``internal error: ...`` line asking for a report, exit 1 (``SEATRACK_TRACEBACK=1``
  re-raises it with its traceback). Tests that drive commands
  through :func:`main` see exit status 1, never a user-error 2, so bugs are not hidden.

Every command runs inside one :func:`seatrack.io.atomic.output_transaction`: its outputs
replace the previous files together when it succeeds, and none does when it fails or is
interrupted (their temporaries, and the command's temporary folders, are removed). Its
work is bounded by the ``--memory-limit`` / ``--time-limit`` budget
(:mod:`seatrack.io.budget`).

Numerical ``RuntimeWarning``\ s are silenced in the CLI (results with NaN are reported
as such by the commands); ``-h`` is accepted wherever ``--help`` is.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import signal
import sys
import threading
import warnings
from collections.abc import Iterator
from typing import Any

import typer

from seatrack.errors import UserError
from seatrack.io.atomic import OutputError
from seatrack.io.atomic import output_transaction
from seatrack.io.budget import budget

#: sub-command modules, in the order ``--help`` lists them
COMMAND_MODULES = [
    "seatrack.commands.demo",
    "seatrack.commands.simulate",
    "seatrack.commands.evaluate",
    "seatrack.commands.tma",
    "seatrack.commands.track",
    "seatrack.commands.navigate",
    "seatrack.commands.ais",
    "seatrack.commands.live",
    "seatrack.commands.replay",
    "seatrack.commands.fuse",
]

app = typer.Typer(
    name="seatrack",
    help="Maritime and radar target tracking and navigation (x East, y North; degrees and "
    "knots at the edges, SI inside).",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help texts: "[sensor]", "[elevation_deg]" shown as written
    add_completion=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _print_version(value: bool) -> None:
    if value:
        from importlib.metadata import version

        typer.echo(f"seatrack {version('seatrack')}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False,
        "--version",
        help="Print the version and exit.",
        callback=_print_version,
        is_eager=True,
    ),
    memory_limit: str = typer.Option(
        "1.5G",
        "--memory-limit",
        help="memory budget of a run's data (e.g. 4G); a run estimated above it is refused "
        "before it starts",
    ),
    time_limit: str = typer.Option(
        "1h", "--time-limit", help="time budget of a run (e.g. 90s, 30min, 2h), as above"
    ),
) -> None:
    """Maritime and radar target tracking and navigation."""
    from seatrack.io.budget import parse_duration
    from seatrack.io.budget import parse_size
    from seatrack.io.budget import set_budget

    set_budget(parse_size(memory_limit), parse_duration(time_limit))


def register_commands(target: typer.Typer, modules: list[str]) -> None:
    """Add the command of each module to ``target`` (a missing module is an ImportError)."""
    for name in modules:
        importlib.import_module(name).register(target)


register_commands(app, COMMAND_MODULES)


#: exit status of an interrupted command (128 + SIGINT, as a shell reports Ctrl-C)
INTERRUPTED = 130

#: exceptions that are the user's to fix (printed as ``error: ...``, exit status 2)
USER_ERRORS: tuple[type[BaseException], ...] = (UserError, OSError)


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``seatrack`` console script (always ends in ``sys.exit``)."""
    os.environ.setdefault("PYTHONWARNINGS", "ignore::RuntimeWarning")  # worker processes
    with warnings.catch_warnings(), _terminate_as_interrupt():
        warnings.simplefilter("ignore", RuntimeWarning)
        sys.exit(_run(argv))


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt(signal.Signals(signum).name)


@contextlib.contextmanager
def _terminate_as_interrupt() -> Iterator[None]:
    """SIGTERM ends a command as Ctrl-C does: the exception unwinds every ``with`` block
    (temporary files and folders removed, previous outputs kept). Only in the main thread
    of the main interpreter (elsewhere signals cannot be handled)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGTERM, _interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _run(argv: list[str] | None) -> int:
    try:
        with budget(), output_transaction():  # the run's budget ends with it
            code = app(args=argv, standalone_mode=False)
            if code == INTERRUPTED:  # typer returns an interrupt as this status
                raise KeyboardInterrupt
    except (typer.Abort, KeyboardInterrupt):
        typer.echo("error: interrupted", err=True)
        return INTERRUPTED
    except USER_ERRORS as exc:
        if isinstance(exc, BrokenPipeError):
            return 1
        typer.echo(f"error: {_one_line(_os_message(exc))}", err=True)
        return 2
    except MemoryError:
        typer.echo(
            "error: out of memory (the input or the options ask for too much work)", err=True
        )
        return 2
    except Exception as exc:
        if _is_usage_error(exc):  # click's (typer's) command-line errors
            return _usage(exc)
        if os.environ.get("SEATRACK_TRACEBACK"):
            raise
        typer.echo(
            f"internal error: {type(exc).__name__}: {_one_line(str(exc))} -- please report it "
            "(SEATRACK_TRACEBACK=1 shows the traceback)",
            err=True,
        )
        return 1
    return code if isinstance(code, int) else 0


def _is_usage_error(exc: Exception) -> bool:
    """A click ``ClickException`` (typer vendors click in recent versions: no shared class)."""
    return hasattr(exc, "format_message") and hasattr(exc, "exit_code")


def _usage(exc: Any) -> int:
    ctx = getattr(exc, "ctx", None)
    if type(exc).__name__ == "NoArgsIsHelpError" and ctx is not None:
        typer.echo(ctx.get_help())
        return 2
    hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
    typer.echo(f"error: {_one_line(exc.format_message())}{hint}", err=True)
    return 2


def _os_message(exc: BaseException) -> str:
    """``OSError`` from the standard library as ``FILE: reason``; other errors unchanged."""
    if isinstance(exc, OSError) and not isinstance(exc, OutputError) and exc.strerror:
        return f"{exc.filename}: {exc.strerror}" if exc.filename else exc.strerror
    return str(exc)


if __name__ == "__main__":  # pragma: no cover
    main()
