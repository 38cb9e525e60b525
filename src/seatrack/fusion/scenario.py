"""Simulated radar plots and corrupted AIS reports from a truth, for tests and benchmarks.

The truth is a set of vessel trajectories in the radar's East-North plane, sampled at
known times (:class:`Truth`). :func:`simulate_plots` draws the radar's plots at each scan:
each covered vessel is detected with the site's detection probability, its range and
azimuth disturbed by the sensor noise, and clutter is drawn uniformly in range and
azimuth. :func:`ais_reports` turns a truth into AIS reports with the situations the
fusion must find: vessels whose AIS is removed (dark), moved (spoofed), or sent under
another vessel's MMSI (shared).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.fusion.coverage import Coverage
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import bearing_rad_to_deg
from seatrack.geometry import cart_to_polar
from seatrack.geometry import course_speed
from seatrack.geometry import enu_to_geodetic
from seatrack.geometry import polar_to_cart
from seatrack.io.ais.reports import AisReports

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["Truth", "Corruption", "interpolate", "simulate_plots", "ais_reports"]


@dataclass(frozen=True)
class Truth:
    """Vessel trajectories: rows sorted by (vessel, time); ``pos`` (n, 2) m East, North
    about the radar; ``mmsi`` (V,) each vessel's own identity."""

    vessel: IntArray
    t: FloatArray
    pos: FloatArray
    mmsi: IntArray


def interpolate(truth: Truth, t: float) -> tuple[IntArray, FloatArray, FloatArray]:
    """Vessels alive at ``t`` (between their first and last sample), their positions
    (linear between samples) and velocities (m/s)."""
    v = np.arange(truth.mmsi.size)
    first = np.searchsorted(truth.vessel, v)
    last = np.searchsorted(truth.vessel, v, side="right") - 1
    ok = (last > first) & (truth.t[first] <= t) & (truth.t[np.maximum(last, 0)] >= t)
    v, first, last = v[ok], first[ok], last[ok]
    k = np.empty(v.size, np.int64)
    for n, (a, b) in enumerate(zip(first, last, strict=True)):
        k[n] = min(a + int(np.searchsorted(truth.t[a : b + 1], t, side="right")) - 1, b - 1)
    dt = truth.t[k + 1] - truth.t[k]
    f = ((t - truth.t[k]) / np.where(dt > 0, dt, 1.0))[:, None]
    vel = (truth.pos[k + 1] - truth.pos[k]) / np.where(dt > 0, dt, 1.0)[:, None]
    return v, truth.pos[k] + f * (truth.pos[k + 1] - truth.pos[k]), vel


def simulate_plots(
    truth: Truth,
    scan_times: FloatArray,
    coverage: Coverage,
    sensor: SensorNoise,
    clutter_per_scan: float,
    rng: np.random.Generator,
) -> tuple[Plots, IntArray]:
    """Radar plots of the truth at every scan, and each plot's vessel (-1: clutter)."""
    site = coverage.site
    cols: list[tuple[FloatArray, FloatArray, FloatArray, IntArray]] = []
    for t in scan_times:
        v, pos, _ = interpolate(truth, float(t))
        seen = coverage.covered(pos[:, 0], pos[:, 1])
        seen &= rng.random(v.size) < site.detection_probability
        r, az = cart_to_polar(pos[seen])
        r = np.atleast_1d(r) + sensor.sigma_range * rng.standard_normal(int(seen.sum()))
        az = az + sensor.sigma_azimuth * rng.standard_normal(int(seen.sum()))
        nc = rng.poisson(clutter_per_scan)
        rc = rng.uniform(site.min_range, site.max_range, nc)
        ac = rng.uniform(0.0, 2.0 * math.pi, nc)
        lab = np.r_[v[seen], np.full(nc, -1)].astype(np.int64)
        cols.append((np.full(lab.size, t), np.r_[r, rc], np.mod(np.r_[az, ac], 2 * math.pi), lab))
    t_all, r_all, a_all, lab_all = (np.concatenate(c) for c in zip(*cols, strict=True))
    return Plots(t_all, np.maximum(r_all, 1.0), a_all), lab_all


