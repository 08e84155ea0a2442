"""The advisory lock on a sweep's output (``<out>.lock``, flock): one writer at a time."""

from __future__ import annotations

import errno
import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from geometry.atomic import output_error
from geometry.validation import ParameterError


def _lock_path(out: Path) -> Path:
    return out.with_name(out.name + ".lock")


@contextmanager
def output_lock(out: str | Path) -> Iterator[Path]:
    """Hold the advisory lock of a sweep's output: ``<out>.lock`` beside it, locked with
    flock and holding this process's id. A second writer is refused in one line naming
    the holder. The kernel releases the lock of a process however it ends (SIGKILL too), so
    the lock file a killed run left is taken over; the file is removed at the end.

    The locked file must still be the one at the path (a finishing run removes it while a
    new one waits on it): otherwise the lock is taken again on the new file."""
    out = Path(out)
    lock = _lock_path(out)
    while True:
        try:
            lock.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            raise output_error(lock, exc) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = os.pread(fd, 64, 0).decode("ascii", "replace").strip() or "?"
            os.close(fd)
            if exc.errno in (errno.EAGAIN, errno.EACCES):
                raise ParameterError(
                    f"{out}: another sweep (pid {holder}) is writing it ({lock.name} is "
                    "locked); wait for it to end or stop it"
                ) from None
            raise output_error(lock, exc, "cannot lock") from None
        try:
            same = os.fstat(fd).st_ino == os.stat(lock).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        try:  # the holder's pid is a hint for the refusal line; the flock is the lock
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        except OSError:  # a full disk: the work's own writes say so, in one line
            pass
        yield lock
    finally:
        try:
            lock.unlink()
        except FileNotFoundError:
            pass
        os.close(fd)
