"""The current picture: AIS vessels and radar tracks as GeoJSON point features.

Feature properties: ``id`` (``ais:MMSI`` or ``radar:N``), ``source`` (``ais`` | ``radar``),
``mmsi`` (null for radar), ``time_utc`` (ISO 8601, ms), ``sog_kn``, ``cog_deg`` (true
North), ``status`` (AIS: ``tracking`` or the outlier kind of the last report; radar:
``confirmed`` / ``tentative``), ``std_m`` (1-sigma position, m, the root mean square of the
East and North sigmas), ``name`` (AIS static reports) and ``trail`` (the last positions
shown, ``[lon, lat]``, oldest first). Geometry: ``Point [lon, lat]``.

With radar-AIS fusion (AIS and radar inputs, :mod:`seatrack.live.fusion`), radar features
carry the fusion of the last scan: ``mmsi`` (the associated AIS vessel, null when none),
``identity_prob`` (null when none) and ``class`` (``ais`` | ``dark`` | ``unknown``); AIS
features carry ``not_seen`` (bool). Without fusion these are null. Radar features also
carry ``ais_id``, the feature id of their AIS vessel.

AIS anomalies (:mod:`seatrack.live.identity`): AIS features carry ``sub`` (0 for an MMSI's
first vessel; a shared MMSI's further vessels are ``ais:MMSI#2``, ``#3`` ...) and the
flags of the vessel's last report, ``gap``, ``jump`` and ``identity_conflict``.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC
from datetime import datetime
from typing import Any

from seatrack.filters.ais import OUTLIER_KINDS
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import bearing_rad_to_deg
from seatrack.live.identity import split_key

__all__ = ["Picture", "RadarTrackView", "ais_id", "time_utc"]

TRAIL = 20


def time_utc(t: float) -> str:
    """Unix time (s) -> ``YYYY-MM-DDTHH:MM:SS.mmmZ``."""
    return datetime.fromtimestamp(t, UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


def ais_id(key: int) -> str:
    """The feature id of an AIS vessel key: ``ais:MMSI`` for an MMSI's first vessel,
    ``ais:MMSI#2``, ``#3`` ... for the further vessels a shared MMSI is split into (the
    names of ``seatrack fuse``)."""
    m, sub = split_key(key)
    return f"ais:{m}" if sub == 0 else f"ais:{m}#{sub + 1}"


def _num(x: float, digits: int) -> float | None:
    return round(float(x), digits) if math.isfinite(x) else None


@dataclass
class RadarTrackView:
    """A radar track of the picture: id, time (Unix s), WGS84 position (deg), speed
    (m/s), course (rad, true North), position sigma (m), confirmed or not."""

    track_id: int
    t: float
    lat: float
    lon: float
    speed: float
    course: float
    std_m: float
    confirmed: bool


def _feature(fid: str, lat: float, lon: float, props: dict[str, Any]) -> dict[str, Any]:
    return {
        "type": "Feature",
        "id": fid,
        "geometry": {"type": "Point", "coordinates": [_num(lon, 7), _num(lat, 7)]},
        "properties": {"id": fid, **props},
    }


class Picture:
    """Features of the AIS vessels (:class:`~seatrack.live.ais.LiveAis`) and the radar
    tracks, with short trails; :meth:`refresh` recomputes the features of what changed."""

    def __init__(self) -> None:
        self.features: dict[str, dict[str, Any]] = {}
        self.trails: dict[str, deque] = {}
        self.dirty: set[str] = set()
        self.removed: set[str] = set()
        self.fused = False  # radar-AIS fusion on: the fusion properties are set
        self.not_seen: set[int] = set()  # MMSIs flagged not seen at the last fused scan

    def _put(self, fid: str, lat: float, lon: float, props: dict[str, Any]) -> None:
        trail = self.trails.setdefault(fid, deque(maxlen=TRAIL))
        pos = [_num(lon, 7), _num(lat, 7)]
        if not trail or trail[-1] != pos:
            trail.append(pos)
        props["trail"] = list(trail)
        self.features[fid] = _feature(fid, lat, lon, props)
        self.dirty.add(fid)

    def refresh_ais(self, ais: Any, names: dict[int, str], identities: Any = None) -> None:
        """Features of the vessels changed since the last call (``ais.changed``, and the
        vessels whose anomaly flags changed in ``identities``,
        :class:`~seatrack.live.identity.LiveIdentities`). Vessels are tracked under keys
        (:func:`~seatrack.live.identity.vessel_key`: the MMSI, or the MMSI's second,
        third ... vessel)."""
        if identities is not None and identities.changed:
            ais.changed.update(k for k in identities.changed if k in ais.vessels)
            identities.changed.clear()
        if not ais.changed:
            return
        ids, tr, t = ais.tracks(sorted(ais.changed))
        ais.changed.clear()
        for k, key in enumerate(ids):
            m, _ = split_key(key)
            kind = int(tr.outlier_kind[k])
            props = {
                "source": "ais",
                "mmsi": m,
                "time_utc": time_utc(t[k]),
                "sog_kn": _num(tr.speed[k] / KNOT_MPS, 2),
                "cog_deg": _num(bearing_rad_to_deg(tr.course[k]), 1),
                "status": OUTLIER_KINDS.get(kind, "tracking"),
                "std_m": _num(tr.std_pos_m[k], 2),
                "name": names.get(m, ""),
                "not_seen": (key in self.not_seen) if self.fused else None,
            }
            if identities is not None:
                props.update(identities.describe(key))
            self._put(ais_id(key), tr.lat[k], tr.lon[k], props)

    def set_radar(self, tracks: list[RadarTrackView]) -> None:
        """Replace the radar tracks (after a scan); a track keeps its fusion properties
        until the fusion of the new scan arrives (:meth:`set_fusion`)."""
        keep = set()
        for r in tracks:
            fid = f"radar:{r.track_id}"
            keep.add(fid)
            old = self.features.get(fid)
            fused = old["properties"] if old is not None and self.fused else {}
            props = {
                "source": "radar",
                "mmsi": fused.get("mmsi"),
                "time_utc": time_utc(r.t),
                "sog_kn": _num(r.speed / KNOT_MPS, 2),
                "cog_deg": _num(bearing_rad_to_deg(r.course), 1),
                "status": "confirmed" if r.confirmed else "tentative",
                "std_m": _num(r.std_m, 2),
                "name": "",
                "identity_prob": fused.get("identity_prob"),
                "ais_id": fused.get("ais_id"),
                "class": fused.get("class"),
            }
            self._put(fid, r.lat, r.lon, props)
        for fid in [f for f in self.features if f.startswith("radar:") and f not in keep]:
            del self.features[fid]
            self.trails.pop(fid, None)
            self.removed.add(fid)

    def set_fusion(self, tracks: Mapping[int, Any], not_seen: set[int]) -> None:
        """The fusion's result of the last scan: per radar track id a
        :class:`~seatrack.live.fusion.FusedTrack` (``mmsi``, ``identity_prob``, ``class``),
        and the MMSIs of the AIS vessels ``not_seen``."""
        for tid, f in tracks.items():
            feat = self.features.get(f"radar:{tid}")
            if feat is None:
                continue
            p = feat["properties"]
            p["mmsi"] = None if f.mmsi is None else split_key(f.mmsi)[0]
            p["ais_id"] = None if f.mmsi is None else ais_id(f.mmsi)
            p["identity_prob"] = None if f.identity_prob is None else _num(f.identity_prob, 4)
            p["class"] = f.klass
            self.dirty.add(f"radar:{tid}")
        changed = self.not_seen ^ not_seen
        self.not_seen = set(not_seen)
        for m in changed:
            fid = ais_id(m)
            feat = self.features.get(fid)
            if feat is not None:
                feat["properties"]["not_seen"] = m in not_seen
                self.dirty.add(fid)

    def collection(self) -> dict[str, Any]:
        """The whole picture as a GeoJSON FeatureCollection."""
        return {"type": "FeatureCollection", "features": list(self.features.values())}

    def take_changes(self) -> dict[str, Any] | None:
        """The features changed and the ids removed since the last call (None if none)."""
        if not self.dirty and not self.removed:
            return None
        msg = {
            "type": "FeatureCollection",
            "features": [self.features[f] for f in sorted(self.dirty) if f in self.features],
            "removed": sorted(self.removed),
        }
        self.dirty.clear()
        self.removed.clear()
        return msg

    def count(self, source: str) -> int:
        """Features of ``source``."""
        return sum(1 for f in self.features if f.startswith(source + ":"))
