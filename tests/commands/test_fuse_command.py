"""``seatrack fuse``: the folder of tables, and bad input named by file and line."""

from __future__ import annotations

from pathlib import Path

import pytest

from cli_inprocess import seatrack
from fusion_samples import TOML
from fusion_samples import write_scene
from seatrack.api.fuse import TABLES


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    return write_scene(tmp_path_factory.mktemp("fuse"))


def test_command_writes_the_folder(files, tmp_path: Path) -> None:
    ais, plots, toml = files
    res = seatrack("fuse", "--ais", ais, "--plots", plots, "--config", toml, "--out",
                   tmp_path / "pic")  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in (tmp_path / "pic").iterdir()) == sorted(
        f"{t}.csv" for t in TABLES
    )
    assert "dark" in res.stdout


def test_bad_plot_line_is_named(files, tmp_path: Path) -> None:
    ais, plots, toml = files
    bad = tmp_path / "bad.csv"
    lines = plots.read_text().splitlines()
    lines[3] = lines[3].split(",")[0] + ",-5,10"
    bad.write_text("\n".join(lines) + "\n")
    res = seatrack("fuse", "--ais", ais, "--plots", bad, "--config", toml, "--out", tmp_path / "o")
    assert res.returncode == 2
    assert res.stderr.strip() == f"error: {bad}, line 4: range_m must be > 0"
    assert not (tmp_path / "o" / "radar_tracks.csv").exists()


def test_bad_config_key_is_named(files, tmp_path: Path) -> None:
    ais, plots, _ = files
    toml = tmp_path / "radar.toml"
    toml.write_text(TOML + "gate = -3.0\n")
    res = seatrack(
        "fuse", "--ais", ais, "--plots", plots, "--config", toml, "--out", tmp_path / "o"
    )
    assert res.returncode == 2
    assert res.stderr.startswith(f"error: {toml}: fusion: gate") and res.stderr.count("\n") == 1
