"""seatrack.navigate: the docstring examples (the command's values: test_cli_equivalence)."""

from __future__ import annotations

import math
import re

import pytest
from tests.api.examples import run_examples

import seatrack
from seatrack.io.table import InputError


def test_examples():
    run_examples("seatrack.api.navigate")


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"start": (1e9, 0.0, 0.0, 5.0)}, "start x_m = "),
        ({"start": (0.0, 0.0, 0.0, 500.0)}, "start speed_mps = "),
        ({"antenna_period_s": 0.0}, "antenna_period_s = "),
        ({"range_limit_m": math.nan}, "range_limit_m = "),
        ({"antenna_offset_m": 1e6}, "antenna_offset_m = "),
        ({"clutter_density": -1.0}, "clutter_density = "),
        ({"method": "ukf"}, "method must be 'ekf' or 'srif'"),
        ({"origin": (91.0, 0.0)}, "origin lat_deg = "),
    ],
)
def test_errors_name_the_python_argument(options, message):
    kw = {"start": (0.0, 0.0, 0.0, 5.0)} | options
    with pytest.raises(InputError, match=re.escape(message)) as err:
        seatrack.navigate({}, {}, **kw)
    assert "--" not in str(err.value)
