"""Headline rows of the method benchmarks: a ``seatrack track`` method as a new user runs it.

The rows the benchmarks lead with are the command-line defaults plus the sensor's nominal
noise (``nominal``) -- optionally with ``target = <class>`` -- run through the registry
on the filter contract, all Monte-Carlo runs of a set as the tracks of ONE file (one batch
per scan, as ``seatrack track`` runs a file of many tracks). Tuned rows stand beside them,
labelled.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from seatrack.filters.base import Plots
from seatrack.filters.registry import run

__all__ = ["labelled_plots", "nominal", "run_registry"]


def labelled_plots(
    t: np.ndarray,
    rng: np.ndarray,
    az: np.ndarray,
    el: np.ndarray | None = None,
    rr: np.ndarray | None = None,
    sensor: np.ndarray | None = None,
    sensor_vel: np.ndarray | None = None,
) -> Plots:
    """The runs ``(B, N)`` of polar plots at scan times ``t (N,)`` as one labelled file
    (track ``r<i>`` = run ``i``, its plots in time order); ``sensor`` ``(B, N, 2|3)``."""
    B, N = rng.shape

    def flat(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else np.ascontiguousarray(a).reshape(B * N)

    def xyz(a: np.ndarray | None) -> np.ndarray:
        out = np.zeros((B * N, 3))
        if a is not None:
            out[:, : a.shape[-1]] = a.reshape(B * N, -1)
        return out

    tt = np.tile(np.asarray(t, dtype=float), B)
    labels = np.repeat(np.array([f"r{i}" for i in range(B)]), N)
    return Plots(tt, flat(rng), flat(az), flat(el), flat(rr), xyz(sensor), xyz(sensor_vel),  # type: ignore[arg-type]
                 track=labels)  # fmt: skip


def nominal(
    sigma_range: float,
    sigma_azimuth: float,
    sigma_elevation: float | None = None,
    sigma_range_rate: float | None = None,
) -> dict[str, Any]:
    """The sensor keys a user gives (SI in, edge units out: degrees)."""
    cfg: dict[str, Any] = {
        "sigma_range_m": sigma_range,
        "sigma_azimuth_deg": math.degrees(sigma_azimuth),
    }
    if sigma_elevation is not None:
        cfg["sigma_elevation_deg"] = math.degrees(sigma_elevation)
    if sigma_range_rate is not None:
        cfg["sigma_range_rate_mps"] = sigma_range_rate
    return cfg


def run_registry(
    method: str, plots: Plots, config: dict[str, Any], B: int
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Run ``method`` (registry defaults + ``config``) over the labelled runs.

    Returns the states ``(B, N, 2d)`` (``x, y, [z], vx, vy, [vz]``; 2-D methods on 3-D
    plots give a zero z), their covariance diagonals ``(B, N, 2d)`` and the columns.
    """
    cols = run(method, plots, config)
    d = 3 if plots.is_3d else 2
    axes = ("x", "y", "z")[:d]
    x = np.stack([np.nan_to_num(cols[f"{a}_m"]) for a in axes]
                 + [np.nan_to_num(cols[f"v{a}_mps"]) for a in axes], -1)  # fmt: skip
    var = np.stack([np.nan_to_num(cols[f"std_{a}_m"]) ** 2 for a in axes], -1)
    return x.reshape(B, -1, 2 * d), var.reshape(B, -1, d), cols
