"""seatrack.tma: the docstring examples (the command's values: test_cli_equivalence)."""

from __future__ import annotations

import math
import re

import pytest
from tests.api.examples import run_examples

import seatrack
from seatrack.io.table import InputError


def test_examples():
    run_examples("seatrack.api.tma")


BEARINGS = {
    "time_s": [0.0, 10.0, 20.0],
    "bearing_deg": [10.0, 11.0, 12.0],
    "observer_x_m": [0.0, 50.0, 100.0],
    "observer_y_m": [0.0, 0.0, 0.0],
}


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"sigma_deg": 0.0}, "sigma_deg must be"),
        ({"sound_speed_mps": 0.0}, "sound_speed_mps must be a number of m/s"),
        ({"atb_sigma_deg": math.inf}, "atb_sigma_deg must be a number of degrees"),
        ({"range_sigma_m": -1.0}, "range_sigma_m must be a number of metres"),
        ({"frequency_sigma_hz": -0.1}, "frequency_sigma_hz"),
    ],
)
def test_errors_name_the_python_argument(options, message):
    with pytest.raises(InputError, match=re.escape(message)) as err:
        seatrack.tma(BEARINGS, **options)
    assert "--" not in str(err.value)
