"""Hostile inputs for `seatrack track` (see hostile_inputs.py).

The command and the filters belong to another work package (being rewritten); these tests
state the contract every command meets: exit status 0 or 2, one error line, the previous
TRACK.csv intact on failure, no temporary left, and on success one row per plot whose
estimates are not silently blank.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from hostile_inputs import assert_clean
from hostile_inputs import mutated_csv
from hostile_inputs import mutated_text
from hostile_inputs import plain
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from hypothesis import Phase
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st

from seatrack.filters.registry import METHODS
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory

NO_SHRINK = (Phase.explicit, Phase.reuse, Phase.generate)
CONFIG = "q = 5.0\nsigma_range_m = 20.0\nsigma_azimuth_deg = 0.3\n"


def plots_text(n: int = 20) -> str:
    """A valid PLOTS.csv: two tracks of ``n`` 3-D plots with range rate."""
    tr = trajectory([5000, 8000, 1000], np.radians(100), 150,
                    [Leg.straight(20), Leg.turn(np.pi / 4, np.radians(3))], dt=2.0)  # fmt: skip
    m = observe(tr, None, ["range", "azimuth", "elevation", "range_rate"],
                NoiseModel([20, np.radians(0.3), np.radians(0.3), 1.0]),
                np.random.default_rng(0))  # fmt: skip
    rows = ["track,time_s,range_m,azimuth_deg,elevation_deg,range_rate_mps"]
    for tid in ("a", "b"):
        for i in range(min(n, len(m.t))):
            z = m.z[i]
            rows.append(f"{tid},{m.t[i]:g},{z[0]:.2f},{np.degrees(z[1]) % 360:.4f},"
                        f"{np.degrees(z[2]):.4f},{z[3]:.3f}")  # fmt: skip
    return "\n".join(rows) + "\n"


PLOTS = plots_text()


def _labelled(data: bytes) -> bool:
    """Whether the (mutated) header still has a ``track`` column (else the plots are
    unlabelled and the multi-target tracker runs)."""
    from seatrack.io.table import decode_text

    text, _ = decode_text(plain(data))
    lines = text.splitlines()
    head = next(csv.reader(lines[:1]), []) if lines else []
    return "track" in [h.strip() for h in head]


def _data_rows(data: bytes) -> int:
    return sum(1 for ln in plain(data).splitlines()[1:] if ln.strip(b" ,\r\n\t"))


def _run(d: Path, plots: bytes, method: str, config: bytes | None = None) -> str:
    p = d / "plots.csv"
    p.write_bytes(plots)
    out = d / "track.csv"
    out.write_bytes(b"previous\n")
    args: list[object] = ["track", p, "--method", method, "--out", out]
    if config is not None:
        c = d / "cfg.toml"
        c.write_bytes(config)
        args += ["--config", c]
    before = snapshot([out])
    res = run_cli(*args)
    assert_clean(res, before, args)
    if res.code == 0:
        with out.open(newline="") as fh:
            rows = list(csv.DictReader(fh))
        if not _labelled(plots):  # the multi-target tracker: rows of confirmed tracks
            assert {r["status"] for r in rows} <= {"confirmed", "coasting"}, args
            return res.err
        assert len(rows) == _data_rows(plots), "one TRACK.csv row per plot"
        status = [r.get("status", "") for r in rows]
        blank = [i for i, r in enumerate(rows) if r["x_m"] == "" and status[i] in ("", "ok")]
        assert not blank, f"rows {blank[:5]} have no estimate and no status\n{args}"
    return res.err


@settings(max_examples=100, deadline=None)
@given(data=st.data(), method=st.sampled_from(["ekf", "imm", "mm", "robust", "turning"]))
def test_mutated_plots(tmp_path_factory, data, method):
    _run(tmp_path_factory.mktemp("track"), data.draw(mutated_csv(PLOTS)), method)


@settings(max_examples=50, deadline=None)
@given(data=st.data(), method=st.sampled_from(sorted(METHODS)))
def test_mutated_config(tmp_path_factory, data, method):
    _run(tmp_path_factory.mktemp("trackcfg"), PLOTS.encode(), method,
         data.draw(mutated_text(CONFIG)))  # fmt: skip


@pytest.mark.parametrize("method", sorted(METHODS))
def test_one_absurd_plot_is_isolated_or_named(tmp_path, method):
    """Issue 13 item 1: range 1e308 on one plot must not blank the rest of the track."""
    lines = PLOTS.splitlines()
    cells = lines[5].split(",")
    cells[2] = "1e308"
    lines[5] = ",".join(cells)
    err = _run(tmp_path, ("\n".join(lines) + "\n").encode(), method)
    assert not err or "plots.csv, line 6" in err, err


def test_unknown_config_key_is_an_error_for_every_method(tmp_path):
    """Issue 13 item 8: a typo such as sigma_rnage_m must not be dropped silently."""
    failures = []
    for method in sorted(METHODS):
        err = _run(tmp_path, PLOTS.encode(), method, b"sigma_rnage_m = 20.0\n")
        if "sigma_rnage_m" not in err:
            failures.append(method)
    assert not failures, f"methods accepting an unknown key: {failures}"


@pytest.mark.parametrize("case", ["directory", "under_a_file", "empty"])
def test_bad_output_paths(tmp_path, case):
    f = tmp_path / "f"
    f.write_text("x")
    p = tmp_path / "plots.csv"
    p.write_text(PLOTS)
    out = {"directory": tmp_path, "under_a_file": f / "t.csv", "empty": ""}[case]
    r = run_cli("track", p, "--out", out)
    assert r.code == 2 and r.err.startswith("error: ") and "Traceback" not in r.err
    assert f.read_text() == "x"


@pytest.mark.parametrize("method", sorted(METHODS))
def test_every_numeric_key_at_its_extremes_is_a_result_or_a_clear_error(tmp_path, method):
    """Each numeric configuration key of the method at 1e308 and 1e-308: exit 0 or a one-line
    error (2), never an internal error -- squares overflowed and inverse variances underflowed
    in the initialisers before the keys had physical bounds."""
    from seatrack.filters.registry import describe_method

    keys = [
        k
        for k, default, _, _ in describe_method(method)
        if isinstance(default, int | float) and not isinstance(default, bool)
    ]
    for key in keys:
        for value in ("1e308", "1e-308"):
            err = _run(tmp_path, PLOTS.encode(), method, f"{key} = {value}\n".encode())
            assert "internal error" not in err, (key, value, err)
