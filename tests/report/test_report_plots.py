"""Tests of seatrack.report.plots (figures built headless, written as PNG)."""

import numpy as np

from seatrack.report.plots import error_figure
from seatrack.report.plots import save
from seatrack.report.plots import track_figure


def test_track_figure_lines_and_limits(tmp_path):
    t = np.linspace(0, 100, 51)
    truth = {
        "T1": np.stack([1000 + 5 * t, 2000 - 3 * t], -1),
        "T2": np.stack([-500 + 0 * t, 10 * t], -1),
    }
    est = {"ekf": [truth["T1"] + 20.0, truth["T2"] - 20.0], "imm": truth["T1"] + 5.0}
    fig = track_figure(
        truth,
        est,
        plots=truth["T1"] + 50.0,
        ownship=np.zeros((3, 2)),
        clutter=np.array([[1e6, 1e6]]),
        title="x",
    )
    ax = fig.axes[0]
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels == ["clutter", "measurements", "own-ship", "truth", "ekf", "imm"]
    # zoomed on truth and own-ship, so the far clutter point is outside the view (km)
    x0, x1 = ax.get_xlim()
    assert x1 < 10 and x0 > -10
    p = save(fig, tmp_path / "sub" / "tracks.png")
    assert p.stat().st_size > 1000 and p.read_bytes()[:4] == b"\x89PNG"


def test_error_figure(tmp_path):
    t = np.arange(10.0)
    fig = error_figure(
        t,
        {"a": np.linspace(1, 2, 10), "b": np.full(10, np.nan)},
        "m",
        bounds={"CRB": np.ones(10)},
        hlines={"lo": 0.5, "_hi": 3.0},
        logy=True,
    )
    ax = fig.axes[0]
    assert len(ax.get_lines()) == 5 and ax.get_yscale() == "log"
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels == ["a", "b", "CRB", "lo"]
    assert save(fig, tmp_path / "e.png").exists()


def test_save_is_atomic_and_refuses_bad_paths(tmp_path):
    import pytest

    from seatrack.io.atomic import OutputError

    fig = error_figure(np.arange(3.0), {"a": np.ones(3)}, "y")
    out = tmp_path / "sub" / "e.png"
    assert save(fig, out) == out and out.read_bytes()[:4] == b"\x89PNG"
    assert [p.name for p in out.parent.iterdir()] == ["e.png"]
    with pytest.raises(OutputError, match="is a directory"):
        save(fig, tmp_path / "sub")
    (tmp_path / "f").write_text("x")
    with pytest.raises(OutputError, match="is a file"):
        save(fig, tmp_path / "f" / "e.png")
    out.write_bytes(b"previous")
    with pytest.raises(ValueError, match="not supported"):
        save(fig, tmp_path / "sub" / "e.xyz")
    assert sorted(p.name for p in out.parent.iterdir()) == ["e.png"]
