"""How the package compiles its generalised ufuncs: :func:`gufunc`, one place for the
options every ``numba.guvectorize`` kernel of seatrack shares.

Every kernel is compiled

* with one explicit signature, so that importing its module compiles it at once (what
  :func:`seatrack.compiled.compile_all` relies on to compile every kernel in one process
  before worker processes start: numba issue #10128);
* in nopython mode (a kernel that would fall back to object mode is an error, not a slow
  loop);
* with numba's on-disk cache (``cache=True``): a later process loads the kernel instead of
  compiling it again. The cache is keyed by the kernel function's own file and line, so a
  kernel decorated here is cached beside its module as before.

This module imports numba only, so that any layer may use it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from numba import guvectorize

__all__ = ["gufunc"]


def gufunc(signature: str, layout: str) -> Callable[[Callable[..., None]], Any]:
    """Decorator compiling a kernel into a NumPy generalised ufunc (eagerly, nopython,
    cached on disk).

    Parameters
    ----------
    signature : str
        The numba type signature of the kernel, e.g. ``"void(f8[:], f8[:,:], f8[:])"``
        (outputs are the last arguments, written in place).
    layout : str
        The gufunc layout of the core dimensions, e.g. ``"(m),(m,m)->()"``.

    Returns
    -------
    callable
        A decorator turning ``kernel`` into the compiled gufunc
        (``numba.guvectorize([signature], layout, nopython=True, cache=True)``).
    """
    return guvectorize([signature], layout, nopython=True, cache=True)
