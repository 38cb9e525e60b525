"""The work budget (seatrack.io.budget): sizes and durations parsed, runs over the budget
refused with the cause and the way to raise it, long runs noted."""

from __future__ import annotations

import pytest

from seatrack.io.budget import DEFAULT_MEMORY_BYTES
from seatrack.io.budget import budget
from seatrack.io.budget import current
from seatrack.io.budget import format_bytes
from seatrack.io.budget import parse_duration
from seatrack.io.budget import parse_size
from seatrack.io.budget import require
from seatrack.io.table import InputError


@pytest.mark.parametrize(
    ("text", "value"), [("1G", 1 << 30), ("800M", 800 << 20), ("2gb", 2 << 30), ("1.5G", 3 << 29)]
)
def test_sizes(text, value):
    assert parse_size(text) == value


@pytest.mark.parametrize("text", ["", "lots", "-1G", "10K", "nan", "1e400"])
def test_bad_sizes_name_the_option(text):
    with pytest.raises(InputError, match="^--memory-limit: "):
        parse_size(text)


@pytest.mark.parametrize(("text", "s"), [("90", 90), ("90s", 90), ("30min", 1800), ("2h", 7200)])
def test_durations(text, s):
    assert parse_duration(text) == s


@pytest.mark.parametrize("text", ["", "0", "-1h", "soon", "5 years"])
def test_bad_durations_name_the_option(text):
    with pytest.raises(InputError, match="^--time-limit: "):
        parse_duration(text)


def test_over_the_memory_budget_is_refused_with_cause_and_remedy():
    with budget(memory_bytes=1 << 30):
        require("x: 10 runs", memory_bytes=1 << 30)  # at the budget: accepted
        with pytest.raises(InputError) as exc:
            require("x: 11 runs", memory_bytes=(1 << 30) + 1)
    msg = str(exc.value)
    assert msg.startswith("x: 11 runs needs about 1.07 GB of memory, over the budget of 1.07 GB")
    assert "seatrack --memory-limit" in msg
    assert current().memory_bytes == DEFAULT_MEMORY_BYTES  # the block's budget is gone


def test_over_the_time_budget_is_refused_within_it_silent(capsys):
    with budget(time_s=600):
        require("y", seconds=599)  # a long run is announced by seatrack.progress, not here
        assert capsys.readouterr().err == ""
        with pytest.raises(
            InputError, match="would take about 10.2 min, over the budget of 10 min"
        ):
            require("y", seconds=612)
    with pytest.raises(InputError, match="of memory"):
        require("z", memory_bytes=float("inf"))


def test_format_bytes():
    assert [format_bytes(n) for n in (12, 12e3, 1.5e6, 2.25e9)] == [
        "12 B", "12 kB", "1.5 MB", "2.25 GB"]  # fmt: skip
