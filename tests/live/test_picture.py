"""Tests of seatrack.live.picture: feature ids of split MMSIs and the changes handed out."""

from __future__ import annotations

import numpy as np

from seatrack.live.ais import LiveAis
from seatrack.live.identity import vessel_key
from seatrack.live.picture import Picture
from seatrack.live.picture import ais_id


def test_ais_ids_of_an_mmsis_vessels() -> None:
    assert ais_id(vessel_key(219000001, 0)) == "ais:219000001"
    assert ais_id(vessel_key(219000001, 2)) == "ais:219000001#3"


def test_not_seen_change_of_a_split_vessel_is_handed_out_under_its_id() -> None:
    """A shared MMSI's second vessel flagged ``not_seen`` by the fusion: its feature
    (``ais:MMSI#2``) changes and is among the changes the web clients get."""
    key = vessel_key(219000001, 1)
    ais = LiveAis()
    t0 = 1.7e9
    for k in range(3):
        ais.add(np.array([key]), np.array([t0 + 10 * k]), np.array([56.0]),
                np.array([7.0 + 1e-4 * k]), np.array([5.0]), np.array([90.0]))  # fmt: skip
    pic = Picture()
    pic.fused = True
    pic.refresh_ais(ais, {})
    first = pic.take_changes()
    assert first is not None and [f["id"] for f in first["features"]] == ["ais:219000001#2"]
    assert first["features"][0]["properties"]["not_seen"] is False
    pic.set_fusion({}, {key})
    changes = pic.take_changes()
    assert changes is not None
    (feat,) = changes["features"]
    assert feat["id"] == "ais:219000001#2" and feat["properties"]["not_seen"] is True
