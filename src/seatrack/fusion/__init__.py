"""Radar and AIS fused into one identified picture (``seatrack fuse``; docs/fusion.md).

* :mod:`~seatrack.fusion.coverage` -- where the radar can see: range, blind sectors,
  radar horizon, land shadow;
* :mod:`~seatrack.fusion.anomalies` -- AIS reporting gaps, shared MMSIs split into
  trajectories, implausible jumps;
* :mod:`~seatrack.fusion.associate` -- radar tracks and AIS vessels associated scan by
  scan, with hysteresis (the default ``track`` design);
* :mod:`~seatrack.fusion.measurement` -- the ``measurement`` design: AIS reports update
  the radar tracks they are associated with;
* :mod:`~seatrack.fusion.picture` -- the whole run: the tables of the picture;
* :mod:`~seatrack.fusion.scenario` -- simulated plots and corrupted AIS for tests and the
  benchmark.
"""
