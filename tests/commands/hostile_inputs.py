"""Hostile inputs for every command: mutations of valid files, and the contract they must meet.

Used by ``tests/commands/test_hostile_*.py`` (one module per command). A test builds a small
valid input, lets hypothesis mutate it (:func:`mutated_csv`, :func:`mutated_text`), runs the
command in-process through :func:`seatrack.cli.main` (:func:`run_cli`) and checks
:func:`assert_clean`: exit status 0 or 2, no traceback or internal error, a failure is one
``error: ...`` line, and every output that existed before a failed run is intact, with no
temporary file left beside it.

The mutations: cells replaced by NaN, inf, 1e308, -0, empty, garbage, Latin-1 text, huge
integers; rows and columns deleted, duplicated and swapped; extra or missing cells; blank
lines; header-only and empty files; then, on the bytes, a BOM, CRLF or CR line ends,
semicolons or tabs for commas, a cut at any byte, a Latin-1 byte, a NUL or random binary
bytes inserted, or the whole file replaced by binary data; or the file compressed (gzip,
zstd), cut inside its compressed data, or made a compression bomb. :func:`hostile_output`
draws an output path that must be refused or handled (an input, a folder, a pipe, a device,
a symbolic link, a name with no room for its temporary, another output of the run).
"""

from __future__ import annotations

import gzip
import os
import re
from dataclasses import dataclass
from pathlib import Path

import pyarrow as pa
from hypothesis import strategies as st

from cli_inprocess import seatrack

#: values a cell is replaced with
CELL_VALUES = (
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e309",
    "-0",
    "-0.0",
    "0",
    "-1",
    "",
    " ",
    "abc",
    "1e-320",
    "99999999999999999999",
    "1e30",
    "4e9",
    "1,5",
    '"',
    "\x00",
    "ø",
    "Jürgen",
    "0x10",
    "+5",
    "1_000",
    "  7  ",
    "360",
    "-90.5",
)

#: values a number in a TOML file is replaced with
TOML_VALUES = (
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "0",
    "-0.0",
    "-1",
    "1e-300",
    '"abc"',
    "1e30",
    "1e7",
    "1e-6",
    "true",
    "[]",
    "{}",
    "9223372036854775807",
    "0.5",
)


@dataclass(frozen=True)
class Result:
    """Exit status and captured output of one in-process CLI run."""

    code: int
    out: str
    err: str


def run_cli(*args: object) -> Result:
    """Run ``seatrack ARGS`` in this process; never raises (SystemExit is the status)."""
    r = seatrack(*args)
    return Result(r.returncode, r.stdout, r.stderr)


def snapshot(paths: list[Path]) -> dict[Path, bytes | None]:
    """Content of each output path before a run (None when it does not exist)."""
    return {p: (p.read_bytes() if p.is_file() else None) for p in paths}


def assert_clean(res: Result, before: dict[Path, bytes | None], args: list[object]) -> None:
    """The contract of every command on any input (see the module docstring).

    An error line names what is wrong: one of the files or options on the command line.
    """
    where = f"args={args!r}\nstdout={res.out[-2000:]!r}\nstderr={res.err[-2000:]!r}"
    assert res.code in (0, 2), f"exit status {res.code}\n{where}"
    assert "Traceback" not in res.err and "internal error" not in res.err, where
    if res.code == 2:
        lines = [ln for ln in res.err.splitlines() if ln.strip()]
        assert len(lines) == 1 and lines[0].startswith("error: "), where
        named = [str(a) for a in args if isinstance(a, Path) or str(a).startswith("-")]
        assert any(n in lines[0] for n in named), f"the error names no file or option\n{where}"
        for p, old in before.items():
            now = p.read_bytes() if p.is_file() else None
            assert now == old, f"{p} changed by a failed run\n{where}"
    folders = {p.parent for p in before}
    for d in folders:
        if d.is_dir():
            tmp = [f for f in os.listdir(d) if f.startswith(".") and not f.startswith("..")]
            assert not tmp, f"temporary files left in {d}: {tmp}\n{where}"


# ---------------------------------------------------------------------------
# mutations
# ---------------------------------------------------------------------------
def _pick(draw: st.DrawFn, n: int) -> int:
    return draw(st.integers(0, max(n - 1, 0)))


