"""The bounded-memory AIS pipeline: the output does not depend on the vessel groups, on the
number of threads, nor on CSV or Parquet; memory-limit parsing; atomic TRACKS."""

from __future__ import annotations

from pathlib import Path

import numba
import numpy as np
import pyarrow.parquet as pq
import pytest

from ais_samples import data_file
from seatrack.filters.ais import AisTrackerConfig
from seatrack.filters.ais import track_reports
from seatrack.io.ais import read_ais
from seatrack.io.ais import track_files
from seatrack.io.budget import parse_size
from seatrack.io.table import InputError

FILES = ["dk_northsea_20221101_1h_selected.csv", "us_boston_201401_trajectools.csv"]


def test_vessel_groups_give_the_output_of_one_group(tmp_path: Path) -> None:
    files = [data_file(f) for f in FILES]
    one = track_files(files, tmp_path / "one.csv")
    many = track_files(files, tmp_path / "many.csv", group_rows=2000)
    assert one.groups == 1 and many.groups > 5
    assert (tmp_path / "one.csv").read_bytes() == (tmp_path / "many.csv").read_bytes()
    assert one.lines() == many.lines()
    track_files(files, tmp_path / "one.parquet")
    track_files(files, tmp_path / "many.parquet", group_rows=2000)
    a, b = pq.read_table(tmp_path / "one.parquet"), pq.read_table(tmp_path / "many.parquet")
    assert a.equals(b)
    # the same values in CSV and Parquet
    rows = (tmp_path / "one.csv").read_text().splitlines()
    assert len(rows) == a.num_rows + 1
    lat = np.array([float(x) if x else np.nan for x in a.column("lat").to_pylist()])
    csv_lat = np.array([float(r.split(",")[2]) if r.split(",")[2] else np.nan for r in rows[1:]])
    assert np.allclose(np.round(lat, 7), csv_lat, equal_nan=True, rtol=0, atol=1e-9)


def test_results_do_not_depend_on_the_number_of_threads() -> None:
    r = read_ais([data_file(FILES[0])])
    cfg = AisTrackerConfig()
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba has one thread here")
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        a = track_reports(r, cfg)
        numba.set_num_threads(2)
        b = track_reports(r, cfg)
    finally:
        numba.set_num_threads(old)
    for f in a.__dataclass_fields__:
        assert np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True), f


@pytest.mark.parametrize(
    ("text", "value"), [("1G", 1 << 30), ("800M", 800 << 20), ("2gb", 2 << 30), ("1.5G", 3 << 29)]
)
def test_memory_limit_sizes(text: str, value: int) -> None:
    assert parse_size(text) == value


@pytest.mark.parametrize("text", ["", "lots", "-1G", "10K", "nan"])
def test_memory_limit_errors_name_the_option(text: str) -> None:
    with pytest.raises(InputError, match="--memory-limit"):
        parse_size(text)
