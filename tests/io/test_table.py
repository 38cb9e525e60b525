import os

import numpy as np
import pytest

from seatrack.io.table import Check
from seatrack.io.table import InputError
from seatrack.io.table import angle_deg
from seatrack.io.table import between
from seatrack.io.table import check_input_file
from seatrack.io.table import check_times
from seatrack.io.table import decode_text
from seatrack.io.table import latitude
from seatrack.io.table import longitude
from seatrack.io.table import positive
from seatrack.io.table import read_csv_table
from seatrack.io.table import seconds
from seatrack.io.table import sigma
from seatrack.io.table import unix_seconds


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


def test_input_file_check_names_what_is_wrong(tmp_path):
    f = tmp_path / "f.csv"
    f.write_text("a\n1\n")
    assert check_input_file(str(f)) == f
    with pytest.raises(InputError, match=f"^{tmp_path}: is a directory, expected a CSV file$"):
        read_csv_table(tmp_path, ["a"])
    loop = tmp_path / "loop"
    loop.symlink_to(tmp_path / "loop")
    with pytest.raises(InputError, match="loop: file not found \\(a broken or looping symbolic"):
        read_csv_table(loop, ["a"])
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)  # never opened: the check refuses it before any read (no hang)
    with pytest.raises(InputError, match="pipe: not a regular file .*expected an AIS file"):
        check_input_file(fifo, "an AIS file")


# --- encodings, separators, declared checks (issue 13) ---------------------------------


def test_latin1_lines_fall_back_per_line_and_text_columns_keep_them(tmp_path):
    p = tmp_path / "m.csv"
    p.write_bytes("name,value\nJürgen,1\n".encode() + b"S\xf8ren,2\n" + "Åsa,3\n".encode())
    t = read_csv_table(p, ["value"], ["name"], text=["name"])
    assert t["name"].tolist() == ["Jürgen", "Søren", "Åsa"]
    assert t.latin1_lines == (3,)
    np.testing.assert_allclose(t["value"], [1, 2, 3])


def test_a_latin1_byte_in_a_number_names_file_and_line(tmp_path):
    p = tmp_path / "m.csv"
    p.write_bytes(b"time_s,value\n0,1\n1,2\xf8\n")
    with pytest.raises(InputError, match=r"m.csv, line 3: column value = '2\xf8' is not a number"):
        read_csv_table(p, ["time_s", "value"])


@pytest.mark.parametrize(
    "raw",
    [
        b"\xef\xbb\xbftime_s,value\n0,1\n1,2\n",
        b"time_s,value\r\n0,1\r\n1,2\r\n",
        b"time_s,value\r0,1\r1,2\r",
        b"\xef\xbb\xbftime_s,value\r\n0,1\r\n1,2\xf8x\r\n",
    ],
)
def test_bom_and_line_ends(tmp_path, raw):
    p = tmp_path / "m.csv"
    p.write_bytes(raw)
    if b"\xf8" in raw:
        with pytest.raises(InputError, match="line 3: column value"):
            read_csv_table(p, ["time_s", "value"])
    else:
        assert read_csv_table(p, ["time_s", "value"]).lines.tolist() == [2, 3]


def test_decode_text_counts_lines_like_the_csv_reader():
    text, latin1 = decode_text(b"a\r\nb\xe9\rc\n\xff\n")
    assert text == "a\r\nbé\rc\nÿ\n" and latin1 == (2, 4)


@pytest.mark.parametrize(("sep", "hint"), [(";", "';' as separator"), ("\t", "a tab")])
def test_other_separators_get_a_hint(tmp_path, sep, hint):
    p = tmp_path / "m.csv"
    p.write_text(f"time_s{sep}value\n0{sep}1\n")
    with pytest.raises(InputError, match=hint):
        read_csv_table(p, ["time_s", "value"])


def test_binary_header_is_shown_readably_and_short(tmp_path):
    p = tmp_path / "m.csv"
    p.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(InputError) as ei:
        read_csv_table(p, ["time_s"])
    msg = str(ei.value)
    assert "missing required column(s) time_s" in msg and len(msg) < 1200 and "\n" not in msg


def test_duplicated_column_and_directory(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("time_s,value,value\n0,1,2\n")
    with pytest.raises(InputError, match="line 1: column value appears more than once"):
        read_csv_table(p, ["time_s", "value"])
    with pytest.raises(InputError, match="is a directory"):
        read_csv_table(tmp_path, ["time_s"])


def test_blank_lines_are_listed(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("time_s,value\n0,1\n\n , \n1,2\n")
    t = read_csv_table(p, ["time_s", "value"])
    assert t.blank_lines == (3, 4) and t.lines.tolist() == [2, 5] and t.n_read == 2


@pytest.mark.parametrize(
    ("check", "good", "bad", "message"),
    [
        (positive("r"), [1e-9, 1e8], [0.0, -1.0, 1.1e8], "r = {} must be in (0, 1e+08]"),
        (angle_deg("a"), [0.0, 359.9], [360.0, -0.1], "a = {} must be in [0, 360)"),
        (latitude("lat"), [-90.0, 90.0], [90.1], "lat = {} must be in [-90, 90]"),
        (longitude("lon"), [-180.0, 180.0], [180.5], "lon = {} must be in [-180, 180]"),
        (seconds("t"), [-4.1e9, 0.0, 4.1e9], [1e10, 1e308], "t = {} must be in [-4.10244e+09"),
        (unix_seconds("t"), [0.0, 4.1e9], [-1.0, 4102444800.0], "(Unix time, 1970 to 2100)"),
        (sigma("s"), [1e-12, 5.0], [0.0, -2.0], "s = {} must be > 0"),
        (between("x", -1, 1, hi_open=True), [-1.0, 0.999], [1.0], "x = {} must be in [-1, 1)"),
    ],
)
def test_checks_accept_and_refuse(check, good, bad, message):
    assert all(check.problem(v) is None for v in good)
    for v in bad:
        assert message.format(f"{v:g}") in check.problem(v)
    assert check.problem(float("nan")) == f"{check.column} = nan is not a finite number"


def test_checks_in_read_raise_or_collect(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("time_s,range_m\n0,100\n1,-5\n2,1e308\n3,200\n")
    checks = (seconds("time_s"), positive("range_m"))
    with pytest.raises(InputError, match=r"m.csv, line 3: range_m = -5 must be in \(0, 1e\+08\]"):
        read_csv_table(p, ["time_s", "range_m"], checks=checks)
    t = read_csv_table(p, ["time_s", "range_m"], checks=checks, on_error="collect")
    assert t.lines.tolist() == [2, 5] and [r.line for r in t.rejected] == [3, 4]
    assert "range_m = 1e308" in t.rejected[1].reason
    assert isinstance(checks[0], Check)
