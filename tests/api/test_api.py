"""The seatrack package: its names load on first use; importing it or the CLI is cheap."""

from __future__ import annotations

import subprocess
import sys

import pytest

import seatrack


def _loaded(module: str, roots: tuple[str, ...]) -> list[str]:
    """The modules under ``roots`` that ``import module`` loads, in a new interpreter."""
    code = (
        f"import sys, {module}\n"
        f"print(','.join(m for m in sys.modules if m.split('.')[0] in {roots!r}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return [m for m in out.stdout.strip().split(",") if m]


def test_import_seatrack_loads_no_compiled_plotting_or_web_module():
    heavy = ("numba", "matplotlib", "pandas", "scipy", "typer", "dask", "distributed", "numpy")
    assert _loaded("seatrack", heavy) == []
    assert [m for m in _loaded("seatrack", ("seatrack",)) if m != "seatrack"] == []


def test_the_command_line_loads_no_compiled_or_plotting_module_before_a_command_runs():
    assert _loaded("seatrack.cli", ("numba", "matplotlib", "pandas", "scipy", "pyarrow")) == []


def test_public_names_resolve_lazily():
    assert seatrack.__version__
    assert {"tma", "track", "ais", "navigate", "simulate", "evaluate", "Sensor"} <= set(
        dir(seatrack)
    )
    for name in ("tma", "track", "ais", "navigate", "simulate", "evaluate", "Sensor"):
        assert callable(getattr(seatrack, name))
    assert seatrack.TMAResult.__name__ == "TMAResult"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        seatrack.nothing  # noqa: B018
