"""seatrack.evaluate: the docstring examples and the option checks (the command's values:
test_cli_equivalence)."""

from __future__ import annotations

import pytest
from tests.api.examples import run_examples

from seatrack.api.evaluate import EvaluationOptions
from seatrack.api.evaluate import evaluation_options
from seatrack.api.simulate import load
from seatrack.io.table import InputError


def test_examples():
    run_examples("seatrack.api.evaluate")


def test_options_are_checked_by_their_command_line_names():
    """:class:`EvaluationOptions` defaults to the scenario's runs and seed; a bad option is
    an error naming it, before any run."""
    sc = load("linear_cv")
    n, s, sens = evaluation_options(sc, EvaluationOptions())
    assert (n, s) == (sc.runs, sc.seed) and sens.scan_times(sc.duration).size > 3
    assert evaluation_options(sc, EvaluationOptions(runs=2, seed=7))[:2] == (2, 7)
    for bad, name in [({"runs": 0}, "--runs"), ({"processes": 0}, "--processes"),
                      ({"seed": -1}, "--seed"), ({"sensor": "nope"}, "--sensor"),
                      ({"skip": 10**6}, "--skip")]:  # fmt: skip
        with pytest.raises(InputError, match=name):
            evaluation_options(sc, EvaluationOptions(**bad))


def test_multitarget_options_are_checked_by_the_api_and_the_command():
    """A ``[multitarget]`` scenario: bad runs or an unknown method are the same user error
    from :func:`seatrack.evaluate` and from ``seatrack evaluate`` (exit 2), before any run
    (an IndexError and an internal error before)."""
    from tests.cli_inprocess import seatrack as cli

    import seatrack

    for kw, name in (({"runs": 0}, "--runs"), ({"methods": ["foo"]}, "--methods")):
        with pytest.raises(InputError, match=name):
            seatrack.evaluate("coastal_multitarget", **kw)
    res = cli("evaluate", "coastal_multitarget", "--methods", "foo", "--runs", "1")
    assert res.returncode == 2 and "--methods: unknown method 'foo'" in res.stderr
