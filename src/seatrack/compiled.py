"""Compile (or load from numba's cache) every kernel of the package in THIS process.

numba writes a ``@guvectorize`` kernel to its on-disk cache as two files (the kernel and
its gufunc wrapper). When two processes compile the same kernel at the same time on a cold
cache, the two files can come from different processes whose internal ABI tags differ,
and every later load of that pair crashes with a segmentation fault (numba issue #10128,
open in numba 0.68). Our gufuncs have explicit signatures, so importing a module compiles
and caches them at once: importing every module here, before worker processes start
(the demo's and the Monte-Carlo's process pools, pytest-xdist workers), leaves the workers
nothing to compile concurrently.
"""

from __future__ import annotations

import importlib
import pkgutil

__all__ = ["compile_all"]


def compile_all() -> list[str]:
    """Import every module of ``seatrack`` (``__main__`` excepted); returns their names."""
    import seatrack

    names = [
        m.name
        for m in pkgutil.walk_packages(seatrack.__path__, prefix="seatrack.")
        if not m.name.endswith("__main__")
    ]
    for name in names:
        importlib.import_module(name)
    return names
