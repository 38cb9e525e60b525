"""seatrack: maritime and radar target tracking and navigation.

Bearings-only target motion analysis, multiple-model, robust-adaptive and turning-target
filters, landmark navigation and AIS tracking on one Kalman core. x East, y North, z Up;
SI units and radians inside; bearings clockwise from North; degrees, knots and the
unit-suffixed column names of the files at the edges.

The public API (one function per command of the ``seatrack`` command line, with the same
inputs and the same output columns):

* :func:`tma` -- bearings-only target motion analysis (:class:`TMAResult`);
* :func:`track` -- a tracking filter over radar / sonar plots, or the multi-target tracker
  for plots without track labels (:class:`Sensor` for the measurement noise);
* :func:`ais` -- clean and smooth AIS tracks;
* :func:`navigate` -- own-ship position from radar echoes of mapped landmarks;
* :func:`simulate`, :func:`evaluate` -- scenarios and Monte-Carlo comparisons;
* :func:`fuse` -- one picture from radar plots and AIS: identities, dark vessels, AIS
  positions the radar does not see, shared MMSIs;
* :class:`Tracker` and its roles (:class:`Associator`, :class:`Initiator`,
  :class:`TrackManager`) -- the multi-target tracker, built from swappable parts.

Inputs are paths, pandas DataFrames, pyarrow Tables or dicts of arrays with the CSV column
names; outputs are pandas DataFrames with the CSV columns. The names are loaded on first
use: ``import seatrack`` compiles nothing and imports no plotting library.
"""

from __future__ import annotations

import importlib
import sys
import types

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (20 ms)

__version__ = "0.1.0"

#: public name -> module that defines it (imported on first access)
_LAZY: dict[str, str] = {
    "tma": "seatrack.api.tma",
    "TMAResult": "seatrack.api.tma",
    "track": "seatrack.api.track",
    "ais": "seatrack.api.ais",
    "navigate": "seatrack.api.navigate",
    "simulate": "seatrack.api.simulate",
    "evaluate": "seatrack.api.evaluate",
    "fuse": "seatrack.api.fuse",
    "Sensor": "seatrack.api.sensor",
    "UserError": "seatrack.errors",
    "Tracker": "seatrack.tracking.roles",
    "Associator": "seatrack.tracking.roles",
    "Initiator": "seatrack.tracking.roles",
    "TrackManager": "seatrack.tracking.roles",
    "GNN": "seatrack.tracking.roles",
    "JPDA": "seatrack.tracking.roles",
    "TwoPointInitiator": "seatrack.tracking.roles",
    "ExistenceManager": "seatrack.tracking.roles",
    "MofNManager": "seatrack.tracking.roles",
}

#: the public names: the version and every lazily loaded name
__all__ = ["__version__", *_LAZY]

if TYPE_CHECKING:  # the names for type checkers (``X as X``: re-exported)
    from typing import Any

    from seatrack.api.ais import ais as ais
    from seatrack.api.evaluate import evaluate as evaluate
    from seatrack.api.fuse import fuse as fuse
    from seatrack.api.navigate import navigate as navigate
    from seatrack.api.sensor import Sensor as Sensor
    from seatrack.api.simulate import simulate as simulate
    from seatrack.api.tma import TMAResult as TMAResult
    from seatrack.api.tma import tma as tma
    from seatrack.api.track import track as track
    from seatrack.errors import UserError as UserError


def _function_over_package(name: str) -> property:
    """A property giving the API function ``name`` and ignoring the sub-package of the same
    name that the import system binds on the ``seatrack`` module when it imports it."""

    def get(self: types.ModuleType) -> Any:
        return getattr(importlib.import_module(_LAZY[name]), name)

    def ignore(self: types.ModuleType, value: Any) -> None:
        """The sub-package stays importable by its full name (``seatrack.tma.solver``)."""

    return property(get, ignore)


class _Package(types.ModuleType):
    """The ``seatrack`` module: ``tma``, ``simulate`` and ``evaluate`` are the API functions,
    not the sub-packages of the same names."""

    tma = _function_over_package("tma")
    simulate = _function_over_package("simulate")
    evaluate = _function_over_package("evaluate")


sys.modules[__name__].__class__ = _Package


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'seatrack' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
