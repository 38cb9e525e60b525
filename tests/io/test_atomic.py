"""Atomic outputs: a failed write keeps the previous file and leaves no temporary."""

import errno
import os
import subprocess
import sys

import pytest

from seatrack.io import atomic
from seatrack.io.atomic import OutputError
from seatrack.io.atomic import atomic_path
from seatrack.io.atomic import atomic_write
from seatrack.io.atomic import check_output_path


def test_success_replaces_and_leaves_no_temporary(tmp_path):
    out = tmp_path / "a.csv"
    out.write_text("old\n")
    with atomic_write(out, newline="") as fh:
        fh.write("new\n")
    assert out.read_text() == "new\n"
    assert sorted(os.listdir(tmp_path)) == ["a.csv"]


def test_exception_keeps_old_file(tmp_path):
    out = tmp_path / "a.csv"
    out.write_text("old\n")
    with pytest.raises(RuntimeError):
        with atomic_write(out) as fh:
            fh.write("half")
            raise RuntimeError("boom")
    assert out.read_text() == "old\n"
    assert sorted(os.listdir(tmp_path)) == ["a.csv"]


def test_atomic_path_for_libraries(tmp_path):
    out = tmp_path / "sub" / "b.bin"
    with atomic_path(out) as tmp:
        assert tmp.parent == out.parent and tmp.suffix == ".bin"
        tmp.write_bytes(b"xyz")
    assert out.read_bytes() == b"xyz"
    assert sorted(os.listdir(out.parent)) == ["b.bin"]


