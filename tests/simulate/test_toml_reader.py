"""TomlReader: typed TOML values, errors naming file and key path, unit-suffix limits."""

from __future__ import annotations

import math

import pytest

from seatrack.io.table import InputError
from seatrack.simulate.toml_reader import SUFFIX_LIMITS
from seatrack.simulate.toml_reader import TomlReader
from seatrack.simulate.toml_reader import describe
from seatrack.simulate.toml_reader import suffix_limit

R = TomlReader("s.toml")


def test_suffix_limits():
    assert suffix_limit("x_m") == 1e8 and suffix_limit("t_s") == pytest.approx(4.1e9, rel=1e-2)
    assert suffix_limit("a_mps2") == 1e3 and suffix_limit("v_mps") == 1e4
    assert suffix_limit("turn_rate_dps") == 3600 and suffix_limit("q") == math.inf
    assert [s for s, _ in SUFFIX_LIMITS][:2] == ["_mps2", "_mps"]  # longest suffix first


@pytest.mark.parametrize(
    ("tab", "kw", "message"),
    [
        ({"range_m": 2e8}, {}, "s.toml: p.range_m: 2e+08 is implausibly large"),
        ({"range_m": math.nan}, {}, "s.toml: p.range_m: must be finite"),
        ({"range_m": "abc"}, {}, "s.toml: p.range_m: expected a number, got string 'abc'"),
        ({"range_m": True}, {}, "expected a number, got boolean true"),
        ({"range_m": 0}, {"positive": True}, "must be > 0, got 0"),
        ({"range_m": 5}, {"maximum": 4.0}, "must be <= 4, got 5"),
        ({"range_m": 10**400}, {}, "is too large"),
        ({}, {"required": True}, "p.range_m: missing required key"),
    ],
)
def test_number_errors(tab, kw, message):
    with pytest.raises(InputError) as ei:
        R.number(tab, "p", "range_m", **kw)
    assert message in str(ei.value)


def test_number_integer_string_vector_ok():
    assert R.number({"q": 1e30}, "", "q") == 1e30  # no unit suffix: no limit
    assert R.integer({"n": 3}, "", "n", 0, 1, 5) == 3
    with pytest.raises(InputError, match="n: must be <= 5, got 6"):
        R.integer({"n": 6}, "", "n", 0, 1, 5)
    assert R.string({}, "", "s", default="d") == "d"
    assert R.vector({"position_m": [1, 2.5]}, "", "position_m", (2, 3)).tolist() == [1, 2.5]
    for bad in ([1e300, 0], [math.inf, 0], ["a", 0], [True, 0]):
        with pytest.raises(InputError, match=r"position_m\[0\]: expected a finite number"):
            R.vector({"position_m": bad}, "", "position_m", (2,))
    assert describe([1, 2]) == "a list of 2 items" and describe({}) == "a table"
