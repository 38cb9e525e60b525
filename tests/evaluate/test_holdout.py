"""Hold-out evaluation (seatrack.evaluate.holdout) on a small synthetic AIS file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from seatrack.evaluate.holdout import ais_holdout
from seatrack.io.ais import read_ais_csv


def _straight_file(path: Path) -> Path:
    """Two vessels at constant velocity, exact positions every 10 s (one fix per line)."""
    lines = ["mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg"]
    for m, (dlat, dlon) in ((1, (1e-5, 0.0)), (2, (0.0, 2e-5))):
        for k in range(60):
            stamp = np.datetime_as_string(np.datetime64(1_600_000_000 + 10 * k, "s"))
            lines.append(f"{m},{stamp}Z,{56 + k * dlat:.7f},{7 + k * dlon:.7f},,,")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_holdout_withholds_the_phase_and_interpolation_is_exact_on_straight_lines(
    tmp_path: Path,
) -> None:
    r = read_ais_csv(_straight_file(tmp_path / "s.csv"))
    for phase in range(5):
        res = ais_holdout(r, every=5, phase=phase)
        # every 5th report of each vessel, except the ends without a neighbour on both sides
        k = np.array([(r.t[i] - 1_600_000_000) / 10 for i in res.row])
        assert np.all(k % 5 == phase)
        assert res.row.size == 2 * (12 - (phase in (0, 4)))  # k = 0 and k = 59 lack one
        # uniform straight motion: interpolation is exact, the track nearly so
        assert np.all(res.interp < 1e-6)
        assert np.all(res.track < 0.5)
    s = res.summary()
    assert s["n"] == res.row.size and s["interp_p95"] < 1e-6
    with pytest.raises(ValueError, match="phase"):
        ais_holdout(r, every=5, phase=5)
