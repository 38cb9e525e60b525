"""Write ``examples/tma_bearings.csv`` and ``examples/tma_support.csv`` (seeded).

Two contacts seen from one own ship (the classic Ristic et al. ch. 6 geometry):
contact ``A`` is the classic target; contact ``B`` is a second straight-running target.
The support file gives a radar range on ``B`` at the last bearing time. Run::

    python examples/make_tma_example.py
    seatrack tma examples/tma_bearings.csv --support examples/tma_support.csv \
        --out result.json --plot tma.png
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from seatrack.geometry import knots_to_mps
from seatrack.simulate import Leg
from seatrack.simulate import trajectory
from seatrack.simulate.files import write_bearings
from seatrack.simulate.tma import classic_scenario
from seatrack.simulate.tma import scenario_from_trajectories

HERE = Path(__file__).resolve().parent


def main() -> None:
    rng = np.random.default_rng(1984)
    a = classic_scenario()
    tgt_b = trajectory([-3000.0, 7000.0], math.radians(100.0), float(knots_to_mps(9.0)),
                       [Leg.straight(3000.0)], times=a.times)  # fmt: skip
    b = scenario_from_trajectories(tgt_b, a.observer, a.sigma)
    meas = [("A", a.measurements(rng)), ("B", b.measurements(rng))]
    write_bearings(HERE / "tma_bearings.csv", meas, sigma_deg=1.5)
    o = a.observer.pos[-1, :2]
    rng_b = float(np.hypot(*(tgt_b.pos[-1, :2] - o))) + 50.0 * rng.standard_normal()
    (HERE / "tma_support.csv").write_text(
        "contact,kind,time_s,value,sigma,observer_x_m,observer_y_m\n"
        f"B,range,{a.times[-1]:.0f},{rng_b:.0f},50,{o[0]:.1f},{o[1]:.1f}\n"
    )


if __name__ == "__main__":
    main()
