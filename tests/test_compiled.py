"""seatrack.compiled: every module imported (and so every gufunc compiled) in one call."""

import sys
from pathlib import Path

import seatrack
from seatrack.compiled import compile_all


def test_every_module_of_the_package_is_imported():
    names = compile_all()
    root = Path(seatrack.__file__).parent
    files = {
        "seatrack." + ".".join(p.relative_to(root).with_suffix("").parts)
        for p in root.rglob("*.py")
        if p.name not in ("__init__.py", "__main__.py")
    }
    assert files <= set(names)
    assert all(name in sys.modules for name in names)
    assert not any(name.endswith("__main__") for name in names)
