"""Write a small simulated river passage for ``seatrack navigate`` / ``seatrack survey``.

Creates ``examples/river_map.csv`` (landmarks with a few metres of map error),
``examples/river_echoes.csv`` (above-threshold radar samples, clutter included),
``examples/river_gyro.csv`` and prints the ``--start`` value to use. Seeded, so the files
are reproducible::

    python examples/make_navigation_example.py
    seatrack navigate --map examples/river_map.csv --echoes examples/river_echoes.csv \\
        --gyro examples/river_gyro.csv --start "<printed value>" --out nav.csv
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from seatrack.io.landmarks import write_map_csv
from seatrack.io.navigation import write_echoes
from seatrack.io.navigation import write_gyro
from seatrack.simulate.radar_echoes import channel_landmarks
from seatrack.simulate.radar_echoes import river_route
from seatrack.simulate.radar_echoes import simulate_radar


def main() -> None:
    here = Path(__file__).resolve().parent
    route = river_route(1500.0, 4.0)  # 1.5 km at 4 m/s: about six minutes of radar
    landmarks = channel_landmarks(route, 8, np.random.default_rng(1))
    sim = simulate_radar(route, landmarks, np.random.default_rng(2))
    e = sim.echoes
    write_echoes(here / "river_echoes.csv", e.t, e.antenna, e.range, e.amplitude)
    write_gyro(here / "river_gyro.csv", sim.gyro_t, sim.gyro_rate)
    write_map_csv(sim.nav_map, here / "river_map.csv")
    x0 = sim.truth[0]
    start = f"{x0[0]:.1f},{x0[1]:.1f},{np.degrees(x0[2]):.2f},{np.hypot(x0[3], x0[4]):.2f}"
    print(f'wrote {len(e.t)} echo samples; --start "{start}"')


if __name__ == "__main__":
    main()
