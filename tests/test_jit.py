"""seatrack.jit: the one decorator of the package's generalised ufuncs."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

from seatrack.jit import gufunc

SRC = Path(__file__).resolve().parents[1] / "src" / "seatrack"


@gufunc("void(f8[:], f8[:], f8[:])", "(n),(n)->()")
def _dot_kernel(a, b, out):  # pragma: no cover - compiled
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    out[0] = s


def test_gufunc_broadcasts_over_leading_axes() -> None:
    a = np.arange(12.0).reshape(4, 3)
    b = np.array([1.0, -2.0, 0.5])
    np.testing.assert_array_equal(_dot_kernel(a, b), a @ b)


def test_gufunc_compiles_eagerly_in_nopython_mode_with_the_disk_cache() -> None:
    assert not _dot_kernel.is_dynamic  # compiled at decoration: one explicit signature
    assert _dot_kernel.types == ["dd->d"]
    assert _dot_kernel.signature == "(n),(n)->()"
    builder = _dot_kernel.gufunc_builder
    assert builder.cache is True
    assert builder.targetoptions["nopython"] is True


def test_every_gufunc_of_the_package_goes_through_jit() -> None:
    users = []
    for p in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module == "numba":
                if any(a.name == "guvectorize" for a in node.names):
                    users.append(p.relative_to(SRC).as_posix())
    assert users == ["jit.py"]
