"""Counters of the live process and the latency from datagram to picture.

Every AIS message received is counted once, in ``received``, and once in exactly one of
``decoded`` (used: a position report folded into the picture, or another message type
decoded), ``duplicate`` (the same message from another receiver, or repeated), ``late``
(older than the vessel's out-of-order window) and ``rejected`` (by reason), so that
``received = decoded + duplicate + late + rejected`` whenever the counters are read (they
change together, between two awaits of the one asyncio thread). A message is one
sentence, or the fragments of a multi-sentence message once complete; a line rejected on
its own (bad checksum, not NMEA, ...) is one message. Radar plots have their own counters.
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

__all__ = ["Counters", "Latency"]


#: edges (s) of the since-start latency histogram: 1 us to 100 s, 40 bins a decade (each
#: bin 6 % wide), the last bin open
_EDGES = np.logspace(-6, 2, 8 * 40 + 1)


class Latency:
    """The last ``size`` latencies (s) in a ring, and a histogram of every latency since
    the start; percentiles in ms.

    The ring gives the current figures (the last ``size`` values); the histogram the
    figures of the whole run, each percentile as the upper edge of its bin (at most 6 %
    above the exact value), with the exact maximum.
    """

    def __init__(self, size: int = 20_000) -> None:
        self._ring = np.zeros(size)
        self._n = 0
        self._hist = np.zeros(_EDGES.size + 1, np.int64)
        self._max = 0.0

    def add(self, values: Any) -> None:
        """Record latencies (s)."""
        every = np.atleast_1d(np.asarray(values, dtype=float))
        if every.size == 0:
            return
        self._hist += np.bincount(np.searchsorted(_EDGES, every), minlength=self._hist.size)
        self._max = max(self._max, float(every.max()))
        v = every[-self._ring.size :]
        k = self._n % self._ring.size
        first = min(v.size, self._ring.size - k)
        self._ring[k : k + first] = v[:first]
        self._ring[: v.size - first] = v[first:]
        self._n += every.size

    def percentiles_ms(self) -> dict[str, Any]:
        """``{"p50": ms, "p99": ms, "since_start": {"p50", "p99", "max", "n"}}``: the
        percentiles of the last recorded latencies, and those of every latency since the
        start (None before any)."""
        if self._n == 0:
            return {"p50": None, "p99": None,
                    "since_start": {"p50": None, "p99": None, "max": None, "n": 0}}  # fmt: skip
        r = self._ring[: min(self._n, self._ring.size)]
        p50, p99 = np.percentile(r, [50, 99]) * 1e3
        cum = np.cumsum(self._hist)
        upper = np.r_[_EDGES, np.inf]  # upper edge of each bin (s)
        h50, h99 = (min(upper[np.searchsorted(cum, q * self._n)], self._max) * 1e3
                    for q in (0.5, 0.99))  # fmt: skip
        return {"p50": round(float(p50), 3), "p99": round(float(p99), 3),
                "since_start": {"p50": round(h50, 3), "p99": round(h99, 3),
                                "max": round(self._max * 1e3, 3), "n": self._n}}  # fmt: skip


class Counters:
    """AIS message counters, radar counters and display drops (see the module docstring)."""

    def __init__(self) -> None:
        self.received = 0
        self.decoded = 0
        self.duplicate = 0
        self.late = 0
        self.rejected: Counter[str] = Counter()
        self.positions = 0
        self.plots_received = 0
        self.plots_rejected: Counter[str] = Counter()
        self.scans = 0
        self.display_drops = 0
        self.reconnects = 0
        self.nmea_out_errors = 0
        self.nmea_out_not_sent = 0  # track-scans beyond the 99 TTM target numbers
        self.latency = Latency()
        self.scan_latency = Latency(2_000)

    def reject(self, reason: str, n: int = 1) -> None:
        """``n`` messages received and rejected for ``reason``."""
        self.received += n
        self.rejected[reason] += n

    def check(self) -> bool:
        """The invariant ``received = decoded + duplicate + late + rejected``."""
        total = self.decoded + self.duplicate + self.late + sum(self.rejected.values())
        return self.received == total

    def health(self) -> dict[str, Any]:
        """The counters as the ``/api/health`` JSON fields."""
        return {
            "received": self.received,
            "decoded": self.decoded,
            "duplicate": self.duplicate,
            "late": self.late,
            "rejected": dict(sorted(self.rejected.items())),
            "positions": self.positions,
            "latency_ms": self.latency.percentiles_ms(),
            "plots": {
                "received": self.plots_received,
                "rejected": dict(sorted(self.plots_rejected.items())),
                "scans": self.scans,
                "scan_ms": self.scan_latency.percentiles_ms(),
            },
            "display_drops": self.display_drops,
            "reconnects": self.reconnects,
            "nmea_out_errors": self.nmea_out_errors,
            "nmea_out_not_sent": self.nmea_out_not_sent,
        }
