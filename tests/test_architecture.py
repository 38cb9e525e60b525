"""The layering of ``src/seatrack``, checked by parsing every module's imports with ``ast``.

Layers point one way (a module imports only from its own layer or lower ones)::

    0  geometry, kalman, models, config, information, jit, data, errors, progress   (foundations)
    1  filters, tma, navigation                    (estimators)
    2  tracking                                    (multi-target tracking)
    3  io                                          (file formats: readers and writers)
    4  simulate, evaluate                          (scenarios, statistics; they use io)
    5  report, live, fusion                        (live: the streaming process)
    6  api                                         (the public Python API)
    7  commands, cli
    8  the ``seatrack`` package itself (its public names come from the api)

``io`` sits below ``simulate`` and ``evaluate``: a file format depends on the estimators'
types only, while a simulator reads scenario files and real data (the AIS replay) and the
evaluation reads and writes results. The simulator's own output files (plots and truth of
a simulated run) are written by :mod:`seatrack.simulate.files`.

and, besides: no import cycle between modules or between packages, no private name
(``_name``) imported from another module, no module over 800 lines, at most three functions
over 120 lines (compiled kernels included).

``KNOWN_*`` list the violations that other work in progress removes, each with its owner;
delete an entry when its fix is merged -- the test then keeps it fixed. An entry that no
longer occurs makes the test fail too, so the lists cannot go stale.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "seatrack"

LAYERS: dict[str, int] = {
    "geometry": 0,
    "kalman": 0,
    "models": 0,
    "config": 0,
    "information": 0,
    "compiled": 0,
    "jit": 0,
    "data": 0,
    "errors": 0,
    "progress": 0,
    "filters": 1,
    "tma": 1,
    "navigation": 1,
    "tracking": 2,
    "io": 3,
    "simulate": 4,
    "evaluate": 4,
    "report": 5,
    "live": 5,
    "fusion": 5,
    "api": 6,
    "commands": 7,
    "cli": 7,
    # the package itself: the public names, loaded from the api on first use
    "seatrack": 8,
}
MAX_LINES = 800
LONG_FUNCTION = 120
MAX_LONG_FUNCTIONS = 3

# --- known violations, owned by work in progress (delete each when fixed) -------------------
#: (importer, imported) module edges that break the layer order
KNOWN_LAYER_BREAKS: set[tuple[str, str]] = set()
#: module-level import cycles (each a frozenset of modules)
KNOWN_MODULE_CYCLES: set[frozenset[str]] = set()
#: package-level cycles (each a frozenset of top-level packages)
KNOWN_PACKAGE_CYCLES: set[frozenset[str]] = set()
#: (importer, module, name) private imports across modules
KNOWN_PRIVATE_IMPORTS: set[tuple[str, str, str]] = set()
#: modules over MAX_LINES
KNOWN_BIG_MODULES: set[str] = set()
#: functions allowed over LONG_FUNCTION lines (at most MAX_LONG_FUNCTIONS), with the reason
ALLOWED_LONG_FUNCTIONS = {
    # one compiled loop: split into helpers taking the named tuples it ran 1.7-2x slower
    # (measured; see its docstring)
    ("seatrack.filters.ais.kernel", "_track_flat"),
}
#: (module, function) over LONG_FUNCTION lines that work in progress shortens
KNOWN_LONG_FUNCTIONS: set[tuple[str, str]] = set()


def _modules() -> dict[str, Path]:
    out = {}
    for p in sorted(SRC.rglob("*.py")):
        parts = p.relative_to(SRC.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = p
    return out


MODULES = _modules()
TREES = {name: ast.parse(p.read_text(encoding="utf-8")) for name, p in MODULES.items()}


def _resolve(name: str, importer: str) -> str | None:
    """The seatrack module an import refers to (longest known prefix), or None."""
    if not name.startswith("seatrack"):
        return None
    parts = name.split(".")
    while parts:
        cand = ".".join(parts)
        if cand in MODULES:
            return cand
        parts.pop()
    return None


def _imports(name: str) -> Iterator[tuple[str, str | None]]:
    """(imported module, imported name or None) of every import in module ``name``."""
    for node in ast.walk(TREES[name]):
        if isinstance(node, ast.Import):
            for a in node.names:
                m = _resolve(a.name, name)
                if m:
                    yield m, None
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for a in node.names:
                sub = _resolve(f"{node.module}.{a.name}", name)
                m = sub if sub and sub != _resolve(node.module, name) else None
                if m:  # ``from seatrack.filters import base``: the submodule itself
                    yield m, None
                else:
                    target = _resolve(node.module, name)
                    if target:
                        yield target, a.name


def _graph() -> dict[str, set[str]]:
    g: dict[str, set[str]] = defaultdict(set)
    for name in MODULES:
        for m, _ in _imports(name):
            if m != name and m != "seatrack":
                g[name].add(m)
    return g


def _package(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "seatrack"


def _cycles(graph: dict[str, set[str]]) -> set[frozenset[str]]:
    """Strongly connected components with more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: set[frozenset[str]] = set()
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.add(frozenset(comp))

    for v in list(graph):
        if v not in index:
            visit(v)
    return out


