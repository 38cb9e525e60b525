"""Seeded Monte-Carlo runner and side-by-side result tables.

Run ``i`` of ``monte_carlo(fn, n_runs, seed)`` draws from
``np.random.default_rng(np.random.SeedSequence(seed).spawn(n_runs)[i])``, so every run has
its own independent stream and the results do not depend on the number of processes or
on the order in which runs finish.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from collections.abc import Mapping
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from dataclasses import field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.compiled import compile_all
from seatrack.progress import Progress

__all__ = ["MonteCarloResult", "monte_carlo", "run_seeds", "Column", "format_table", "rich_table"]

RunFunction = Callable[[np.random.Generator, int], Mapping[str, Any]]


@dataclass(frozen=True)
class MonteCarloResult:
    """Stacked results of a Monte-Carlo experiment.

    Attributes
    ----------
    arrays : dict of name -> ndarray
        Each value returned by the run function, stacked along a new leading axis (run).
    n_runs : int
    seed : int
    elapsed_s : float
        Wall-clock time of the whole experiment (s).
    """

    arrays: dict[str, NDArray[Any]]
    n_runs: int
    seed: int
    elapsed_s: float = field(default=0.0, compare=False)

    def __getitem__(self, name: str) -> NDArray[Any]:
        return self.arrays[name]

    def __contains__(self, name: str) -> bool:
        return name in self.arrays

    def keys(self) -> list[str]:
        return list(self.arrays)


def run_seeds(seed: int, n_runs: int) -> list[np.random.SeedSequence]:
    """The independent seed sequence of each run (``SeedSequence(seed).spawn(n_runs)``)."""
    return np.random.SeedSequence(seed).spawn(n_runs)


def _one_run(fn: RunFunction, ss: np.random.SeedSequence, run: int) -> dict[str, Any]:
    out = fn(np.random.default_rng(ss), run)
    if not isinstance(out, Mapping):
        raise TypeError(
            f"run function must return a mapping of name -> array, got {type(out).__name__}"
        )
    return {k: np.asarray(v) for k, v in out.items()}


def _stack(results: list[dict[str, Any]]) -> dict[str, NDArray[Any]]:
    keys = list(results[0])
    arrays: dict[str, NDArray[Any]] = {}
    for i, r in enumerate(results):
        if list(r) != keys:
            raise ValueError(f"run {i} returned keys {sorted(r)}, run 0 returned {sorted(keys)}")
    for k in keys:
        shapes = {r[k].shape for r in results}
        if len(shapes) > 1:
            raise ValueError(
                f"value {k!r} has different shapes across runs ({sorted(shapes)}); "
                "return fixed-size arrays (pad with NaN) to stack them"
            )
        arrays[k] = np.stack([r[k] for r in results])
    return arrays


def monte_carlo(
    fn: RunFunction,
    n_runs: int,
    seed: int,
    processes: int = 1,
    progress: Progress | None = None,
) -> MonteCarloResult:
    """Run ``fn(rng, run)`` for ``run = 0 .. n_runs-1`` and stack the results.

    Parameters
    ----------
    fn : callable ``(rng: numpy.random.Generator, run: int) -> dict[str, array_like]``
        One run. Must return the same keys with the same shapes every run. With
        ``processes > 1`` it must be picklable (a module-level function or a
        :func:`functools.partial` of one).
    n_runs : int
        Number of runs (>= 1).
    seed : int
        Master seed; run ``i`` uses ``default_rng(SeedSequence(seed).spawn(n_runs)[i])``.
    processes : int
        Worker processes (:class:`concurrent.futures.ProcessPoolExecutor`); 1 runs in
        this process. Results are identical for any value.
    progress : Progress, optional
        Told of every finished run (:mod:`seatrack.progress`: lines on standard error
        when the run was estimated long).

    Returns
    -------
    MonteCarloResult
    """
    if n_runs < 1:
        raise ValueError(f"n_runs must be >= 1, got {n_runs}")
    if processes < 1:
        raise ValueError(f"processes must be >= 1, got {processes}")
    seeds = run_seeds(seed, n_runs)
    results: list[dict[str, Any] | None] = [None] * n_runs
    t0 = time.perf_counter()

    bar = progress if progress is not None else Progress.silent()
    if processes == 1:
        for i in range(n_runs):
            results[i] = _one_run(fn, seeds[i], i)
            bar.advance()
    else:
        compile_all()  # the workers must not compile the same kernels at once (numba #10128)
        with ProcessPoolExecutor(max_workers=processes) as ex:
            futures = {ex.submit(_one_run, fn, seeds[i], i): i for i in range(n_runs)}
            from concurrent.futures import as_completed

            for fut in as_completed(futures):
                results[futures[fut]] = fut.result()
                bar.advance()
    done = [r for r in results if r is not None]
    return MonteCarloResult(_stack(done), n_runs, seed, time.perf_counter() - t0)


@dataclass(frozen=True)
class Column:
    """A table column: row key, header text and a format spec for numbers (e.g. ``".3g"``)."""

    key: str
    header: str | None = None
    fmt: str = ".4g"

    @property
    def title(self) -> str:
        return self.header if self.header is not None else self.key


def _columns(columns: Sequence[str | Column | tuple[str, ...]]) -> list[Column]:
    out = []
    for c in columns:
        if isinstance(c, Column):
            out.append(c)
        elif isinstance(c, str):
            out.append(Column(c))
        else:
            out.append(Column(*c))
    return out


def _cell(value: Any, fmt: str) -> str:
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        if math.isnan(float(value)):
            return "-"
        return format(float(value), fmt)
    return str(value)


def _cells(rows: Sequence[Mapping[str, Any]], cols: list[Column]) -> list[list[str]]:
    return [[_cell(r.get(c.key), c.fmt) for c in cols] for r in rows]


def format_table(
    rows: Sequence[Mapping[str, Any]], columns: Sequence[str | Column | tuple[str, ...]]
) -> str:
    """Aligned plain-text table.

    Parameters
    ----------
    rows : sequence of mappings
        One mapping per row; missing keys and NaN print as ``-``.
    columns : sequence of str, :class:`Column` or ``(key, header[, fmt])`` tuples

    Returns
    -------
    str
        Header, a rule, one line per row; text left-aligned, numbers right-aligned.
    """
    cols = _columns(columns)
    body = _cells(rows, cols)
    widths = [max([len(c.title)] + [len(b[j]) for b in body]) for j, c in enumerate(cols)]
    numeric = [all(not isinstance(r.get(c.key), str) for r in rows) and len(rows) > 0 for c in cols]

    def line(cells: list[str]) -> str:
        parts = [
            s.rjust(w) if num else s.ljust(w)
            for s, w, num in zip(cells, widths, numeric, strict=True)
        ]
        return "  ".join(parts).rstrip()

    out = [line([c.title for c in cols]), "  ".join("-" * w for w in widths)]
    out += [line(b) for b in body]
    return "\n".join(out)


def rich_table(
    rows: Sequence[Mapping[str, Any]],
    columns: Sequence[str | Column | tuple[str, ...]],
    title: str | None = None,
) -> Any:
    """The same table as :func:`format_table` as a :class:`rich.table.Table` (for the CLI)."""
    from rich.table import Table

    cols = _columns(columns)
    table = Table(title=title)
    for c in cols:
        num = all(not isinstance(r.get(c.key), str) for r in rows)
        table.add_column(c.title, justify="right" if num else "left")
    for b in _cells(rows, cols):
        table.add_row(*b)
    return table