def test_new_file_gets_umask_permissions(tmp_path):
    out = tmp_path / "p.txt"
    with atomic_write(out) as fh:
        fh.write("x")
    mask = os.umask(0)
    os.umask(mask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~mask


@pytest.mark.parametrize("case", ["directory", "parent_is_file", "empty"])
def test_bad_output_paths_are_refused(tmp_path, case):
    if case == "directory":
        path = tmp_path
    elif case == "parent_is_file":
        (tmp_path / "f").write_text("x")
        path = tmp_path / "f" / "out.csv"
    else:
        path = ""
    with pytest.raises(OutputError):
        check_output_path(path)


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write into read-only folders")
def test_unwritable_folder_is_refused(tmp_path):
    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(0o500)
    try:
        with pytest.raises(OutputError, match="not writable"):
            check_output_path(d / "x.csv")
    finally:
        d.chmod(0o700)


def test_write_cut_by_file_size_limit_keeps_old_file(tmp_path):
    """A write that fails part-way (RLIMIT_FSIZE in a child process) keeps the old file."""
    out = tmp_path / "big.csv"
    out.write_text("previous good output\n")
    code = f"""
import resource, signal
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
from seatrack.io.atomic import atomic_write
with atomic_write({str(out)!r}) as fh:
    for i in range(100000):
        fh.write("%d,%d,%d\\n" % (i, i, i))
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode != 0
    assert "OutputError" in r.stderr or "File too large" in r.stderr
    assert out.read_text() == "previous good output\n"
    assert sorted(os.listdir(tmp_path)) == ["big.csv"]


def test_check_output_dir(tmp_path):
    from seatrack.io.atomic import check_output_dir

    d = check_output_dir(tmp_path / "a" / "b")
    assert d.is_dir()
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(OutputError, match="is a file, expected a folder"):
        check_output_dir(f)
    with pytest.raises(OutputError, match=f"cannot create the folder {f / 'sub'}, {f} is a file"):
        check_output_dir(f / "sub")
    with pytest.raises(OutputError, match="not a folder name"):
        check_output_dir("")


def test_atomic_files_replace_all_or_none(tmp_path):
    from seatrack.io.atomic import atomic_files

    paths = [tmp_path / "a.csv", tmp_path / "b.csv"]
    for p in paths:
        p.write_text("old\n")
    with pytest.raises(RuntimeError):
        with atomic_files(paths) as tmp:
            tmp[0].write_text("new a\n")
            raise RuntimeError("the second file failed")
    assert [p.read_text() for p in paths] == ["old\n", "old\n"]
    assert sorted(os.listdir(tmp_path)) == ["a.csv", "b.csv"]
    with atomic_files(paths) as tmp:
        for t, text in zip(tmp, ("A\n", "B\n"), strict=True):
            t.write_text(text)
    assert [p.read_text() for p in paths] == ["A\n", "B\n"]


def test_errors_about_the_temporary_name_the_destination(tmp_path):
    out = tmp_path / "t.csv"
    with pytest.raises(OutputError) as ei:
        with atomic_path(out) as tmp:
            raise ValueError(f"{tmp}: cannot write (disk full)")
    assert str(ei.value) == f"{out}: cannot write (disk full)"


def test_folder_that_refuses_files_is_refused_before_any_work(tmp_path, monkeypatch):
    # os.access answers yes for root and knows nothing of read-only or special file systems
    # (/proc): the folder check creates (and removes) a probe file
    def refuse(*args, **kwargs):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))

    monkeypatch.setattr(atomic.tempfile, "mkstemp", refuse)
    out = tmp_path / "t.csv"
    msg = f"^{out}: folder {tmp_path} is not writable \\(Read-only"
    with pytest.raises(OutputError, match=msg):
        check_output_path(out)
    assert list(tmp_path.iterdir()) == []


def test_probe_leaves_nothing_and_temporary_failure_names_the_destination(tmp_path, monkeypatch):
    out = tmp_path / "t.csv"
    check_output_path(out)
    assert list(tmp_path.iterdir()) == []
    real = atomic.tempfile.mkstemp

    def refuse_outputs(*args, **kwargs):  # the probe passes, the output's temporary fails
        if kwargs.get("prefix", "").startswith(".seatrack-probe."):
            return real(*args, **kwargs)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(atomic.tempfile, "mkstemp", refuse_outputs)
    with pytest.raises(OutputError, match=f"^{out}: cannot create a file in {tmp_path}"):
        with atomic_write(out) as fh:
            fh.write("x")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fail_at", [1, 2])
def test_a_rename_failing_midway_puts_back_the_outputs_already_replaced(
    tmp_path, monkeypatch, fail_at
):
    paths = [tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "new.csv"]
    paths[0].write_text("old a\n")
    paths[1].write_text("old b\n")
    real_replace = os.replace
    calls = []

    def replace(src, dst):  # the commit's renames of temporaries: the n-th one fails
        if (
            str(src).endswith(".csv")
            and os.path.basename(str(src)).startswith(".")
            and (os.path.basename(str(dst)) in ("a.csv", "b.csv", "new.csv"))
        ):
            calls.append(dst)
            if len(calls) == fail_at + 1:
                raise OSError(errno.EXDEV, "Invalid cross-device link")
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(OutputError, match="cannot replace"):
        with atomic.output_transaction():
            for p, text in zip(paths, ("A\n", "B\n", "N\n"), strict=True):
                with atomic_write(p) as fh:
                    fh.write(text)
    assert [p.read_text() for p in paths[:2]] == ["old a\n", "old b\n"]
    assert not paths[2].exists()
    assert sorted(os.listdir(tmp_path)) == ["a.csv", "b.csv"]  # no temporary, no backup


def test_a_transaction_keeps_no_backup_after_success_or_interrupt(tmp_path, monkeypatch):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("old a\n")
    with atomic.output_transaction():
        for p in (a, b):
            with atomic_write(p) as fh:
                fh.write(f"new {p.name}\n")
    assert a.read_text() == "new a.csv\n" and b.read_text() == "new b.csv\n"
    assert sorted(os.listdir(tmp_path)) == ["a.csv", "b.csv"]
    real_replace = os.replace

    fired = []

    def interrupted(src, dst):  # one interrupt, while the second output is renamed
        if os.path.basename(str(dst)) == "b.csv" and not fired:
            fired.append(src)
            raise KeyboardInterrupt
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        with atomic.output_transaction():
            for p in (a, b):
                with atomic_write(p) as fh:
                    fh.write("newer\n")
    assert a.read_text() == "new a.csv\n" and b.read_text() == "new b.csv\n"
    assert sorted(os.listdir(tmp_path)) == ["a.csv", "b.csv"]


def test_without_hard_links_the_previous_file_is_renamed_away_and_back(tmp_path, monkeypatch):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("old a\n")
    b.mkdir()  # the second output became a folder after the checks

    def no_links(src, dst):
        raise OSError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(os, "link", no_links)
    with pytest.raises(OutputError, match="b.csv: cannot replace"):
        with atomic.output_transaction():
            with atomic_write(a) as fh:
                fh.write("new\n")
            tmp = tmp_path / ".b.csv.12345678.csv"
            tmp.write_text("new b\n")
            atomic._active().add(tmp, b)  # as atomic_path does after its checks
    assert a.read_text() == "old a\n" and b.is_dir()
    assert sorted(os.listdir(tmp_path)) == ["a.csv", "b.csv"]
