"""Live radar plots: datagrams -> plots -> scans -> the multi-target tracker.

A UDP datagram holds either ASTERIX CAT048 data blocks (:mod:`seatrack.io.asterix`; the
time of day is put on the UTC day of receipt, the nearest one) or CSV text: a header line
with the PLOTS.csv column names (``time_s`` = Unix time, ``range_m``, ``azimuth_deg``;
other columns ignored) followed by plots. Plots are in the radar's local East-North plane
(2-D, the sensor at the origin); the radar's position, noise and tracker keys come from
``radar.toml`` (:func:`seatrack.io.radar.load_radar_config`).

Scans. Plots of one time form a scan; the scan closes when a plot of a later time
arrives or, once every datagram received is processed, ``scan_timeout_s`` (receipt time)
after its first plot, and is then handed to the tracker. A plot older than the open scan
(or of a closed scan) is rejected (``"late plot"``). The tracker is the one of
``seatrack track`` on unlabelled plots: the per-track filter ``method`` with the
automatic process noise for ``scan_period_s`` (:func:`seatrack.tracking.auto.per_track_filter`)
inside
:class:`~seatrack.tracking.roles.Tracker`, stepped scan by scan through
:class:`ScanTracker` (the one place that calls it).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import Plots
from seatrack.geometry import bearing
from seatrack.geometry import enu_to_geodetic
from seatrack.geometry import north_convergence
from seatrack.geometry import wrap_2pi
from seatrack.io.ais.reports import TIME_MAX
from seatrack.io.ais.reports import TIME_MIN
from seatrack.io.asterix import DAY_S
from seatrack.io.asterix import AsterixError
from seatrack.io.asterix import decode_cat048
from seatrack.live.picture import RadarTrackView
from seatrack.tracking import Tracker
from seatrack.tracking import TrackStatus
from seatrack.tracking.auto import per_track_filter

FloatArray = NDArray[np.float64]

__all__ = ["LiveRadar", "ScanTracker", "parse_plot_datagram", "unix_time_of_day"]

REQUIRED = ("time_s", "range_m", "azimuth_deg")


def unix_time_of_day(tod_s: FloatArray, received_s: float) -> FloatArray:
    """Times of day (s since midnight UTC) -> Unix time on the day nearest the receipt."""
    midnight = math.floor(received_s / DAY_S) * DAY_S
    t = midnight + np.asarray(tod_s, dtype=float)
    t = np.where(t > received_s + DAY_S / 2, t - DAY_S, t)
    return np.where(t < received_s - DAY_S / 2, t + DAY_S, t)


def parse_plot_datagram(
    data: bytes, received_s: float
) -> tuple[FloatArray, FloatArray, FloatArray, dict[str, int]]:
    """One datagram -> plot times (Unix s), ranges (m), azimuths (rad) and the counts of
    what was rejected, by reason (a malformed datagram counts once; bad rows each)."""
    empty = np.zeros(0)
    if data[:1] == b"\x30":  # CAT048
        try:
            c = decode_cat048(data, "datagram")
        except AsterixError:
            return empty, empty, empty, {"bad CAT048 datagram": 1}
        ok = np.isfinite(c.time_of_day_s)
        bad = {"no time of day": int((~ok).sum())} if not ok.all() else {}
        t = unix_time_of_day(c.time_of_day_s[ok], received_s)
        return t, c.range_m[ok], c.azimuth[ok], bad
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        return empty, empty, empty, {"not CAT048 or CSV": 1}
    lines = text.splitlines()
    head = [h.strip() for h in lines[0].split(",")] if lines else []
    if not set(REQUIRED) <= set(head):
        return empty, empty, empty, {"no PLOTS.csv header": 1}
    col = [head.index(c) for c in REQUIRED]
    rows, bad = [], {}
    for line in lines[1:]:
        cells = line.split(",")
        try:
            if len(cells) != len(head):
                raise ValueError
            ti, ri, ai = (float(cells[k]) for k in col)
        except ValueError:
            bad["bad plot row"] = bad.get("bad plot row", 0) + 1
            continue
        if not (TIME_MIN <= ti < TIME_MAX and 0 < ri < 1e7 and 0 <= ai < 360):
            bad["bad plot value"] = bad.get("bad plot value", 0) + 1
            continue
        rows.append((ti, ri, math.radians(ai)))
    arr = np.array(rows, dtype=float).reshape(-1, 3)
    return arr[:, 0], arr[:, 1], arr[:, 2], bad


class ScanTracker:
    """The multi-target tracker stepped one scan at a time (the adapter the live process
    uses, so that the tracker behind it can change in one place)."""

    def __init__(self, setup: Any, source: str = "radar config") -> None:
        site = setup.site
        self.method, self.noise = per_track_filter(
            site.method, setup.method_table, 2, False, site.scan_period, source,
            turn_rate=setup.tracker.turn_rate,
        )  # fmt: skip
        self.tracker = Tracker(self.method.filter, sensor=setup.sensor, config=setup.tracker)

    def step(self, t: float, rng: FloatArray, az: FloatArray) -> Any:
        """One scan of 2-D plots (range m, azimuth rad, sensor at the origin) at ``t``;
        returns the tracker's :class:`~seatrack.tracking.roles.ScanResult`."""
        plots = Plots(np.full(rng.size, t), rng, az)
        return self.tracker.step(t, self.method.prepare(plots))

    def columns(self, state: Any) -> dict[str, NDArray[Any]]:
        """The filter's output columns of a scan result's states."""
        return dict(self.method.filter.columns(state))


