"""The worked example of ``docs/architecture.md`` ("How to add a method") runs as written:
registered, it goes through ``seatrack track``'s path and the contract's checks."""

from __future__ import annotations

import re
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from seatrack.filters import registry
from seatrack.filters.base import COMMON_COLUMNS
from seatrack.filters.base import Plots
from seatrack.filters.base import RecursiveFilter

DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"


@pytest.fixture
def alpha_beta(monkeypatch):
    """The page's method module (its first code block, as module ``my_filters``) and its
    record (the second block: ``register``), taken out of the registry afterwards."""
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("## How to add a method") :]
    method, record = re.findall(r"```python\n(.*?)```", section, re.S)[:2]
    mod = types.ModuleType("my_filters")
    monkeypatch.setitem(sys.modules, "my_filters", mod)  # dataclasses look it up
    exec(compile(method, str(DOC), "exec"), mod.__dict__)
    monkeypatch.setattr(registry, "METHODS", dict(registry.METHODS))  # restored afterwards
    exec(compile(record, str(DOC), "exec"), {})
    return mod


def _plots(n: int = 80) -> tuple[Plots, np.ndarray]:
    rng = np.random.default_rng(5)
    t = np.arange(n) * 2.0
    pos = np.stack([3000 + 8.0 * t, 5000 - 5.0 * t], -1)
    r = np.hypot(pos[:, 0], pos[:, 1]) + rng.normal(0, 10.0, n)
    az = np.arctan2(pos[:, 0], pos[:, 1]) + rng.normal(0, 0.003, n)
    return Plots(t, r, az % (2 * np.pi), track=np.full(n, "A")), pos


def test_the_documented_record_lists_the_method(alpha_beta):
    rec = registry.METHODS["alpha-beta"]
    assert rec.load() is alpha_beta.AlphaBeta and rec.group == "baseline"
    assert "alpha-beta" in registry.list_methods().split("sources as written")[0]
    assert "`alpha-beta` | baseline | `my_filters.AlphaBeta`" in registry.methods_table()
    with pytest.raises(ValueError, match="registered already"):
        registry.register(rec)


def test_the_documented_method_runs_through_the_registry(alpha_beta):
    plots, pos = _plots()
    cfg = {"alpha": 0.4, "beta": 0.1, "sigma_range_m": 10.0, "sigma_azimuth_deg": 0.17}
    m = registry.build("alpha-beta", cfg)
    assert isinstance(m.filter, RecursiveFilter)
    cols = registry.run("alpha-beta", plots, cfg)
    assert list(cols)[: len(COMMON_COLUMNS) + 2] == [*COMMON_COLUMNS, "status", "nis"]
    assert np.isfinite(cols["x_m"]).all() and (cols["status"][1:] == "updated").all()
    err = np.hypot(cols["x_m"] - pos[:, 0], cols["y_m"] - pos[:, 1])[20:]
    raw = plots.positions() - pos
    assert np.sqrt(np.mean(err**2)) < 0.8 * np.sqrt(np.mean(np.sum(raw[20:] ** 2, -1)))
    with pytest.raises(ValueError, match="unknown key 'gamma'"):
        registry.build("alpha-beta", {"gamma": 1.0})


def test_the_documented_method_isolates_a_bad_plot(alpha_beta):
    plots, _ = _plots()
    rng = plots.range.copy()
    rng[30] = 1e308
    bad = Plots(plots.t, rng, plots.azimuth, track=plots.track)
    with np.errstate(all="raise"):
        cols = registry.run("alpha-beta", bad, {})
    assert cols["status"][30] == "rejected"
    assert np.isfinite(cols["x_m"]).all()


def test_the_documented_config_checks_its_bounds_when_built_directly(alpha_beta):
    assert alpha_beta.AlphaBetaConfig(alpha=0.3).alpha == 0.3
    with pytest.raises(ValueError, match=r"AlphaBetaConfig\.alpha: must be <= 1"):
        alpha_beta.AlphaBetaConfig(alpha=1.5)
