"""The tma package: no import cycle between its modules, no private name imported from
another module, and nothing imported from the layers above it (evaluate, io, simulate,
report, commands, filters, navigation, tracking) -- checked on the source with ``ast``."""

import ast
import importlib
from pathlib import Path

# the package by its full name (``seatrack.tma`` on the seatrack module is the API function)
PKG = Path(importlib.import_module("seatrack.tma").__file__).parent
ABOVE = ("evaluate", "io", "simulate", "report", "commands", "filters", "navigation", "tracking")


def _imports(path: Path) -> list[ast.ImportFrom]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [
        n
        for n in ast.walk(tree)
        if isinstance(n, ast.ImportFrom) and n.module and n.module.startswith("seatrack")
    ]


def test_tma_layering_and_no_cycles():
    graph: dict[str, set[str]] = {}
    for p in PKG.glob("*.py"):
        name = p.stem
        graph[name] = set()
        for node in _imports(p):
            parts = node.module.split(".")
            assert not (len(parts) > 1 and parts[1] in ABOVE), (name, node.module)
            assert not any(a.name.startswith("_") for a in node.names), (name, node.module)
            if parts[:2] == ["seatrack", "tma"] and len(parts) == 3:
                graph[name].add(parts[2])
    graph.pop("__init__")
    done: set[str] = set()

    def visit(u: str, path: tuple[str, ...]) -> None:
        assert u not in path, f"import cycle {' -> '.join(path + (u,))}"
        if u in done:
            return
        for v in graph.get(u, ()):
            visit(v, path + (u,))
        done.add(u)

    for m in graph:
        visit(m, ())
