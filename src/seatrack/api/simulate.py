"""``seatrack.simulate``: one seeded run of a scenario, as ``seatrack simulate``.

A scenario is a bundled name (``demo``, ``linear_cv``, ``tma_classic``,
``coastal_multitarget``), a TOML file or a dict with the keys of such a file. The run is
written to files by the command's writers and read back, so the frames hold exactly the
values of the command's files.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.api.inputs import read_frame
from seatrack.api.options import option_in
from seatrack.api.options import prepare_outputs
from seatrack.progress import Progress

__all__ = [
    "simulate",
    "load",
    "simulate_to_folder",
    "simulation_files",
    "write_simulation",
    "multitarget_files",
    "write_multitarget",
    "seeded_rng",
    "TEXT_COLUMNS",
]

#: columns of the simulation files read as text
TEXT_COLUMNS = ("track", "target", "contact")


def load(scenario: str | os.PathLike[str] | Mapping[str, Any]) -> Any:
    """The :class:`~seatrack.simulate.scenarios.Scenario` of a bundled name, a TOML file or
    a dict with the keys of a scenario file (checked as a file is)."""
    from seatrack.simulate.scenarios import load_scenario
    from seatrack.simulate.scenarios import parse_scenario
    from seatrack.simulate.scenarios import resolve_scenario

    if isinstance(scenario, Mapping):
        return parse_scenario(scenario, "scenario (dict)")
    return load_scenario(resolve_scenario(os.fspath(scenario)))


def simulation_files(scenario: Any, out: Path) -> list[Path]:
    """The files :func:`write_simulation` writes for ``scenario`` into folder ``out``.

    ``plots_<sensor>.csv`` (PLOTS format, one track per target) for each active sensor,
    ``clutter_<sensor>.csv`` for each active sensor with a clutter density (possibly with
    no rows), ``bearings_<sensor>.csv`` for each passive sonar, ``truth.csv`` (all
    targets at the truth interval) and ``ownship.csv``.
    """
    files = []
    for s in scenario.sensors:
        if s.is_passive:
            files.append(out / f"bearings_{s.name}.csv")
        else:
            files.append(out / f"plots_{s.name}.csv")
            if s.clutter_density > 0:
                files.append(out / f"clutter_{s.name}.csv")
    return [*files, out / "truth.csv", out / "ownship.csv"]


def write_simulation(
    sim: Any, out: Path, progress: Progress | None = None
) -> list[tuple[Path, int]]:
    """Write one :class:`~seatrack.simulate.scenarios.SimulationResult` to ``out``.

    The files of :func:`simulation_files` are written together: if one fails, none of
    them replaces its previous version (:func:`seatrack.io.atomic.atomic_files`).
    Returns (path, rows) for each file; ``progress`` is told of the rows written (one per
    sample) after each file.
    """
    from seatrack.io.atomic import atomic_files
    from seatrack.simulate.files import write_bearings
    from seatrack.simulate.files import write_clutter
    from seatrack.simulate.files import write_plots
    from seatrack.simulate.files import write_truth

    paths = simulation_files(sim.scenario, out)
    prepare_outputs(paths, [out])
    names = sim.scenario.target_names
    rows: list[int] = []
    bar = progress if progress is not None else Progress.silent()

    def written(n: int) -> None:
        rows.append(n)
        done = sum(rows)
        share = SIMULATED_SHARE + (1 - SIMULATED_SHARE) * min(done / max(bar.total, 1), 1)
        bar.update(done, stage="written", fraction=share)

    with atomic_files(paths) as tmp:
        it = iter(tmp)
        for sd in sim.sensors:
            s = sd.sensor
            meas = zip(names, sd.measurements, strict=True)
            if s.is_passive:
                written(write_bearings(next(it), meas, float(np.degrees(s.sigma[0]))))
                continue
            written(write_plots(next(it), meas))
            if s.clutter_density > 0:
                args = (sd.clutter_t, sd.clutter_range, sd.clutter_azimuth, sd.clutter_sensor)
                written(write_clutter(next(it), *args))
        written(write_truth(next(it), list(zip(names, sim.targets, strict=True))))
        written(write_truth(next(it), sim.ownship))
    return list(zip(paths, rows, strict=True))


def multitarget_files(scenario: Any, out: Path) -> list[Path]:
    """The files :func:`write_multitarget` writes for a ``[multitarget]`` scenario."""
    from seatrack.evaluate.tracking import tracking_sensor

    name = tracking_sensor(scenario).name
    return [out / f"plots_{name}.csv", out / f"plot_origin_{name}.csv", out / "truth.csv"]


def write_multitarget(scenario: Any, rng: np.random.Generator, out: Path) -> list[tuple[Path, int]]:
    """One run of a multi-target scenario, as its first active sensor sees it.

    ``plots_<sensor>.csv``: every plot (targets and clutter) WITHOUT a track column, in time
    order -- the input of the multi-target tracker; ``plot_origin_<sensor>.csv``: each plot
    with its line in that file and the target it came from (``clutter`` otherwise);
    ``truth.csv``: every live target at every scan (``time_s, target``, position and
    velocity). Written together (:func:`seatrack.io.atomic.atomic_files`).
    """
    import dataclasses

    from seatrack.evaluate.multitarget import simulate_scenario
    from seatrack.evaluate.tracking import tracking_sensor
    from seatrack.io.atomic import atomic_files
    from seatrack.io.multitarget import write_plot_labels
    from seatrack.io.multitarget import write_unlabelled_plots
    from seatrack.simulate.files import write_target_states

    paths = multitarget_files(scenario, out)
    prepare_outputs(paths, [out])
    bar = simulate_progress(scenario)
    sim = simulate_scenario(scenario, rng, tracking_sensor(scenario))
    bar.update(0, stage="written", fraction=SIMULATED_SHARE)
    order = np.argsort(sim.plots.t, kind="stable")
    plots = sim.plots.take(order)
    plots = dataclasses.replace(plots, line=np.arange(2, len(plots) + 2, dtype=np.int64))
    with atomic_files(paths) as (f_plots, f_origin, f_truth):
        rows = [
            write_unlabelled_plots(f_plots, plots),
            write_plot_labels(f_origin, plots, sim.origin[order]),
            write_target_states(f_truth, sim.truth_t, sim.truth_id, sim.truth_pos, sim.truth_vel),
        ]
    return list(zip(paths, rows, strict=True))


def seeded_rng(seed: int, run: int) -> np.random.Generator:
    """The generator of Monte-Carlo run ``run`` under master seed ``seed`` (as in evaluate)."""
    from seatrack.simulate.scenarios import MAX_RUNS

    option_in("--seed", seed, 0, 2**63 - 1)
    option_in("--run", run, 0, MAX_RUNS - 1)
    return np.random.default_rng(np.random.SeedSequence(seed).spawn(run + 1)[run])


#: seconds per simulated sample (:func:`~seatrack.simulate.multitarget.work_samples`),
#: simulating and writing the files: linear_cv stretched to 999,000 s at 1 s scans (4.0
#: million samples) took 74.6 s on the 2-core development machine at load 7.8
SIMULATE_SECONDS_PER_SAMPLE = 2e-5
#: the same for a ``[multitarget]`` scenario (clutter and the births of the population):
#: coastal_multitarget with 3,000 targets (487,000 samples) took 23.6 s, same machine
MULTITARGET_SECONDS_PER_SAMPLE = 5e-5
#: share of a run's time taken by the simulation itself, the rest by the files (linear_cv
#: at 800,000 samples: 0.66 s simulating, 14.7 s writing)
SIMULATED_SHARE = 0.05


def simulate_progress(scenario: Any) -> Progress:
    """The progress of simulating one run of ``scenario`` (in samples; told when the run
    is simulated and when its files are written)."""
    from seatrack.simulate.multitarget import work_samples

    sc = scenario
    n = work_samples(sc.duration, sc.dt, len(sc.targets), sc.sensors, sc.multitarget)
    rate = MULTITARGET_SECONDS_PER_SAMPLE if scenario.multitarget else SIMULATE_SECONDS_PER_SAMPLE
    return Progress("seatrack simulate", n, "samples", n * rate)


def simulate_to_folder(
    scenario: Any, out: Path, seed: int | None = None, run: int = 0
) -> list[tuple[Path, int]]:
    """Simulate run ``run`` of a loaded scenario (:func:`load`) into folder ``out``; returns
    (path, rows) of each file written."""
    rng = seeded_rng(scenario.seed if seed is None else seed, run)
    if scenario.multitarget is not None:  # unlabelled plots for the multi-target tracker
        return write_multitarget(scenario, rng, out)
    prepare_outputs(simulation_files(scenario, out), [out])
    bar = simulate_progress(scenario)
    sim = scenario.simulate(rng)
    bar.update(0, stage="written", fraction=SIMULATED_SHARE)
    return write_simulation(sim, out, bar)


def simulate(
    scenario: str | os.PathLike[str] | Mapping[str, Any],
    *,
    seed: int | None = None,
    run: int = 0,
) -> dict[str, Any]:
    """Simulate a scenario once: the measurements and the truth, as ``seatrack simulate``.

    Parameters
    ----------
    scenario : str, path or dict
        A bundled scenario name, a scenario TOML file, or a dict with its keys.
    seed : int, optional
        Master seed (default: the scenario's).
    run : int
        Monte-Carlo run index: the run ``run`` of :func:`seatrack.evaluate`.

    Returns
    -------
    dict of str to pandas.DataFrame
        One frame per file of the command, keyed by the file name without ``.csv``:
        ``plots_<sensor>`` (PLOTS columns, the input of :func:`seatrack.track`),
        ``clutter_<sensor>``, ``bearings_<sensor>`` (passive sonars, the input of
        :func:`seatrack.tma`), ``truth`` and ``ownship``; for a ``[multitarget]`` scenario
        ``plots_<sensor>`` without a track column, ``plot_origin_<sensor>`` and ``truth``.

    Examples
    --------
    >>> import seatrack
    >>> sim = seatrack.simulate("linear_cv", seed=7)
    >>> sorted(sim)
    ['ownship', 'plots_radar', 'truth']
    >>> list(sim["plots_radar"].columns[:4])
    ['track', 'time_s', 'range_m', 'azimuth_deg']
    """
    sc = load(scenario)
    with tempfile.TemporaryDirectory(prefix="seatrack-") as folder:
        written = simulate_to_folder(sc, Path(folder), seed, run)
        return {p.stem: read_frame(p, TEXT_COLUMNS) for p, _ in written}