class LiveRadar:
    """Scans of live plots through :class:`ScanTracker` (see the module docstring)."""

    def __init__(self, setup: Any, counters: Any) -> None:
        self.setup = setup
        self.site = setup.site
        self.counters = counters
        self.scans = ScanTracker(setup)
        self.open_t: float | None = None
        self.open_since = 0.0
        self.parts: list[tuple[FloatArray, FloatArray]] = []
        self.last_t = -math.inf
        self.changed = False
        self.current: list[RadarTrackView] = []
        self.scan_plots: tuple[float, FloatArray, FloatArray] = (0.0, np.zeros(0), np.zeros(0))
        self.scan_rows: list[tuple] = []  # per current track: x, y, vx, vy (m, m/s), status
        self.listeners: list[Any] = []  # fn(t, ids, status, columns) after each scan
        #: exceptions raised by listeners, by type (counted, reported in ``/api/health``)
        self.listener_errors: dict[str, int] = {}
        self.on_scan: list[Any] = []  # fn(self) after each scan

    @property
    def n_tracks(self) -> int:
        return len(self.current)

    def datagram(self, data: bytes, received_s: float, perf_s: float) -> None:
        """A datagram of plots."""
        t, rng, az, bad = parse_plot_datagram(data, received_s)
        cnt = self.counters
        for reason, n in bad.items():
            cnt.plots_rejected[reason] += n
        cnt.plots_received += t.size + sum(bad.values())
        self.add(t, rng, az, received_s)

    def add(self, t: FloatArray, rng: FloatArray, az: FloatArray, received_s: float) -> None:
        """Plots in arrival order."""
        if t.size == 0:
            return
        cuts = np.flatnonzero(np.diff(t) != 0) + 1
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, t.size], strict=True):
            tk = float(t[a])
            if self.open_t is not None and tk > self.open_t:
                self.close()
            if tk <= self.last_t or (self.open_t is not None and tk < self.open_t):
                self.counters.plots_rejected["late plot"] += int(b - a)
                continue
            if self.open_t is None:
                self.open_t, self.open_since = tk, received_s
            self.parts.append((rng[a:b], az[a:b]))

    def timeout(self, now_s: float) -> None:
        """Close the open scan if it waited ``scan_timeout_s``."""
        if self.open_t is not None and now_s - self.open_since > self.site.scan_timeout:
            self.close()

    def flush(self) -> None:
        """Close the open scan now."""
        if self.open_t is not None:
            self.close()

    def close(self) -> None:
        """Track the open scan."""
        assert self.open_t is not None
        t = self.open_t
        rng = np.concatenate([p[0] for p in self.parts])
        az = np.concatenate([p[1] for p in self.parts])
        self.open_t, self.parts, self.last_t = None, [], t
        t0 = time.perf_counter()
        res = self.scans.step(t, rng, az)
        shown = np.flatnonzero(res.status != int(TrackStatus.TENTATIVE))
        cols = self.scans.columns(res.state.take(shown)) if shown.size else {}
        self.current = self.views(t, res.track[shown], res.status[shown], cols)
        self.scan_plots = (t, rng, az)
        self.scan_rows = [
            (cols["x_m"][k], cols["y_m"][k], cols["vx_mps"][k], cols["vy_mps"][k],
             TrackStatus(int(res.status[shown][k])).label)
            for k in range(shown.size)
        ]  # fmt: skip
        self.counters.scans += 1
        self.counters.scan_latency.add(time.perf_counter() - t0)
        self.changed = True
        for fn in self.listeners:
            try:
                fn(t, res.track[shown], res.status[shown], cols)
            except Exception as exc:  # a failing consumer (the fusion) never stops the radar
                self.listener_errors[type(exc).__name__] = (
                    self.listener_errors.get(type(exc).__name__, 0) + 1
                )
        for hook in self.on_scan:
            hook(self)

    def views(
        self, t: float, ids: NDArray[np.int64], status: NDArray[Any], cols: dict[str, Any]
    ) -> list[RadarTrackView]:
        """The reported tracks in WGS84 (true-North courses)."""
        if not ids.size:
            return []
        lat0, lon0 = math.degrees(self.site.lat), math.degrees(self.site.lon)
        x, y = np.asarray(cols["x_m"]), np.asarray(cols["y_m"])
        enu = np.stack([x, y, np.zeros_like(x)], -1)
        lat, lon, _ = enu_to_geodetic(enu, lat0, lon0)
        gam = np.nan_to_num(north_convergence(lat, lon, lat0, lon0))
        vx, vy = np.asarray(cols["vx_mps"]), np.asarray(cols["vy_mps"])
        course = wrap_2pi(bearing(vx, vy) - gam)
        std = np.sqrt(0.5 * (np.asarray(cols["std_x_m"]) ** 2 + np.asarray(cols["std_y_m"]) ** 2))
        confirmed = status == int(TrackStatus.CONFIRMED)
        speed = np.hypot(vx, vy)
        return [
            RadarTrackView(int(ids[k]), t, float(lat[k]), float(lon[k]), float(speed[k]),
                           float(course[k]), float(std[k]), bool(confirmed[k]))
            for k in range(ids.size)
        ]  # fmt: skip