def _row_op(draw: st.DrawFn, rows: list[list[str]]) -> list[list[str]]:
    """One structural or cell mutation of a table (header = rows[0])."""
    if not rows:
        return rows
    op = draw(
        st.sampled_from(
            (
                "cell",
                "cell",
                "cell",
                "text",
                "del_row",
                "dup_row",
                "swap_rows",
                "del_col",
                "dup_col",
                "swap_cols",
                "swap_header",
                "rename",
                "extra_cell",
                "short_row",
                "blank",
                "head_only",
                "keep_some",
            )
        )
    )
    rows = [list(r) for r in rows]
    n = len(rows)
    width = max(len(r) for r in rows)
    i = 1 + _pick(draw, n - 1) if n > 1 else 0
    j = _pick(draw, width)
    if op in ("cell", "text") and j < len(rows[i]):
        if op == "cell":
            rows[i][j] = draw(st.sampled_from(CELL_VALUES))
        else:
            rows[i][j] = draw(st.text(max_size=6))
    elif op == "del_row" and n > 1:
        del rows[i]
    elif op == "dup_row":
        rows.insert(i, list(rows[i]))
    elif op == "swap_rows" and n > 2:
        k = 1 + _pick(draw, n - 1)
        rows[i], rows[k] = rows[k], rows[i]
    elif op == "del_col":
        rows = [r[:j] + r[j + 1 :] for r in rows]
    elif op == "dup_col":
        rows = [r[: j + 1] + r[j : j + 1] + r[j + 1 :] for r in rows]
    elif op in ("swap_cols", "swap_header"):
        k = _pick(draw, width)
        lo = 0 if op == "swap_header" else 1
        hi = 1 if op == "swap_header" else n
        for r in rows[lo:hi]:
            if j < len(r) and k < len(r):
                r[j], r[k] = r[k], r[j]
    elif op == "rename" and j < len(rows[0]):
        rows[0][j] = rows[0][j] + draw(st.sampled_from(("x", " ", "_", "É")))
    elif op == "extra_cell":
        rows[i].append(draw(st.sampled_from(CELL_VALUES)))
    elif op == "short_row" and rows[i]:
        rows[i] = rows[i][: _pick(draw, len(rows[i]))]
    elif op == "blank":
        rows.insert(i, [])
    elif op == "head_only":
        rows = rows[:1]
    elif op == "keep_some":
        rows = rows[: 1 + _pick(draw, n)]
    return rows


def _byte_op(draw: st.DrawFn, data: bytes) -> bytes:
    """One encoding-level mutation (or none)."""
    op = draw(
        st.sampled_from(
            (
                "none",
                "none",
                "none",
                "bom",
                "crlf",
                "cr",
                "semicolon",
                "tab",
                "cut",
                "latin1",
                "nul",
                "binary",
                "all_binary",
                "empty",
                "gzip",
                "zstd",
                "gzip_cut",
                "gzip_bomb",
            )
        )
    )
    pos = draw(st.integers(0, len(data)))
    if op == "bom":
        return b"\xef\xbb\xbf" + data
    if op == "crlf":
        return data.replace(b"\n", b"\r\n")
    if op == "cr":
        return data.replace(b"\n", b"\r")
    if op == "semicolon":
        return data.replace(b",", b";")
    if op == "tab":
        return data.replace(b",", b"\t")
    if op == "cut":
        return data[:pos]
    if op == "latin1":
        return data[:pos] + draw(st.sampled_from((b"\xf8", b"\xe9", b"\xff\xfe"))) + data[pos:]
    if op == "nul":
        return data[:pos] + b"\x00" + data[pos:]
    if op == "binary":
        return data[:pos] + draw(st.binary(min_size=1, max_size=24)) + data[pos:]
    if op == "all_binary":
        return draw(st.binary(max_size=300))
    if op == "empty":
        return b""
    if op == "gzip":
        return gzip.compress(data)
    if op == "zstd":
        sink = pa.BufferOutputStream()
        with pa.CompressedOutputStream(sink, "zstd") as fh:
            fh.write(data)
        return bytes(sink.getvalue().to_pybytes())
    if op == "gzip_cut":
        packed = gzip.compress(data)
        return packed[: draw(st.integers(0, len(packed)))]
    if op == "gzip_bomb":  # the data, then 40 MB of NUL bytes: refused as a bomb, quickly
        return gzip.compress(data + bytes(40 << 20), compresslevel=9)
    return data


