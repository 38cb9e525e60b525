"""Tables from memory read as files are: every kind of table, errors by row."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from tests.api.examples import labelled_plots

import seatrack
from seatrack.api.inputs import read_frame
from seatrack.api.inputs import to_arrow
from seatrack.io.table import InputError


@pytest.mark.parametrize("kind", ["dict", "DataFrame", "pyarrow Table", "path"])
def test_track_reads_every_kind_of_table_alike(kind, tmp_path):
    import pyarrow as pa

    d = labelled_plots()
    frame = pd.DataFrame(d)
    path = tmp_path / "plots.csv"
    frame.to_csv(path, index=False)
    data = {"dict": d, "DataFrame": frame, "pyarrow Table": pa.table(d), "path": path}[kind]
    out = seatrack.track(data, method="ekf")
    ref = seatrack.track(path, method="ekf")
    pd.testing.assert_frame_equal(out, ref)
    assert list(out.columns[:3]) == ["track", "time_s", "x_m"]


def test_a_bad_table_is_reported_by_row_like_a_bad_file(tmp_path):
    d = labelled_plots()
    d["range_m"] = d["range_m"].copy()
    d["range_m"][3] = -5.0
    with pytest.raises(InputError, match=r"^plots \(DataFrame\), row 3: range_m must be > 0"):
        seatrack.track(pd.DataFrame(d))
    path = tmp_path / "plots.csv"
    pd.DataFrame(d).to_csv(path, index=False)
    with pytest.raises(InputError, match=rf"^{path}, line 5: range_m must be > 0"):
        seatrack.track(path)


def test_a_table_that_is_not_one_is_refused():
    with pytest.raises(InputError, match=r"plots \(dict\): column 'a' must be 1-D"):
        to_arrow({"a": np.zeros((2, 2))}, "plots")
    with pytest.raises(InputError, match=r"column 'b' has 3 values, the others 2"):
        to_arrow({"a": [1.0, 2.0], "b": [1.0, 2.0, 3.0]}, "plots")
    with pytest.raises(InputError, match="expected a file path, a pandas DataFrame"):
        seatrack.track(42)


def test_read_frame_keeps_text_and_exact_numbers(tmp_path):
    path = tmp_path / "f.csv"
    path.write_text("track,x\n007,0.1\n,\n")
    frame = read_frame(path, ("track",))
    assert frame["track"].tolist() == ["007", ""]
    assert frame["x"].iloc[0] == 0.1 and np.isnan(frame["x"].iloc[1])
