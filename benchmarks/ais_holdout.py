"""AIS hold-out accuracy on the real files, every fold: tracker vs linear interpolation.

For each real file bundled in seatrack/data/ais and each phase 0..4, every 5th report of each vessel
(the one at that position in each group of five) is withheld and predicted
(:func:`seatrack.evaluate.holdout.ais_holdout`); the table gives the median and 95th
percentile of the error (m) of the track and of linear interpolation between the neighbours,
and their ratio (track / interpolation; below 1 = the track is better). The tests use phase 4
(the 5th of each five); the tracker's tuned parameters were chosen on phases 0-3.

Then the evidence behind the timestamp-offset model: for moving vessels (chord speed
> 3 m/s, both neighbours within 25 s), the along-track residual of each report against the
chord of its neighbours, divided by the speed, clusters at whole and half seconds (a report
one second off, or a neighbour that is).

    python benchmarks/ais_holdout.py [--phases 4]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ais import DATA  # the real files, as in benchmarks/ais.py
from ais import REAL as FILES
from seatrack.evaluate.holdout import ais_holdout
from seatrack.geometry import local_frames
from seatrack.io.ais import read_ais_csv


def time_residuals(r) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Along-chord residual / chord speed (s) of moving reports with close neighbours."""
    ok = np.flatnonzero(r.valid)
    o = ok[np.lexsort((r.t[ok], r.mmsi[ok]))]
    m, t, E = r.mmsi[o], r.t[o], local_frames(r.mmsi, r.lat, r.lon, r.valid).enu[o, :2]
    i = np.arange(1, o.size - 1)
    i = i[(m[i - 1] == m[i]) & (m[i + 1] == m[i]) & (t[i + 1] - t[i - 1] <= 25)]
    i = i[(t[i + 1] > t[i]) & (t[i] > t[i - 1])]
    w = (t[i] - t[i - 1]) / (t[i + 1] - t[i - 1])
    v = (E[i + 1] - E[i - 1]) / (t[i + 1] - t[i - 1])[:, None]
    speed = np.hypot(*v.T)
    mv = speed > 3.0
    res = E[i] - (E[i - 1] + w[:, None] * (E[i + 1] - E[i - 1]))
    return (res[mv] * v[mv]).sum(axis=1) / speed[mv] ** 2


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--phases", type=int, nargs="*", default=[0, 1, 2, 3, 4])
    args = ap.parse_args(argv)
    for name in FILES:
        if not (DATA / name).is_file():
            print(f"error: real AIS data missing: {(DATA / name).resolve()}", file=sys.stderr)
            return 2
    reports = {name: read_ais_csv(DATA / name) for name in FILES}
    hdr = (
        f"{'file':38s} {'phase':>5s} {'n':>5s} {'median trk':>10s} {'lin':>6s} {'ratio':>6s} "
        f"{'p95 trk':>8s} {'lin':>6s} {'ratio':>6s}"
    )
    print(hdr)
    print("-" * len(hdr))
    for name, r in reports.items():
        for ph in args.phases:
            s = ais_holdout(r, phase=ph).summary()
            print(
                f"{name:38s} {ph:5d} {int(s['n']):5d} {s['track_median']:10.3f} "
                f"{s['interp_median']:6.3f} {s['track_median'] / s['interp_median']:6.3f} "
                f"{s['track_p95']:8.2f} {s['interp_p95']:6.2f} "
                f"{s['track_p95'] / s['interp_p95']:6.3f}"
            )
    print("\nalong-chord residual / speed of moving reports (s), share per 0.1-s bin centred at:")
    centres = np.round(np.arange(-1.5, 1.51, 0.1), 1)
    for name in FILES[:4]:
        x = time_residuals(reports[name])
        h, _ = np.histogram(x, bins=np.r_[centres - 0.05, centres[-1] + 0.05])
        peaks = {
            c: h[k] / x.size for k, c in enumerate(centres) if c in (-1.0, -0.5, 0.0, 0.5, 1.0)
        }
        between = {c: h[k] / x.size for k, c in enumerate(centres) if c in (-0.7, -0.3, 0.3, 0.7)}
        print(
            f"{name:38s} n={x.size:6d}  at -1, -0.5, 0, 0.5, 1 s: "
            + " ".join(f"{100 * peaks[c]:4.1f}%" for c in sorted(peaks))
            + "   at -0.7, -0.3, 0.3, 0.7 s: "
            + " ".join(f"{100 * between[c]:4.1f}%" for c in sorted(between))
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
