"""Headless Chromium for page tests: the flags, and the skip / CI rule.

The browser tests run wherever Chromium is on PATH. Without it a test is skipped with the
install command, except under CI (``CI=true``), where a missing browser is a failure.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def chromium() -> str:
    """The Chromium executable (skip, or fail under CI, without one)."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is not None:
        return exe
    msg = (
        "headless Chromium is not on PATH; install it with `apt-get install chromium` "
        "(Debian/Ubuntu) to run the page tests"
    )
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(msg + " (required when CI=true)")
    pytest.skip(msg)


def browse(exe: str, profile: Path, url: str, *args: str) -> subprocess.CompletedProcess[str]:
    """Open ``url`` headless (a fresh profile ``profile``) with extra ``args``."""
    run = subprocess.run(
        [exe, *FLAGS, f"--user-data-dir={profile}", "--virtual-time-budget=5000", *args, url],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    return run