def _check(found: set, known: set, what: str) -> None:
    new = sorted(sorted(v) if isinstance(v, frozenset) else v for v in found - known)
    assert not new, f"new {what}: {new}"
    fixed = known - found
    assert not fixed, f"fixed {what} still listed as known (delete them): {fixed}"


def test_every_package_has_a_layer():
    pkgs = {_package(m) for m in MODULES} - {"seatrack"}
    assert pkgs <= set(LAYERS), pkgs - set(LAYERS)


def test_layers_point_one_way():
    breaks = set()
    for a, targets in _graph().items():
        for b in targets:
            if LAYERS[_package(b)] > LAYERS[_package(a)]:
                breaks.add((a, b))
    _check(breaks, KNOWN_LAYER_BREAKS, "layer breaks (importer, imported)")


def test_no_module_cycles():
    _check(_cycles(_graph()), KNOWN_MODULE_CYCLES, "module import cycles")


def test_no_package_cycles():
    pg: dict[str, set[str]] = defaultdict(set)
    for a, targets in _graph().items():
        for b in targets:
            if _package(a) != _package(b) and "seatrack" not in (_package(a), _package(b)):
                pg[_package(a)].add(_package(b))
    _check(_cycles(pg), KNOWN_PACKAGE_CYCLES, "package import cycles")


def test_no_private_names_imported_from_another_module():
    found = set()
    for name in MODULES:
        for m, n in _imports(name):
            if n and n.startswith("_") and not n.startswith("__") and m != name:
                found.add((name, m, n))
    _check(found, KNOWN_PRIVATE_IMPORTS, "private cross-module imports")


def test_module_size():
    big = {n for n, p in MODULES.items() if len(p.read_text().splitlines()) > MAX_LINES}
    _check(big, KNOWN_BIG_MODULES, f"modules over {MAX_LINES} lines")


def test_long_functions():
    long = set()
    for name, tree in TREES.items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                assert node.end_lineno is not None
                if node.end_lineno - node.lineno + 1 > LONG_FUNCTION:
                    long.add((name, node.name))
    _check(long - ALLOWED_LONG_FUNCTIONS, KNOWN_LONG_FUNCTIONS, f"functions over {LONG_FUNCTION}")
    assert len(ALLOWED_LONG_FUNCTIONS) <= MAX_LONG_FUNCTIONS
    assert ALLOWED_LONG_FUNCTIONS <= long, "an allowed long function is short now: delete it"


@pytest.mark.parametrize("pkg", ["filters", "navigation", "models"])
def test_estimators_import_no_io(pkg):
    """The estimators build on the foundations only (filters take base.Plots, not files)."""
    for name in MODULES:
        if _package(name) != pkg:
            continue
        for m, _ in _imports(name):
            if (name, m) in KNOWN_LAYER_BREAKS:
                continue
            assert _package(m) not in ("io", "simulate", "evaluate", "report", "commands"), (
                name,
                m,
            )
