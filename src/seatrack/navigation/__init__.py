"""seatrack.navigation: own-ship positioning from radar echoes of mapped landmarks
(JP H03-66630, spec ``landmark_nav.md``).

Modules: :mod:`~seatrack.navigation.landmarks` (map, CSV and binary records),
:mod:`~seatrack.navigation.window` (active window FIRST/NBR),
:mod:`~seatrack.navigation.schedule` (next landmark, JUMP counters),
:mod:`~seatrack.navigation.echoes` (gate, echo weights, weighted measurement),
:mod:`~seatrack.navigation.filter` (state, prediction, measurement rows, Kalman and SRIF),
:mod:`~seatrack.navigation.navigator` (the loop over an echo log),
:mod:`~seatrack.navigation.survey` (map corrections from passages).
The files (ECHOES.csv, GYRO.csv, NAV.csv; MAP.csv) are read and written by
:mod:`seatrack.io.navigation` and :mod:`seatrack.io.landmarks`.
The echo simulator is :mod:`seatrack.simulate.radar_echoes`.
"""
