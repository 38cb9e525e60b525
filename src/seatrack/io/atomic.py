"""Atomic output files: every file seatrack writes goes through this module.

A file is written to a temporary file in the destination folder, flushed and fsynced, then
moved over the destination with :func:`os.replace` (atomic on POSIX and Windows). On any
failure -- an exception, a full disk, a size limit, an interrupt -- the temporary file is
removed and the previous content of the destination, if any, is intact. A reader never sees
a half-written file.

* :func:`atomic_write` -- a context manager yielding an open file object (text or binary);
* :func:`atomic_path` -- a context manager yielding a temporary *path*, for libraries that
  write to a file name themselves (matplotlib, pyarrow);
* :func:`atomic_files` -- several files that are replaced together at the end (a failure
  while writing any of them keeps all the previous files);
* :func:`check_output_path` / :func:`check_output_dir` -- the one check every command runs
  on an output file / folder before doing any work, so a bad path fails fast with
  :class:`OutputError` and nothing is computed in vain;
* :func:`output_transaction` -- every output of one command replaced together: while it is
  open, :func:`atomic_path` keeps each finished temporary instead of moving it; they all
  replace their destinations when the block ends without an error, and are all removed
  when it ends with one (a full disk on the last output, an interrupt). The ``seatrack``
  command line runs every command inside one; a file read back before the end is found
  with :func:`pending_output`, and worker processes hand their outputs to the parent's
  transaction with :func:`held_outputs` / :func:`adopt_outputs`.

Output paths: an existing output must be a regular file (a device node, a pipe or a socket
is refused: replacing ``/dev/null`` with a regular file is never what was meant). An output
that is a symbolic link is resolved: the file it points to is replaced and the link is
kept. The file name must leave room for the temporary's name (``.NAME.XXXXXXXX.SUFFIX``)
within the file system's limit.

Output folders are created when missing (like ``mkdir -p``); a path that is a directory,
or whose parent is a file, or a folder that is not writable is refused with a clear message.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import tempfile
from collections.abc import Iterator
from collections.abc import Mapping
from pathlib import Path
from typing import IO
from typing import Any

from seatrack.errors import UserError

__all__ = [
    "OutputError",
    "atomic_path",
    "atomic_write",
    "check_output_dir",
    "check_output_path",
    "atomic_files",
    "output_transaction",
    "pending_output",
    "immediate_outputs",
    "held_outputs",
    "adopt_outputs",
    "discard_outputs",
    "TEMP_NAME_EXTRA",
]

#: characters the temporary's name adds to the output's name (``.`` + ``.XXXXXXXX``)
TEMP_NAME_EXTRA = 10


class OutputError(UserError, OSError):
    """An output file cannot be written; the message names the file and the reason."""


def _folder_problem(p: Path, create: bool) -> str | None:
    """Why folder ``p`` cannot hold outputs (creating it when ``create``), or None."""
    if p.exists() and not p.is_dir():
        return f"{p} is a file, expected a folder"
    for anc in p.parents:
        if anc.exists():
            if not anc.is_dir():
                return f"cannot create the folder {p}, {anc} is a file"
            break
    if create:
        try:
            p.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            return f"cannot create the folder {p} ({exc.strerror})"
    if p.exists() and not os.access(p, os.W_OK | os.X_OK):
        return f"folder {p} is not writable"
    if p.is_dir():  # os.access says yes to root and knows no read-only or special file system
        try:
            fd, probe = tempfile.mkstemp(dir=p, prefix=".seatrack-probe.")
        except OSError as exc:
            return f"folder {p} is not writable ({exc.strerror or exc})"
        os.close(fd)
        with contextlib.suppress(OSError):
            os.unlink(probe)
    return None


def check_output_dir(path: str | os.PathLike[str], *, create: bool = True) -> Path:
    """Validate an output folder (create it, like ``mkdir -p``); return it as a :class:`Path`.

    Raises
    ------
    OutputError
        When the path is a file, a parent is a file, the folder cannot be created, or it
        is not writable.
    """
    if str(path) == "":
        raise OutputError("an empty string is not a folder name")
    p = Path(path)
    problem = _folder_problem(p, create)
    if problem is not None:
        raise OutputError(f"{p}: {problem}")
    return p


def check_output_path(path: str | os.PathLike[str], *, create_parent: bool = True) -> Path:
    """Validate an output file path (and create its folder); return it as a :class:`Path`.

    Raises
    ------
    OutputError
        When the path is a directory, a parent is not a directory, or the folder is not
        writable.
    """
    p = Path(path)
    if str(path) == "" or p.name in ("", ".", ".."):
        raise OutputError(f"{path!s}: not a file name")
    if p.is_dir():
        raise OutputError(f"{p}: is a directory, expected a file name")
    if p.is_symlink():
        p = Path(os.path.realpath(p))  # the link is kept, its target replaced
    if p.exists() and not p.is_file():
        raise OutputError(f"{path}: not a regular file (a device, pipe or socket), not replaced")
    problem = _folder_problem(p.parent, create_parent)
    if problem is not None:
        raise OutputError(f"{p}: {problem}")
    if p.exists() and not os.access(p, os.W_OK):
        raise OutputError(f"{p}: file is not writable")
    most = _name_max(p.parent) - TEMP_NAME_EXTRA - len(p.suffix)
    if len(os.fsencode(p.name)) > most:
        raise OutputError(
            f"{path}: file name too long (at most {most} bytes, to leave room for the "
            "temporary file's name)"
        )
    return p


def _name_max(folder: Path) -> int:
    try:
        return int(os.pathconf(folder if folder.is_dir() else ".", "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return 255


def _umask_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path`` atomically.

    ``suffix`` (default: the suffix of ``path``) lets libraries that infer the format from
    the file name (``savefig``) see the right one.
    """
    dest = check_output_path(path)
    tx = _active()
    try:
        fd, tmp = tempfile.mkstemp(
            dir=dest.parent,
            prefix=f".{dest.name}.",
            suffix=(dest.suffix if suffix is None else suffix),
        )
    except OSError as exc:
        raise OutputError(
            f"{dest}: cannot create a file in {dest.parent} ({exc.strerror or exc})"
        ) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        with open(tmp_path, "rb+") as fh:  # data of the library's writer reach the disk
            os.fsync(fh.fileno())
        os.chmod(tmp_path, _umask_mode())
        if tx is None or tx.direct:
            os.replace(tmp_path, dest)
        else:
            tx.add(tmp_path, dest)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        if isinstance(exc, Exception) and str(tmp_path) in str(exc):  # name the destination
            raise OutputError(str(exc).replace(str(tmp_path), str(dest))) from None
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            raise OutputError(f"{dest}: write failed ({exc.strerror or exc})") from None
        raise


