"""Tests of seatrack.evaluate.montecarlo: per-run seeding, process-count independence,
stacking, tables."""

import functools

import numpy as np
import pytest

from seatrack.evaluate.montecarlo import Column
from seatrack.evaluate.montecarlo import format_table
from seatrack.evaluate.montecarlo import monte_carlo
from seatrack.evaluate.montecarlo import rich_table
from seatrack.evaluate.montecarlo import run_seeds
from seatrack.progress import Progress


def draw(rng, run, size=3):
    return {"x": rng.standard_normal(size), "run": np.array(run), "u": rng.random()}


def test_run_i_uses_spawned_seed_sequence():
    res = monte_carlo(draw, 5, seed=42)
    for i in range(5):
        rng = np.random.default_rng(np.random.SeedSequence(42).spawn(5)[i])
        np.testing.assert_array_equal(res["x"][i], rng.standard_normal(3))
    np.testing.assert_array_equal(res["run"], np.arange(5))
    assert res["x"].shape == (5, 3) and res["u"].shape == (5,)
    assert res.n_runs == 5 and res.seed == 42 and set(res.keys()) == {"x", "run", "u"}


def test_reproducible_and_independent_of_process_count():
    a = monte_carlo(draw, 8, seed=7, processes=1)
    b = monte_carlo(draw, 8, seed=7, processes=2)
    c = monte_carlo(draw, 8, seed=7, processes=1)
    for k in ("x", "run", "u"):
        np.testing.assert_array_equal(a[k], b[k])
        np.testing.assert_array_equal(a[k], c[k])
    d = monte_carlo(draw, 8, seed=8)
    assert not np.array_equal(a["x"], d["x"])
    # runs are independent streams: no two runs share their numbers
    assert len({tuple(r) for r in a["x"]}) == 8


def test_partial_functions_and_progress():
    fn = functools.partial(draw, size=2)
    bar = Progress("mc", 3, "runs", 0.0, shown=False)
    res = monte_carlo(fn, 3, seed=1, processes=2, progress=bar)
    ref = monte_carlo(fn, 3, seed=1)
    np.testing.assert_array_equal(res["x"], ref["x"])
    assert res["x"].shape == (3, 2)
    assert bar.done == 3  # told of every run


def ragged(rng, run):
    return {"x": np.zeros(run + 1)}


def test_shape_mismatch_is_a_clear_error():
    with pytest.raises(ValueError, match="different shapes"):
        monte_carlo(ragged, 3, seed=0)
    with pytest.raises(ValueError):
        monte_carlo(draw, 0, seed=0)
    with pytest.raises(TypeError, match="mapping"):
        monte_carlo(lambda rng, i: [1, 2], 2, seed=0)


def test_run_seeds_prefix_stable():
    # run i's stream does not depend on how many runs there are
    a = run_seeds(3, 4)
    b = run_seeds(3, 10)
    for i in range(4):
        assert np.random.default_rng(a[i]).random() == np.random.default_rng(b[i]).random()


def test_format_table_alignment_and_missing_values():
    rows = [{"m": "ekf", "rmse": 12.3456, "n": 3}, {"m": "imm-long", "rmse": float("nan")}]
    text = format_table(rows, ["m", Column("rmse", "RMSE m", ".2f"), ("n", "count")])
    lines = text.splitlines()
    assert lines[0].split() == ["m", "RMSE", "m", "count"]
    assert lines[2].startswith("ekf ") and "12.35" in lines[2]
    assert lines[3].split() == ["imm-long", "-", "-"]
    # numbers right-aligned: the decimal points line up with the header's right edge
    assert lines[2].index("12.35") + len("12.35") == len(lines[0].split("  count")[0])
    table = rich_table(rows, ["m", ("rmse", "RMSE")], title="t")
    assert table.row_count == 2 and len(table.columns) == 2
