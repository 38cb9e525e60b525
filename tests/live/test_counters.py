"""Tests of seatrack.live.counters: the latency ring and the since-start histogram."""

from __future__ import annotations

import numpy as np

from seatrack.live.counters import Counters
from seatrack.live.counters import Latency


def test_latency_before_any_value_is_none() -> None:
    p = Latency(10).percentiles_ms()
    assert p["p50"] is None and p["p99"] is None
    assert p["since_start"] == {"p50": None, "p99": None, "max": None, "n": 0}


def test_ring_holds_the_last_values_and_the_histogram_every_value() -> None:
    lat = Latency(100)
    lat.add(np.full(1_000, 0.5))  # an early stall: 500 ms
    lat.add(np.full(100, 0.002))  # then 2 ms
    p = lat.percentiles_ms()
    assert p["p99"] == 2.0  # the ring: the last 100 values only
    run = p["since_start"]
    assert run["n"] == 1_100 and run["max"] == 500.0
    assert 500.0 <= run["p99"] <= 500.0 * 1.06  # an upper bin edge, within 6 %
    assert run["p50"] == 500.0  # capped at the maximum


def test_histogram_percentiles_bound_the_exact_ones_within_a_bin() -> None:
    rng = np.random.default_rng(3)
    v = rng.lognormal(np.log(3e-3), 0.8, 50_000)  # seconds
    lat = Latency(20_000)
    for chunk in np.array_split(v, 200):
        lat.add(chunk)
    run = lat.percentiles_ms()["since_start"]
    for q, key in ((50, "p50"), (99, "p99")):
        exact = np.percentile(v, q) * 1e3
        assert exact <= run[key] <= exact * 1.06 + 1e-9
    assert run["max"] == round(v.max() * 1e3, 3)


def test_counters_invariant_and_health_fields() -> None:
    c = Counters()
    c.reject("bad checksum", 3)
    c.received += 2
    c.decoded += 1
    c.duplicate += 1
    assert c.check()
    h = c.health()
    assert h["received"] == 5 and h["rejected"] == {"bad checksum": 3}
    assert set(h["latency_ms"]) == {"p50", "p99", "since_start"}
    c.late += 1
    assert not c.check()
