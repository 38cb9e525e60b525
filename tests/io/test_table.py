import numpy as np
import pytest

from seatrack.io.table import InputError, check_times, read_csv_table


def _write(tmp_path, text, name="m.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_reads_required_optional_and_extra(tmp_path):
    p = _write(tmp_path, "time_s,value,extra,note\n0,1.5,x,a\n1,2.5,y,\n")
    t = read_csv_table(p, ["time_s", "value"], ["note", "sigma"], text=["note"])
    np.testing.assert_allclose(t["value"], [1.5, 2.5])
    assert t["note"].tolist() == ["a", ""]
    assert "sigma" not in t and "extra" not in t
    assert t.lines.tolist() == [2, 3] and t.n_read == 2


@pytest.mark.parametrize(
    "text,msg",
    [
        ("time_s\n0\n", "missing required column.*value"),
        ("time_s,value\n0,nan\n", "line 2: column value = 'nan' is not a finite number"),
        ("time_s,value\n0,1\n1,inf\n", "line 3: column value = 'inf' is not a finite"),
        ("time_s,value\n0,abc\n", "line 2: column value = 'abc' is not a number"),
        ("time_s,value\n0,\n", "line 2: column value is empty"),
        ("time_s,value\n", "no data rows"),
        ("", "file is empty"),
    ],
)
def test_errors_name_file_line_and_problem(tmp_path, text, msg):
    p = _write(tmp_path, text)
    with pytest.raises(InputError, match=msg) as ei:
        read_csv_table(p, ["time_s", "value"])
    assert str(p) in str(ei.value)


def test_collect_mode_counts_rejected_rows(tmp_path):
    p = _write(tmp_path, "time_s,value\n0,1\n1,nan\n2,3\n3,\n")
    t = read_csv_table(p, ["time_s", "value"], on_error="collect")
    assert len(t) == 2 and t.n_read == 4
    assert [r.line for r in t.rejected] == [3, 5]
    assert "not a finite" in t.rejected[0].reason


def test_check_times_unsorted_and_duplicate(tmp_path):
    t = read_csv_table(
        _write(tmp_path, "id,time_s\na,0\nb,5\na,1\nb,4\n"), ["time_s"], ["id"], text=["id"]
    )
    with pytest.raises(
        InputError, match="line 5: time_s = 4 is earlier than 5 on line 3 for id 'b'"
    ):
        check_times(t, group="id")
    t2 = read_csv_table(_write(tmp_path, "time_s\n0\n1\n1\n", "d.csv"), ["time_s"])
    with pytest.raises(InputError, match="line 4: duplicate time_s = 1"):
        check_times(t2)
    check_times(t2, strict=False)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        read_csv_table(tmp_path / "nope.csv", ["a"])