@dataclass(frozen=True)
class Corruption:
    """What :func:`ais_reports` does to the vessels (indices into the truth's vessels).

    ``dark``: no AIS at all; ``silent``: AIS stops for ``[start, end)`` seconds of each
    vessel's own period (``silent_start``, ``silent_end``; absolute times);
    ``spoof``: positions moved by ``spoof_offset`` (k, 2) m during
    ``[spoof_start, spoof_end)``; ``shared``: pairs (a, b) -- vessel ``b`` transmits
    vessel ``a``'s MMSI.
    """

    dark: tuple[int, ...] = ()
    silent: tuple[int, ...] = ()
    silent_start: tuple[float, ...] = ()
    silent_end: tuple[float, ...] = ()
    spoof: tuple[int, ...] = ()
    spoof_offset: tuple[tuple[float, float], ...] = ()
    spoof_start: tuple[float, ...] = ()
    spoof_end: tuple[float, ...] = ()
    shared: tuple[tuple[int, int], ...] = ()


def ais_reports(
    truth: Truth,
    interval_s: FloatArray,
    origin_deg: tuple[float, float],
    corruption: Corruption,
    sigma_pos_m: float,
    rng: np.random.Generator,
) -> tuple[AisReports, IntArray]:
    """AIS reports of every vessel every ``interval_s[vessel]`` seconds (with a random
    phase), position noise ``sigma_pos_m``, SOG and COG from the truth, corrupted as
    ``corruption`` says; and each report's true vessel."""
    mmsi = truth.mmsi.copy()
    for a, b in corruption.shared:
        mmsi[b] = truth.mmsi[a]
    parts: list[tuple[FloatArray, ...]] = []
    for v in range(truth.mmsi.size):
        if v in corruption.dark:
            continue
        rows = truth.vessel == v
        t0, t1 = truth.t[rows].min(), truth.t[rows].max()
        times = np.arange(t0 + rng.uniform(0, interval_s[v]), t1, interval_s[v])
        keep = np.ones(times.size, bool)
        if v in corruption.silent:
            k = corruption.silent.index(v)
            keep &= (times < corruption.silent_start[k]) | (times >= corruption.silent_end[k])
        times = times[keep]
        xy = np.empty((times.size, 2))
        vel = np.empty((times.size, 2))
        for n, t in enumerate(times):
            alive, p, u = interpolate(truth, float(t))
            i = int(np.searchsorted(alive, v))
            xy[n], vel[n] = p[i], u[i]
        xy += sigma_pos_m * rng.standard_normal(xy.shape)
        if v in corruption.spoof:
            k = corruption.spoof.index(v)
            on = (times >= corruption.spoof_start[k]) & (times < corruption.spoof_end[k])
            xy[on] += np.asarray(corruption.spoof_offset[k])
        cog, sog = course_speed(vel[:, 0], vel[:, 1])
        parts.append((times, xy[:, 0], xy[:, 1], np.asarray(sog) / KNOT_MPS,
                      bearing_rad_to_deg(cog), np.full(times.size, float(v))))  # fmt: skip
    t, x, y, sog_kn, cog_deg, who = (np.concatenate(c) for c in zip(*parts, strict=True))
    order = np.argsort(t, kind="stable")
    t, x, y, sog_kn, cog_deg, who = (a[order] for a in (t, x, y, sog_kn, cog_deg, who))
    lat, lon, _ = enu_to_geodetic(np.stack([x, y], -1), *origin_deg)
    n = t.size
    vessel = who.astype(np.int64)
    rep = AisReports(
        ("simulated",), np.zeros(n, np.int64), np.arange(2, n + 2, dtype=np.int64),
        mmsi[vessel], t, lat, lon, sog_kn, cog_deg, np.full(n, np.nan), np.zeros(n, np.int8),
    )  # fmt: skip
    return rep, vessel


def straight_truth(
    start: FloatArray, course_deg: FloatArray, speed_kn: FloatArray, t0: float,
    duration_s: float, step_s: float = 10.0, first_mmsi: int = 219000001,
) -> Truth:  # fmt: skip
    """Vessels on straight lines from ``start`` (V, 2) m at constant course and speed."""
    times = np.arange(t0, t0 + duration_s + step_s, step_s)
    vel = polar_to_cart(np.asarray(speed_kn) * KNOT_MPS, np.radians(course_deg))
    nv = vel.shape[0]
    pos = np.asarray(start)[:, None, :] + vel[:, None, :] * (times - t0)[None, :, None]
    vessel = np.repeat(np.arange(nv), times.size)
    return Truth(vessel, np.tile(times, nv), pos.reshape(-1, 2),
                 np.arange(first_mmsi, first_mmsi + nv, dtype=np.int64))  # fmt: skip
