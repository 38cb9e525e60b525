"""Run the ``seatrack`` command line in this process (no interpreter start-up per call).

A new Python process costs ~2 s here (imports and compiled-kernel loading), so tests drive
:func:`seatrack.cli.main` directly; a few tests keep a real subprocess for what only a
process shows (the installed entry point, resource limits).
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
from pathlib import Path

from seatrack.cli import main


def seatrack(*args: object, cwd: str | Path | None = None) -> subprocess.CompletedProcess[str]:
    """``seatrack ARGS`` in-process; the exit status, stdout and stderr as a subprocess gives.

    Never raises: SystemExit from ``main`` becomes the return code.
    """
    out, err = io.StringIO(), io.StringIO()
    code = 0
    old = os.getcwd()
    argv = [str(a) for a in args]
    try:
        if cwd is not None:
            os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    finally:
        os.chdir(old)
    return subprocess.CompletedProcess(["seatrack", *argv], code, out.getvalue(), err.getvalue())
