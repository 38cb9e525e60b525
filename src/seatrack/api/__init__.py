"""The public Python API of seatrack: one function per command of the command line.

:func:`~seatrack.api.tma.tma`, :func:`~seatrack.api.track.track`,
:func:`~seatrack.api.ais.ais`, :func:`~seatrack.api.navigate.navigate`,
:func:`~seatrack.api.simulate.simulate`, :func:`~seatrack.api.evaluate.evaluate`,
:func:`~seatrack.api.fuse.fuse` and :class:`~seatrack.api.sensor.Sensor`, exported by the
``seatrack`` package. Tables come in as paths, pandas DataFrames, pyarrow Tables or dicts
of arrays with the CSV column names (:mod:`seatrack.api.inputs`) and are read by the
commands' readers; results go out as pandas DataFrames with the columns of the commands'
files. The commands
(:mod:`seatrack.commands`) parse their options, call these functions and write the results.
"""
