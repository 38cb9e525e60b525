"""seatrack.tma.config: every TMAConfig field validated, the message naming the field."""

import math

import pytest

from seatrack.tma import TMAConfig


@pytest.mark.parametrize(
    "field, value",
    [
        ("sigma", 0.0),
        ("sigma", math.nan),
        ("sigma", 4.0),
        ("max_iterations", 0),
        ("max_iterations", 2.5),
        ("position_tolerance", -1.0),
        ("position_tolerance", math.inf),
        ("cost_tolerance", 1.0),
        ("lm_lambda0", 0.0),
        ("lm_increase", 1.0),
        ("lm_decrease", 1.5),
        ("lm_lambda_max", 1e-9),
        ("lm_converge_lambda", math.nan),
        ("support_residual", "cubic"),
        ("start_ranges", (500.0, 100.0, 7)),
        ("start_ranges", (500.0, 6e4, 0)),
        ("start_ranges", (math.nan, 6e4, 7)),
        ("start_iterations", -1),
        ("start_max_bearings", 1),
        ("min_observer_deviation", -1.0),
        ("rank_tolerance", 0.0),
        ("rank_tolerance", 1.0),
        ("max_relative_range_sigma", 0.0),
        ("max_relative_range_sigma", math.nan),
        ("residual_test_probability", 1.0),
        ("confidence", 0.0),
    ],
)
def test_bad_values_name_the_field(field, value):
    with pytest.raises(ValueError, match=f"TMAConfig.{field} must be"):
        TMAConfig(**{field: value})


def test_defaults_are_valid_and_inf_disables_the_range_test():
    TMAConfig()
    assert TMAConfig(max_relative_range_sigma=math.inf).max_relative_range_sigma == math.inf
