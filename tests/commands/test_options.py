"""Option checks and output preparation shared by the commands."""

from __future__ import annotations

import math

import pytest

from seatrack.commands.options import option_in
from seatrack.commands.options import option_positive
from seatrack.commands.options import prepare_outputs
from seatrack.io.atomic import OutputError
from seatrack.io.table import InputError


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (math.nan, "--x = nan is not a finite number"),
        (math.inf, "--x = inf is not a finite number"),
        (-1.0, "--x = -1 must be in [0, 10]"),
        (10.5, "--x = 10.5 must be in [0, 10]"),
    ],
)
def test_option_in_names_the_option(value, message):
    with pytest.raises(InputError) as ei:
        option_in("--x", value, 0.0, 10.0)
    assert str(ei.value) == message
    assert option_in("--x", 10.0, 0.0, 10.0) == 10.0


def test_option_positive():
    assert option_positive("--p", 1e300) == 1e300
    for bad in (0.0, -0.0, -1.0, math.nan, math.inf):
        with pytest.raises(InputError, match="--p = "):
            option_positive("--p", bad)
    with pytest.raises(InputError, match=r"must be in \(0, 5\]"):
        option_positive("--p", 6.0, 5.0)


def test_prepare_outputs_creates_folders_and_refuses_bad_paths(tmp_path):
    prepare_outputs([tmp_path / "a" / "x.csv", None], [tmp_path / "b" / "c", None])
    assert (tmp_path / "a").is_dir() and (tmp_path / "b" / "c").is_dir()
    assert not (tmp_path / "a" / "x.csv").exists()
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(OutputError, match="is a file, expected a folder"):
        prepare_outputs(folders=[f])
    with pytest.raises(OutputError, match=f"{f} is a file"):
        prepare_outputs([f / "x.csv"])
    with pytest.raises(OutputError, match="is a directory, expected a file name"):
        prepare_outputs([tmp_path])
