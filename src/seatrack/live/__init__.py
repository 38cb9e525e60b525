"""``seatrack live``: AIS and radar streams in, a tracked picture out, in real time.

Modules: :mod:`~seatrack.live.sources` (UDP, TCP, FILE sources), :mod:`~.nmea` (NMEA
checks, tag blocks, multi-part reassembly, duplicates, decoding), :mod:`~.ais` (per-vessel
causal AIS tracking with the out-of-order window), :mod:`~.radar` (scans and the
multi-target tracker), :mod:`~.picture` (GeoJSON picture), :mod:`~.counters`,
:mod:`~.web` (map, API, WebSocket), :mod:`~.process` (the asyncio wiring). See
docs/live.md.
"""
