"""Result files written complete or not at all.

Every result file of attitude_c (``attitude simulate``'s CSV, JSON, PNG and
Markdown files; the budget's) goes through this module:

* :func:`atomic_path` / :func:`atomic_open` / :func:`write_text` /
  :func:`write_with`: the file
  is written under a temporary name in the same directory
  (``.NAME.tmp-XXXXXX.EXT``: same filesystem, same extension for writers
  that go by it), flushed to the disk (``fsync``) and renamed into place
  (``os.replace``, atomic on POSIX), then the directory is synced. On any
  failure (a full disk, an I/O error, an exception of the writer) the
  temporary file is removed and the destination is left as it was: absent,
  or the previous run's complete file.
* :func:`write_results`: a set of files one after the other; when one
  fails, :class:`ResultsIncomplete` (an ``OSError``) says which are
  complete and which are absent.
* :func:`check_output_dir`: before a long computation, make sure its
  results can be written (the directory exists or can be made, and a file
  can be created in it), so a run is never lost at its end to a mistyped
  ``--out``.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import IO, Any, Callable

__all__ = ["ResultsIncomplete", "atomic_open", "atomic_path", "check_output_dir", "write_results", "write_text",
           "write_with"]


def _fsync_dir(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:  # not supported (some filesystems): the rename is still atomic
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _new_temp(dest: Path) -> Path:
    """Create an empty ``.STEM.tmp-XXXXXXXX.SUFFIX`` next to ``dest`` with the
    permissions of an ordinary new file (0666 less the umask, unlike mkstemp's 0600)."""
    for _ in range(100):
        tmp = dest.with_name(f".{dest.stem}.tmp-{secrets.token_hex(4)}{dest.suffix}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(dest))  # pragma: no cover


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path next to ``path`` for a writer to fill; on a
    clean exit it is fsynced and renamed to ``path``; on any exception it
    is removed and the exception propagates (``path`` untouched)."""
    dest = Path(path)
    tmp = _new_temp(dest)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)  # data on the disk before the name: ENOSPC/EIO surface here at the latest
        finally:
            os.close(fd)
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    _fsync_dir(dest.parent)


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w", **kw: Any) -> Iterator[IO[Any]]:
    """``open(path, mode, **kw)`` written through :func:`atomic_path`
    (mode "w", "wb", "x" is not supported)."""
    if mode not in ("w", "wb", "wt"):
        raise ValueError(f"atomic_open: mode must be 'w' or 'wb', got {mode!r}")
    if "b" not in mode:
        kw.setdefault("encoding", "utf-8")
    with atomic_path(path) as tmp, open(tmp, mode, **kw) as fh:
        yield fh


def write_with(path: str | os.PathLike[str], writer: Callable[[Path], object]) -> None:
    """``writer(tmp)`` fills a temporary path, renamed to ``path`` once complete
    (:func:`atomic_path`): for writers that take a file name (savefig, to_csv, savetxt)."""
    with atomic_path(path) as tmp:
        writer(tmp)


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` complete or not at all."""
    with atomic_open(path, "w") as fh:
        fh.write(text)


class ResultsIncomplete(OSError):
    """A set of result files could not be written whole: ``complete`` are
    in place, ``absent`` were not written (``failed`` is the one that
    failed, first of ``absent``); ``errno``/``strerror``/``filename`` are
    those of the failure."""

    def __init__(self, cause: OSError, failed: Path, complete: Sequence[Path], absent: Sequence[Path]) -> None:
        why = cause.strerror or str(cause)
        done = ", ".join(p.name for p in complete) or "none"
        gone = ", ".join(p.name for p in absent)
        old = [p.name for p in absent if p.exists()]
        older = f" ({', '.join(old)}: an earlier run's file, left as it was)" if old else ""
        super().__init__(cause.errno or errno.EIO, f"cannot write {failed}: {why}; complete: {done}; "
                         f"not written: {gone}{older}")
        self.failed = failed
        self.complete = list(complete)
        self.absent = list(absent)

    def __str__(self) -> str:
        return str(self.strerror)


def write_results(files: Sequence[tuple[Path, Callable[[Path], object]]]) -> list[Path]:
    """Write each ``(path, writer)`` in order: ``writer(tmp)`` fills a
    temporary path, renamed to ``path`` once complete (:func:`atomic_path`).
    Returns the paths; on an OS error raises :class:`ResultsIncomplete`
    naming the complete and the absent files."""
    done: list[Path] = []
    for k, (path, writer) in enumerate(files):
        try:
            write_with(path, writer)
        except OSError as exc:
            raise ResultsIncomplete(exc, path, done, [p for p, _ in files[k:]]) from exc
        done.append(path)
    return done


def check_output_dir(directory: str | os.PathLike[str]) -> Path:
    """Make sure result files can be written into ``directory`` (created with
    its parents when missing): raises ``OSError`` (one-line ``strerror``,
    ``filename`` set) when it is a file, cannot be created, or refuses a new
    file (permissions, read-only filesystem, no inode or block left)."""
    d = Path(directory)
    if d.exists() and not d.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "exists and is not a directory", str(d))
    d.mkdir(parents=True, exist_ok=True)
    try:
        fd, probe = tempfile.mkstemp(prefix=".write-test-", dir=d)
    except OSError as exc:
        raise type(exc)(exc.errno, f"cannot create files there ({exc.strerror})", str(d)) from exc
    try:
        os.write(fd, b"\0" * 4096)  # one block: a full filesystem says so now, not after the run
        os.fsync(fd)
    except OSError as exc:
        raise type(exc)(exc.errno, f"cannot write files there ({exc.strerror})", str(d)) from exc
    finally:
        os.close(fd)
        with contextlib.suppress(OSError):
            os.unlink(probe)
    return d
