"""seatrack.progress: a run estimated long says so and shows progress; a short run is silent.

The command tests lower the threshold with ``SEATRACK_PROGRESS_AFTER_S=0`` (every run is
"long") and ``SEATRACK_PROGRESS_EVERY_S=0`` (a line at every update), so that the lines of
each command appear on small inputs; without them the same runs print nothing extra.
"""

from __future__ import annotations

import io
import re
import shutil

import numpy as np
import pytest

from cli_inprocess import seatrack
from seatrack.data import ais_sample
from seatrack.progress import Progress
from seatrack.progress import format_duration

START = re.compile(r"^seatrack (\w+): about [0-9.]+ (s|min|h) for [0-9,]+ [a-z ]+ \(estimate\)$")
LINE = re.compile(
    r"^seatrack (\w+): [0-9,]+/[0-9,]+ [a-z ]+, [0-9.]+ (s|min|h) elapsed, "
    r"about [0-9.]+ (s|min|h) remaining$"
)


@pytest.fixture
def long_runs(monkeypatch):
    monkeypatch.setenv("SEATRACK_PROGRESS_AFTER_S", "0")
    monkeypatch.setenv("SEATRACK_PROGRESS_EVERY_S", "0")


def _lines(err: str, command: str) -> tuple[list[str], list[str]]:
    starts = [ln for ln in err.splitlines() if START.match(ln) and f"seatrack {command}:" in ln]
    lines = [ln for ln in err.splitlines() if LINE.match(ln) and f"seatrack {command}:" in ln]
    return starts, lines


def test_a_long_estimate_prints_a_start_line_then_progress_at_most_every_interval(monkeypatch):
    monkeypatch.setenv("SEATRACK_PROGRESS_EVERY_S", "3600")
    out = io.StringIO()
    p = Progress("seatrack x", 12_400_000, "reports", 180.0, stream=out)
    assert out.getvalue() == "seatrack x: about 3 min for 12,400,000 reports (estimate)\n"
    for k in range(1000):
        p.update(k * 100)
    assert out.getvalue().count("\n") == 1  # the interval is not over: no line
    p.next_line = 0.0  # the interval is over
    p.update(3_100_000)
    last = out.getvalue().splitlines()[-1]
    assert last.startswith("seatrack x: 3,100,000/12,400,000 reports, ")
    assert LINE.match(last.replace("seatrack x", "seatrack x"))


def test_a_short_estimate_or_no_progress_prints_nothing():
    out = io.StringIO()
    p = Progress("seatrack x", 10, "runs", 59.0, stream=out)
    q = Progress("seatrack x", 10, "runs", 600.0, stream=out, shown=False)
    for k in range(10):
        p.advance()
        q.advance()
    assert out.getvalue() == ""
    assert p.done == q.done == 10


def test_remaining_time_scales_the_elapsed_time_by_the_work_left():
    p = Progress("seatrack x", 100, "runs", 500.0, shown=False)
    assert p.remaining_s(20.0) == 480.0  # nothing done: what is left of the estimate
    p.update(25)
    assert p.remaining_s(20.0) == pytest.approx(60.0)
    p.update(10, total=100, stage="read", fraction=0.5)  # a stage of the run
    assert p.remaining_s(20.0) == pytest.approx(20.0)
    assert " read, " in p.line(20.0)
    assert [format_duration(s) for s in (45, 138, 5400)] == ["45 s", "2.3 min", "1.5 h"]


def test_bad_environment_values_keep_the_defaults(monkeypatch):
    monkeypatch.setenv("SEATRACK_PROGRESS_AFTER_S", "soon")
    out = io.StringIO()
    Progress("seatrack x", 1, "runs", 59.0, stream=out)
    monkeypatch.setenv("SEATRACK_PROGRESS_AFTER_S", "-1")
    Progress("seatrack x", 1, "runs", 59.0, stream=out)
    assert out.getvalue() == ""


def test_evaluate_shows_its_estimate_and_runs(long_runs):
    res = seatrack("evaluate", "linear_cv", "--methods", "ekf", "--runs", "3")
    assert res.returncode == 0, res.stderr
    starts, lines = _lines(res.stderr, "evaluate")
    assert len(starts) == 1 and "for 3 runs" in starts[0]
    assert [ln.split()[2] for ln in lines] == ["1/3", "2/3", "3/3"]
    quiet = seatrack("evaluate", "linear_cv", "--methods", "ekf", "--runs", "3", "--no-progress")
    assert quiet.stderr == ""


def test_simulate_and_track_show_progress_when_long(long_runs, tmp_path):
    res = seatrack("simulate", "linear_cv", "--out", tmp_path)
    assert res.returncode == 0, res.stderr
    starts, lines = _lines(res.stderr, "simulate")
    assert len(starts) == 1 and lines and "samples written" in lines[-1]
    plots = tmp_path / "plots_radar.csv"
    res = seatrack("track", plots, "--method", "ekf", "--out", tmp_path / "t.csv")
    assert res.returncode == 0, res.stderr
    starts, lines = _lines(res.stderr, "track")
    n = len(plots.read_text().splitlines()) - 1
    assert len(starts) == 1 and f"for {n:,} plots" in starts[0]
    assert lines  # one per step of the batch of tracks


def test_navigate_shows_filter_cycles(long_runs, tmp_path):
    from seatrack.io.landmarks import write_map_csv
    from seatrack.io.navigation import write_echoes
    from seatrack.simulate.radar_echoes import channel_landmarks
    from seatrack.simulate.radar_echoes import river_route
    from seatrack.simulate.radar_echoes import simulate_radar

    route = river_route(1500.0, 4.0)
    sim = simulate_radar(route, channel_landmarks(route, 8, np.random.default_rng(1)),
                         np.random.default_rng(2))  # fmt: skip
    e = sim.echoes
    write_echoes(tmp_path / "e.csv", e.t, e.antenna, e.range, e.amplitude)
    write_map_csv(sim.nav_map, tmp_path / "m.csv")
    x0 = sim.truth[0]
    start = f"{x0[0]:.1f},{x0[1]:.1f},{np.degrees(x0[2]):.2f},{np.hypot(x0[3], x0[4]):.2f}"
    res = seatrack("navigate", "--map", tmp_path / "m.csv", "--echoes", tmp_path / "e.csv",
                   "--start", start, "--out", tmp_path / "nav.csv")  # fmt: skip
    assert res.returncode == 0, res.stderr
    starts, lines = _lines(res.stderr, "navigate")
    assert len(starts) == 1 and "filter cycles" in starts[0] and lines


def test_ais_shows_reports_read_and_tracked(long_runs, tmp_path):
    src = tmp_path / "in.csv"
    shutil.copy(ais_sample("dk_gothenburg_20170705_cpa.csv"), src)
    res = seatrack("ais", src, "--out", tmp_path / "tracks.csv")
    assert res.returncode == 0, res.stderr
    starts, lines = _lines(res.stderr, "ais")
    assert len(starts) == 1 and "reports (estimate)" in starts[0]
    assert any("reports read," in ln for ln in lines)
    assert "reports tracked," in lines[-1]


def test_short_runs_print_nothing_extra(tmp_path):
    res = seatrack("simulate", "linear_cv", "--out", tmp_path)
    assert res.returncode == 0 and res.stderr == ""
    res = seatrack("track", tmp_path / "plots_radar.csv", "--out", tmp_path / "t.csv")
    assert res.returncode == 0 and res.stderr == ""
    res = seatrack("evaluate", "linear_cv", "--methods", "ekf", "--runs", "2")
    assert res.returncode == 0 and res.stderr == ""
