"""Every command and its API function on the same inputs give the same values.

The command's output file is read with pandas (numbers parsed with round-trip precision,
text columns as text) and compared column by column, exactly, with the frame the API
function returns. Only the evaluate table's time per plot (a measured duration) is left
out of the comparison.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from tests.cli_inprocess import seatrack as cli

import seatrack
from seatrack.data import ais_sample

EXAMPLES = Path(__file__).parents[2] / "examples"


def _read(path: Path, text: tuple[str, ...] = ()) -> pd.DataFrame:
    """The file as text cells; every column not in ``text`` parsed with Python's float
    (correctly rounded; an empty cell is NaN)."""
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    for c in frame.columns:
        if c not in text:
            frame[c] = np.array([float(v) if v != "" else np.nan for v in frame[c]])
    return frame


def _texts(col: pd.Series) -> list[str]:
    return ["" if v is None or (isinstance(v, float) and math.isnan(v)) else str(v) for v in col]


def _same(cli_frame: pd.DataFrame, api_frame: pd.DataFrame, skip: tuple[str, ...] = ()) -> None:
    assert list(cli_frame.columns) == list(api_frame.columns)
    assert len(cli_frame) == len(api_frame) > 0
    for c in cli_frame.columns:
        if c in skip:
            continue
        a, b = cli_frame[c], api_frame[c]
        if not (pd.api.types.is_numeric_dtype(a) and pd.api.types.is_numeric_dtype(b)):
            assert _texts(a) == _texts(b), c
        else:
            x, y = a.astype("float64").to_numpy(), b.astype("float64").to_numpy()
            assert np.array_equal(x, y, equal_nan=True), c


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    out = tmp_path_factory.mktemp("sim")
    assert cli("simulate", "demo", "--out", out / "demo").returncode == 0
    assert cli("simulate", "coastal_multitarget", "--out", out / "mt").returncode == 0
    return out


def test_simulate(sim):
    for name, folder in (("demo", "demo"), ("coastal_multitarget", "mt")):
        frames = seatrack.simulate(name)
        files = sorted(p.stem for p in (sim / folder).glob("*.csv"))
        assert sorted(frames) == files
        for stem, frame in frames.items():
            _same(_read(sim / folder / f"{stem}.csv", ("track", "target", "contact")), frame)


@pytest.mark.parametrize("method", ["ekf", "imm"])
def test_track_labelled(sim, tmp_path, method):
    plots = sim / "demo" / "plots_radar.csv"
    out = tmp_path / "track.csv"
    assert cli("track", plots, "--method", method, "--out", out).returncode == 0
    _same(_read(out, ("track", "status")), seatrack.track(plots, method=method))


def test_track_unlabelled(sim, tmp_path):
    plots = sim / "mt" / "plots_radar.csv"
    out = tmp_path / "tracks.csv"
    r = cli("track", plots, "--association", "jpda", "--all-tracks", "--out", out)
    assert r.returncode == 0, r.stderr
    api = seatrack.track(plots, association="jpda", all_tracks=True)
    _same(_read(out, ("track", "status")), api)


def test_tma(tmp_path):
    out = tmp_path / "result.json"
    b, s = EXAMPLES / "tma_bearings.csv", EXAMPLES / "tma_support.csv"
    assert cli("tma", b, "--support", s, "--out", out).returncode == 0
    res = seatrack.tma(b, support=s, sigma_deg=1.0)
    assert json.loads(out.read_text()) == res.to_dict()
    assert out.read_text() == res.to_json()
    frame = res.to_frame()
    assert list(frame["contact"]) == list(res)
    for cid, row in zip(frame["contact"], frame.itertuples(), strict=True):
        entry = res.to_dict()[cid]
        for k in ("x_m", "vx_mps", "residual_rms_deg"):
            v = entry[k]
            assert (v is None and math.isnan(getattr(row, k))) or getattr(row, k) == v


def test_tma_debrief_rep(tmp_path):
    """REP input with bearings and frequencies: RESULT.json and the REP solution of the
    command equal the API's."""
    data = Path(__file__).parents[1] / "data" / "debrief"
    reps = [data / "Freq_BlueSensor.rep", data / "Freq_BlueTrack.rep"]
    out, rep = tmp_path / "result.json", tmp_path / "solution.rep"
    args = ("--sigma-deg", "0.1", "--out", out, "--rep-out", rep)
    assert cli("tma", *reps, *args).returncode == 0
    res = seatrack.tma(reps, sigma_deg=0.1)
    assert out.read_text() == res.to_json()
    assert rep.read_text() == res.to_rep()
    assert any(e["base_frequencies"] for e in res.to_dict().values())


def test_ais(tmp_path):
    src = ais_sample("us_boston_201401_trajectools.csv")
    out = tmp_path / "tracks.csv"
    assert cli("ais", src, "--out", out, "--max-speed", "40").returncode == 0
    api = seatrack.ais(src, max_speed_kn=40.0)
    _same(_read(out, ("time_utc", "outlier_reason", "reject_reason", "source")), api)


def test_evaluate(tmp_path):
    out = tmp_path / "eval.csv"
    r = cli("evaluate", "linear_cv", "-m", "ekf,imm", "-n", "2", "--csv", out, "--no-progress")
    assert r.returncode == 0, r.stderr
    api = seatrack.evaluate("linear_cv", methods="ekf,imm", runs=2)
    _same(_read(out, ("method",)), api, skip=("us_per_plot",))


@pytest.mark.parametrize("association", ["track", "measurement"])
def test_fuse(tmp_path, association):
    """``seatrack fuse --association`` and ``seatrack.fuse(association=...)``: the same three
    tables (the API's written as the command writes them, six decimals)."""
    from fusion_samples import write_scene
    from seatrack.api.fuse import TABLES

    ais, plots, toml = write_scene(tmp_path)
    out = tmp_path / "out"
    r = cli("fuse", "--ais", ais, "--plots", plots, "--config", toml, "--out", out,
            "--association", association)  # fmt: skip
    assert r.returncode == 0, r.stderr
    api = seatrack.fuse(ais, plots, toml, association=association)
    text = ("status", "mmsi", "vessel", "class", "covered", "not_seen", "gap", "jump",
            "identity_conflict")  # fmt: skip
    for name in TABLES:
        mine = tmp_path / f"api_{name}.csv"
        api[name].to_csv(mine, index=False, float_format="%.6f")
        _same(_read(out / f"{name}.csv", text), _read(mine, text))
