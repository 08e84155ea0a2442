"""The output layer: every file the tool writes goes through here.

A file is written to a temporary name in its target folder, flushed to the disk (fsync)
and renamed into place, so it appears complete or not at all: an error, Ctrl-C or a kill
leaves any previous file untouched and no temporary file behind. Any OSError on the way
(disk full, read-only file system, permission, a quota) becomes one ``OutputError``
naming the path and the reason, which the command line prints as one line (exit 2). A
target that exists and is not a regular file (a device node, a FIFO, a socket) is refused,
never replaced; a symbolic link is written through (the link stays, its target changes).

Lives in the lowest package so that geometry (CAD export), the product (sweeps, designs)
and the command line (plots, report, JSON) all write files the same way.
"""

from __future__ import annotations

import errno
import os
import stat
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = [
    "OutputError",
    "atomic_path",
    "check_target",
    "fsync_dir",
    "output_error",
    "user_cache",
    "write_bytes",
    "write_text",
]


class OutputError(Exception):
    """A file could not be written: one line naming the path and the reason."""


def output_error(path: str | os.PathLike[str], exc: OSError, what: str = "cannot write"
                 ) -> OutputError:  # fmt: skip
    """``OutputError`` of ``exc`` met while writing ``path``: ``PATH: cannot write (reason)``."""
    reason = exc.strerror or (errno.errorcode.get(exc.errno or 0) if exc.errno else None)
    return OutputError(f"{os.fspath(path)}: {what} ({reason or str(exc) or type(exc).__name__})")


_KINDS = (
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISDIR, "a directory"),
)


def check_target(path: str | os.PathLike[str]) -> Path:
    """The file ``path`` names, links followed; OutputError when it exists and is not a
    regular file (it would be replaced by one: a device node, a FIFO, a folder)."""
    dest = Path(path)
    try:
        st = os.stat(dest)
    except FileNotFoundError:
        return Path(os.path.realpath(dest)) if dest.is_symlink() else dest
    except OSError as exc:
        raise output_error(dest, exc) from None
    for test, kind in _KINDS:
        if test(st.st_mode):
            raise OutputError(f"{dest}: is {kind}, not a regular file; not replaced")
    return Path(os.path.realpath(dest)) if dest.is_symlink() else dest


def fsync_dir(folder: str | os.PathLike[str]) -> None:
    """Flush a folder's entries (a rename in it) to the disk; file systems that cannot
    (EINVAL) are left as they are."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as exc:
        if exc.errno not in (errno.EINVAL, errno.EBADF, errno.EROFS):
            raise
    finally:
        os.close(fd)


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; when the body returns, the file there is
    flushed to the disk and renamed into place.

    On any exception (or Ctrl-C) the temporary file is removed and ``path`` is untouched;
    an OSError (the body's or the layer's own) is raised as ``OutputError`` naming ``path``.
    """
    shown = Path(path)
    dest = check_target(shown)
    tmp_path: Path | None = None
    try:
        dest.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{dest.stem}-", suffix=dest.suffix, dir=dest.parent)
        os.close(fd)
        tmp_path = Path(tmp)
        yield tmp_path
        fd = os.open(tmp_path, os.O_RDONLY)
        try:
            os.fsync(fd)  # the bytes are on the disk before the name points at them
        finally:
            os.close(fd)
        os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
        check_target(shown)  # it may have become a device or FIFO while we worked
        os.replace(tmp_path, dest)
        tmp_path = None
        fsync_dir(dest.parent)
    except OSError as exc:
        raise output_error(shown, exc) from None
    finally:
        if tmp_path is not None:
            try:
                tmp_path.unlink()
            except FileNotFoundError:
                pass


def write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """``data`` into ``path`` through ``atomic_path``."""
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(data)
    return Path(path)


def write_text(path: str | os.PathLike[str], text: str, newline: str | None = None) -> Path:
    """``text`` (UTF-8) into ``path`` through ``atomic_path``."""
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline=newline) as f:
        f.write(text)
    return Path(path)


def user_cache(name: str) -> Path:
    """The folder ``name`` of mrclutch's caches in the user's cache folder
    (``$XDG_CACHE_HOME``, ``~/.cache``; ``%LOCALAPPDATA%`` on Windows), never inside the
    installed package (issue 39); not created here."""
    if sys.platform == "win32" and os.environ.get("LOCALAPPDATA"):
        base = Path(os.environ["LOCALAPPDATA"])
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "mrclutch" / name


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
