"""Rebuild ``src/seatrack/report/assets/ne_10m_land.npz`` from Natural Earth via world-atlas.

    npm pack world-atlas@2.0.2 && tar xzf world-atlas-2.0.2.tgz
    python tools/make_land_asset.py package/land-10m.json

The TopoJSON ``land`` object (Natural Earth 1:10m land, public domain, quantised by
world-atlas to a 1e5 x 1e5 grid) is decoded to rings and stored on the same grid, per ring
delta-coded (first value absolute) as int32, compressed, with the grid's scale and origin.
See ``src/seatrack/report/assets/README.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from seatrack.io.atomic import atomic_path
from seatrack.report.land import LAND_ASSET, rings_from_topojson, topojson_transform

OUT = Path(__file__).resolve().parents[1] / "src" / "seatrack" / "report" / "assets" / LAND_ASSET


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("topojson", type=Path, help="world-atlas land-10m.json")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    r = rings_from_topojson(args.topojson)
    scale, origin = topojson_transform(args.topojson)
    qlon = np.round((r.lon - origin[0]) / scale[0]).astype(np.int64)
    qlat = np.round((r.lat - origin[1]) / scale[1]).astype(np.int64)
    first = r.offsets[:-1]
    dlon, dlat = np.diff(qlon, prepend=0), np.diff(qlat, prepend=0)
    dlon[first], dlat[first] = qlon[first], qlat[first]
    with atomic_path(args.out) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(
            fh,
            dlon=dlon.astype(np.int32),
            dlat=dlat.astype(np.int32),
            offsets=r.offsets.astype(np.int32),
            scale=np.asarray(scale, np.float64),
            origin=np.asarray(origin, np.float64),
        )
    print(
        f"{args.out}: {r.n_rings} rings, {r.offsets[-1]} vertices, {args.out.stat().st_size} bytes"
    )


if __name__ == "__main__":
    main()
