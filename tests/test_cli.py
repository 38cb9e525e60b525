"""The CLI entry point: -h everywhere, one error line per user error (exit 2), one line for
an internal error (exit 1, traceback on request), no numpy warnings on stderr."""

from __future__ import annotations

import contextlib
import io
import warnings

import pytest
import typer

from seatrack import cli
from seatrack.cli import COMMAND_MODULES
from seatrack.cli import app
from seatrack.cli import main


def _run(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        with pytest.raises(SystemExit) as exc:
            main(list(args))
    return int(exc.value.code or 0), out.getvalue(), err.getvalue()


COMMANDS = [
    "demo",
    "simulate",
    "evaluate",
    "tma",
    "track",
    "navigate",
    "survey",
    "ais",
    "live",
    "replay",
    "fuse",
]


def test_every_command_module_is_registered():
    names = {c.name for c in typer.main.get_command(app).commands.values()}  # type: ignore[attr-defined]
    assert set(COMMANDS) <= names and len(COMMAND_MODULES) == 10


@pytest.mark.parametrize("args", [["-h"], ["--help"], *([c, "-h"] for c in COMMANDS)])
def test_short_help_works_like_help(args):
    code, out, err = _run(*args)
    assert code == 0 and "Usage" in out and err == ""


def test_no_arguments_prints_help_and_exits_2():
    code, out, _ = _run()
    assert code == 2 and "Usage" in out


@pytest.mark.parametrize(
    ("args", "expect"),
    [
        (["nosuch"], "No such command 'nosuch'"),
        (["navigate", "--bogus"], "No such option: --bogus"),
        (["simulate"], "Missing argument 'SCENARIO'"),
        (["evaluate", "linear_cv", "--runs", "x"], "Invalid value for '--runs'"),
        (["simulate", "nosuch"], "nosuch: no such scenario file"),
        (["track", "missing.csv", "--out", "x.csv"], "missing.csv: file not found"),
    ],
)
def test_user_errors_are_one_line_exit_2(args, expect):
    code, _, err = _run(*args)
    assert code == 2, err
    assert err.startswith("error: ") and expect.lower() in err.lower()
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_os_errors_name_the_file(tmp_path, monkeypatch):
    def boom(*_a: object, **_k: object) -> None:
        raise PermissionError(13, "Permission denied", str(tmp_path / "x.csv"))

    monkeypatch.setattr(cli, "app", boom)
    code, _, err = _run("anything")
    assert code == 2 and err == f"error: {tmp_path / 'x.csv'}: Permission denied\n"


def test_an_internal_error_is_one_line_exit_1_and_the_traceback_on_request(monkeypatch):
    def bug(*_a: object, **_k: object) -> None:
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(cli, "app", bug)
    code, _, err = _run("anything")
    assert code == 1
    assert err.startswith("internal error: ZeroDivisionError: float division by zero")
    assert len(err.strip().splitlines()) == 1
    monkeypatch.setenv("SEATRACK_TRACEBACK", "1")
    with pytest.raises(ZeroDivisionError):
        main(["anything"])


def test_numpy_runtime_warnings_do_not_reach_stderr(monkeypatch):
    import numpy as np

    def noisy(*_a: object, **_k: object) -> int:
        with warnings.catch_warnings(record=True) as seen:  # keeps the active filters
            np.log(np.zeros(3))
            np.mean(np.array([]))
        return len(seen)  # the exit status: warnings that would have been shown

    monkeypatch.setattr(cli, "app", noisy)
    code, _, err = _run("anything")
    assert code == 0 and err == ""
    with warnings.catch_warnings(record=True) as seen:  # outside main() they are shown
        warnings.simplefilter("default")
        np.log(np.zeros(3))
    assert seen
