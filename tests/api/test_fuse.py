"""``seatrack.api.fuse.fuse``: the three tables of a simulated scene."""

from __future__ import annotations

from pathlib import Path

import pytest

from fusion_samples import write_scene
from seatrack.api.fuse import TABLES
from seatrack.api.fuse import fuse


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    return write_scene(tmp_path_factory.mktemp("fuse"))


def test_fuse_returns_the_three_tables(files) -> None:
    ais, plots, toml = files
    out = fuse(ais, plots, toml)
    assert list(out) == list(TABLES)
    r = out["radar_tracks"]
    for col in ("track", "time_s", "lat_deg", "lon_deg", "mmsi", "identity_prob", "class"):
        assert col in r.columns
    assert set(r["class"]) <= {"ais", "dark", "unknown"}
    named = r[r["class"] == "ais"]
    assert set(named["mmsi"]) == {"219000001", "219000002"}
    assert (r[r["class"] == "dark"]["mmsi"] == "").all() and (r["class"] == "dark").sum() > 50
    v = out["ais_vessels"]
    assert {"vessel", "time_s", "covered", "track", "not_seen"} <= set(v.columns)
    assert not v["not_seen"].any()
    a = out["ais_reports"]
    assert {"line", "gap", "jump", "identity_conflict"} <= set(a.columns)
    assert a["line"].min() == 2


def test_fuse_takes_tables_as_well_as_files(files) -> None:
    """The same scene given as pandas DataFrames gives the same radar tracks."""
    import pandas as pd

    ais, plots, toml = files
    a = fuse(ais, plots, toml)["radar_tracks"]
    b = fuse(pd.read_csv(ais, dtype={"mmsi": str}), pd.read_csv(plots), toml)["radar_tracks"]
    pd.testing.assert_frame_equal(a, b)


def test_association_chooses_the_design(files) -> None:
    """``association="measurement"`` (the AIS reports update the radar tracks) gives the
    same tables with other radar positions; an unknown design is a ConfigError."""
    from seatrack.config import ConfigError

    ais, plots, toml = files
    a = fuse(ais, plots, toml)["radar_tracks"]
    b = fuse(ais, plots, toml, association="measurement")["radar_tracks"]
    assert list(a.columns) == list(b.columns)
    assert set(b[b["class"] == "ais"]["mmsi"]) == {"219000001", "219000002"}
    assert not a["x_m"].equals(b["x_m"])
    with pytest.raises(ConfigError, match="association"):
        fuse(ais, plots, toml, association="plots")
