"""Shared test configuration: headless plotting, deterministic hypothesis profile."""

import os

import matplotlib

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

from hypothesis import settings  # noqa: E402

settings.register_profile("ci", max_examples=200, deadline=None, derandomize=True)
settings.load_profile("ci")


def pytest_configure(config):  # type: ignore[no-untyped-def]
    """Under pytest-xdist, compile (or load) every kernel in the controller before the
    workers start: two workers compiling the same gufunc on a cold numba cache can write a
    mismatched pair of cache files that crashes every later load (numba issue #10128;
    see ``seatrack.compiled``)."""
    if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
        from seatrack.compiled import compile_all

        compile_all()
