"""Exit statuses of the command line: only user errors exit 2, a bug exits 1."""

from __future__ import annotations

import pytest
import typer
from tests.cli_inprocess import seatrack as cli

import seatrack
from seatrack.cli import register_commands
from seatrack.config import ConfigError
from seatrack.errors import UserError
from seatrack.io.atomic import OutputError
from seatrack.io.table import InputError


@pytest.fixture
def plots(tmp_path):
    path = tmp_path / "plots.csv"
    path.write_text("track,time_s,range_m,azimuth_deg\nA,0,1000,10\nA,2,1010,10\n")
    return path


def test_version():
    r = cli("--version")
    assert r.returncode == 0
    assert r.stdout.strip() == f"seatrack {seatrack.__version__}"


def test_user_error_types():
    assert issubclass(InputError, UserError) and issubclass(InputError, ValueError)
    assert issubclass(ConfigError, UserError) and issubclass(ConfigError, ValueError)
    assert issubclass(OutputError, UserError) and issubclass(OutputError, OSError)
    assert seatrack.UserError is UserError


def test_an_internal_value_error_is_an_internal_error(plots, tmp_path, monkeypatch):
    import seatrack.api.track as api_track

    def broken(*args, **kwargs):
        raise ValueError("operands could not be broadcast together with shapes (3,) (4,)")

    monkeypatch.setattr(api_track, "run_track", broken)
    r = cli("track", plots, "--out", tmp_path / "out.csv")
    assert r.returncode == 1
    assert r.stderr.startswith("internal error: ValueError: operands could not be broadcast")


def test_a_user_error_exits_2(plots, tmp_path, monkeypatch):
    import seatrack.api.track as api_track

    def bad_input(*args, **kwargs):
        raise InputError(f"{plots}, line 3: range_m must be > 0")

    monkeypatch.setattr(api_track, "run_track", bad_input)
    r = cli("track", plots, "--out", tmp_path / "out.csv")
    assert r.returncode == 2
    assert r.stderr == f"error: {plots}, line 3: range_m must be > 0\n"


def test_bad_inputs_of_every_kind_still_exit_2(plots, tmp_path):
    assert cli("track", plots, "--method", "nope", "--out", tmp_path / "o.csv").returncode == 2
    assert cli("track", tmp_path / "missing.csv", "--out", tmp_path / "o.csv").returncode == 2
    bad = tmp_path / "bad.toml"
    bad.write_text("q = 'abc'\n")
    r = cli("track", plots, "--config", bad, "--out", tmp_path / "o.csv")
    assert r.returncode == 2, r.stderr


def test_a_missing_command_module_fails_loudly():
    with pytest.raises(ModuleNotFoundError, match="seatrack.commands.no_such_command"):
        register_commands(typer.Typer(), ["seatrack.commands.no_such_command"])