@st.composite
def mutated_csv(draw: st.DrawFn, text: str, max_ops: int = 3) -> bytes:
    """A valid CSV text (no quoting) with 1..max_ops table mutations and a byte mutation."""
    rows = [ln.split(",") for ln in text.splitlines()]
    for _ in range(draw(st.integers(1, max_ops))):
        rows = _row_op(draw, rows)
    data = "".join(",".join(r) + "\n" for r in rows).encode("utf-8")
    return _byte_op(draw, data)


_NUMBER = re.compile(r"(?<![\w.\"])-?\d+(?:\.\d+)?(?:e-?\d+)?(?![\w.\"])")


@st.composite
def mutated_text(draw: st.DrawFn, text: str, max_ops: int = 3) -> bytes:
    """A valid line-based text (TOML, NMEA) with 1..max_ops line/number mutations and a
    byte mutation."""
    lines = text.splitlines()
    for _ in range(draw(st.integers(1, max_ops))):
        if not lines:
            break
        i = _pick(draw, len(lines))
        op = draw(st.sampled_from(("number", "number", "number", "del", "dup", "swap", "cut")))
        if op == "number":
            spans = list(_NUMBER.finditer(lines[i]))
            if spans:
                m = spans[_pick(draw, len(spans))]
                new = draw(st.sampled_from(TOML_VALUES))
                lines[i] = lines[i][: m.start()] + new + lines[i][m.end() :]
        elif op == "del":
            del lines[i]
        elif op == "dup":
            lines.insert(i, lines[i])
        elif op == "swap":
            k = _pick(draw, len(lines))
            lines[i], lines[k] = lines[k], lines[i]
        else:
            lines[i] = lines[i][: _pick(draw, len(lines[i]) + 1)]
    return _byte_op(draw, "".join(ln + "\n" for ln in lines).encode("utf-8"))


#: kinds of hostile output paths :func:`hostile_output` draws
OUTPUT_KINDS = (
    "fresh", "existing", "input", "hard_link", "folder", "under_file", "fifo", "device",
    "symlink", "dangling_symlink", "long_name", "other_output", "no_suffix",
)  # fmt: skip


@st.composite
def hostile_output(
    draw: st.DrawFn, d: Path, inputs: list[Path], other: Path | None = None
) -> tuple[str, Path]:
    """A kind from :data:`OUTPUT_KINDS` and an output path of that kind, made in ``d``."""
    kind = draw(st.sampled_from(OUTPUT_KINDS))
    p = d / f"out-{kind}.csv"
    if kind == "existing":
        p.write_bytes(b"previous\n")
    elif kind == "input":
        p = draw(st.sampled_from(inputs))
    elif kind == "hard_link":
        if not p.exists():
            os.link(draw(st.sampled_from(inputs)), p)
    elif kind == "folder":
        p.mkdir(exist_ok=True)
    elif kind == "under_file":
        (d / "a-file").write_bytes(b"x")
        p = d / "a-file" / "out.csv"
    elif kind == "fifo":
        if not p.exists():
            os.mkfifo(p)
    elif kind == "device":
        p = Path("/dev/null")
    elif kind == "symlink":
        target = d / "link-target.csv"
        target.write_bytes(b"previous\n")
        if not p.is_symlink():
            p.symlink_to(target)
    elif kind == "dangling_symlink":
        if not p.is_symlink():
            p.symlink_to(d / "nowhere" / "x.csv")
    elif kind == "long_name":
        p = d / ("x" * 250 + ".csv")
    elif kind == "other_output" and other is not None:
        p = other
    elif kind == "no_suffix":
        p = d / "out"
    return kind, p


def plain(data: bytes) -> bytes:
    """``data`` as a reader sees it: decompressed when it is whole gzip or zstd data (a
    reader recognises them by their first bytes), else unchanged."""
    for magic, codec in ((b"\x1f\x8b", "gzip"), (b"\x28\xb5\x2f\xfd", "zstd")):
        if data.startswith(magic):
            try:
                with pa.input_stream(pa.BufferReader(data), compression=codec) as fh:
                    return bytes(fh.read())
            except (OSError, ValueError):
                return data
    return data