@contextlib.contextmanager
def atomic_write(
    path: str | os.PathLike[str],
    mode: str = "w",
    *,
    encoding: str | None = "utf-8",
    newline: str | None = None,
) -> Iterator[IO[Any]]:
    """Open a temporary file for writing; on success it replaces ``path`` atomically.

    Parameters
    ----------
    path : output file.
    mode : ``"w"`` (text) or ``"wb"`` (binary).
    encoding, newline : as for :func:`open` (text mode only; CSV writers want ``newline=""``).

    Examples
    --------
    >>> with atomic_write(out, newline="") as fh:   # doctest: +SKIP
    ...     csv.writer(fh).writerows(rows)
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write mode must be 'w' or 'wb', got {mode!r}")
    with atomic_path(path) as tmp:
        if mode == "wb":
            with open(tmp, "wb") as fh:
                yield fh
        else:
            with open(tmp, "w", encoding=encoding, newline=newline) as fh:
                yield fh


@contextlib.contextmanager
def atomic_files(paths: list[Path]) -> Iterator[list[Path]]:
    """Temporary paths for several output files, replacing all of them on success.

    A failure while the files are written (inside the ``with`` block) removes every
    temporary and keeps every previous file; the replacements themselves run one after
    the other at the end.
    """
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(atomic_path(p)) for p in paths]


class _Transaction:
    """Finished temporaries of one command and the files they replace, in write order."""

    def __init__(self, direct: bool = False) -> None:
        self.direct = direct  # replace each output at once (immediate_outputs)
        self.pid = os.getpid()
        self.pending: dict[Path, Path] = {}  # destination -> temporary

    def add(self, tmp: Path, dest: Path) -> None:
        dest = _key(dest)
        old = self.pending.pop(dest, None)
        if old is not None:  # written twice: the last version wins
            with contextlib.suppress(OSError):
                old.unlink()
        self.pending[dest] = tmp

    def discard(self) -> None:
        for tmp in self.pending.values():
            with contextlib.suppress(OSError):
                tmp.unlink()
        self.pending.clear()

    def commit(self) -> None:
        """Replace every destination; on any failure put back those already replaced.

        Before a destination is replaced, its previous file is kept as a hard link beside
        it (or, where the file system has no hard links, renamed there); the backups are
        removed once every temporary is in place. A failure (a rename refused, an
        interrupt) puts each backup back over its destination, removes the outputs that
        had no previous file and every temporary left, and re-raises.
        """
        items = list(self.pending.items())
        self.pending.clear()
        done: list[tuple[Path, Path | None]] = []  # replaced destinations, their backups
        try:
            for dest, tmp in items:
                backup = _backup(dest)
                done.append((dest, backup))  # before the rename: rolled back if it fails
                try:
                    os.replace(tmp, dest)
                except OSError as exc:
                    done.pop()
                    if backup is not None:  # renamed away: put it back
                        _restore(backup, dest)
                    raise OutputError(f"{dest}: cannot replace ({exc.strerror or exc})") from None
        except BaseException:
            for dest, backup in reversed(done):
                _restore(backup, dest)
            for _, tmp in items:
                with contextlib.suppress(OSError):
                    tmp.unlink()
            raise
        for _, backup in done:
            if backup is not None:
                with contextlib.suppress(OSError):
                    backup.unlink()


def _backup(dest: Path) -> Path | None:
    """Keep the previous file of ``dest`` beside it as a hard link (or, if the file system
    refuses hard links, by renaming it); None when there is no previous file (or a folder
    is in the way: the rename fails and nothing is moved)."""
    if not os.path.lexists(dest) or (dest.is_dir() and not dest.is_symlink()):
        return None
    for _ in range(100):
        backup = dest.with_name(f".{dest.name}.{secrets.token_hex(4)}{dest.suffix}")
        try:
            os.link(dest, backup)
            return backup
        except FileExistsError:
            continue
        except OSError:  # no hard links here: the previous file is renamed away
            os.replace(dest, backup)
            return backup
    raise OutputError(f"{dest}: cannot keep a backup of the previous file")


def _restore(backup: Path | None, dest: Path) -> None:
    """Put ``backup`` back over ``dest`` (None: ``dest`` had no previous file, remove it).

    A backup that is still a link of ``dest`` (the rename did not happen) is removed."""
    try:
        if backup is None:
            os.unlink(dest)
            return
        os.replace(backup, dest)  # the same file twice: a no-op that leaves the link
    except OSError:
        return  # the backup is kept: the previous content is not lost
    with contextlib.suppress(OSError):
        os.unlink(backup)


_TRANSACTIONS: list[_Transaction] = []


def _active() -> _Transaction | None:
    """The open transaction of this process (a forked worker writes directly)."""
    if _TRANSACTIONS and _TRANSACTIONS[-1].pid == os.getpid():
        return _TRANSACTIONS[-1]
    return None


@contextlib.contextmanager
def output_transaction() -> Iterator[None]:
    """Replace every output written inside the block together, at its end.

    Each :func:`atomic_path` / :func:`atomic_write` / :func:`atomic_files` inside the block
    writes and fsyncs its temporary as usual but leaves it beside its destination; when
    the block ends without an error the temporaries replace their destinations, in the
    order they were written (renames in the same folder: no data is written then, so a
    full disk cannot stop them). Each previous output is kept as a hard link beside it
    until every rename has succeeded: a rename that fails all the same (a destination
    turned into a folder, a permission taken away, an interrupt) puts back the outputs
    already replaced. When the block ends with an error or an interrupt, every
    temporary is removed and every previous output is intact. A file the command reads
    back before the end (a picture embedded in a report) is found with
    :func:`pending_output`. Transactions nest: an inner one commits into the outer.
    """
    tx = _Transaction()
    outer = _active()
    _TRANSACTIONS.append(tx)
    try:
        yield
    except BaseException:
        _TRANSACTIONS.remove(tx)
        tx.discard()
        raise
    _TRANSACTIONS.remove(tx)
    if outer is not None:
        for dest, tmp in tx.pending.items():
            outer.add(tmp, dest)
        return
    tx.commit()


@contextlib.contextmanager
def held_outputs() -> Iterator[dict[Path, Path]]:
    """Outputs written inside the block kept as finished temporaries and handed over
    (destination -> temporary) instead of replacing their files: a worker process writes
    its part of a command's outputs this way and its parent adds them to its transaction
    with :func:`adopt_outputs` (or removes them with :func:`discard_outputs`). An error
    inside the block removes the temporaries, as :func:`output_transaction` does."""
    tx = _Transaction()
    _TRANSACTIONS.append(tx)
    held: dict[Path, Path] = {}
    try:
        yield held
    except BaseException:
        _TRANSACTIONS.remove(tx)
        tx.discard()
        raise
    _TRANSACTIONS.remove(tx)
    held.update(tx.pending)
    tx.pending.clear()


def adopt_outputs(held: Mapping[Path, Path]) -> None:
    """Outputs held by :func:`held_outputs` (in this or a worker process) added to the open
    :func:`output_transaction`; without one they replace their files at once."""
    tx = _active()
    for dest, tmp in held.items():
        if tx is None or tx.direct:
            os.replace(tmp, dest)
        else:
            tx.add(Path(tmp), Path(dest))


def discard_outputs(held: Mapping[Path, Path]) -> None:
    """Remove the temporaries of outputs held by :func:`held_outputs`."""
    for tmp in held.values():
        with contextlib.suppress(OSError):
            os.unlink(tmp)


@contextlib.contextmanager
def immediate_outputs() -> Iterator[None]:
    """Inside an :func:`output_transaction`, a block whose outputs replace their files at
    once, as without a transaction (a library caller that must see a file in place
    before the end; commands read back what they wrote with :func:`pending_output`)."""
    tx = _Transaction(direct=True)
    _TRANSACTIONS.append(tx)
    try:
        yield
    finally:
        _TRANSACTIONS.remove(tx)


def pending_output(path: str | os.PathLike[str]) -> Path:
    """Where the content of output ``path`` is now: its finished temporary while an
    :func:`output_transaction` holds it, else ``path`` itself."""
    tx = _active()
    if tx is not None:
        tmp = tx.pending.get(_key(Path(path)))
        if tmp is not None:
            return tmp
    return Path(path)


def _key(p: Path) -> Path:
    """The destination as the transaction knows it: absolute, a symbolic link resolved."""
    return Path(os.path.realpath(p)) if p.is_symlink() else Path(os.path.abspath(p))
