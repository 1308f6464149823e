"""Atomic file writes: a reader (or a resumed run) never sees a half-written result file.

A write goes to a temporary file beside the target, named so that preform (and only preform)
recognises it later: ``.<target name>.<8 random chars>.preform-tmp<target suffix>``. The suffix
stays last because writers such as matplotlib, meshio and pyarrow pick the format from it. A
process killed mid-write leaves such a file behind; :func:`remove_stale_temporaries` removes
exactly these, and never a user's file that merely looks temporary. The finished file gets the
permissions of an ordinary new file under the process's umask (``mkstemp`` would leave 0600).

A writer holds an exclusive ``flock`` on its temporary file from just after it is made until it
is renamed into place, and the clean-up removes only a temporary it can lock itself: one whose
writer is gone (the kernel releases a dead process's locks). So the clean-up is safe beside any
live writer, whatever process it is and whatever lock it holds or does not hold: a ``preform
export`` into a folder a run cleans (issue 25), a second run into a folder below another's. The
clean-up can win the race for a temporary only in the moment between ``mkstemp`` and the
writer's lock; the writer then finds its file gone and makes another.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

#: The marker in every temporary file name this module creates.
TEMP_MARKER = ".preform-tmp"
_TEMP_NAME = re.compile(r"^\..+\.[a-z0-9_]{8}" + re.escape(TEMP_MARKER) + r"(\.[^./]*)?$")
_umask_lock = threading.Lock()


def is_temporary_name(name: str) -> bool:
    """Whether a file name is one of the temporary names this module creates."""
    return bool(_TEMP_NAME.match(name))


def current_umask() -> int:
    """The process's umask, without changing it for other threads where the OS allows."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    with _umask_lock:  # elsewhere the only way to read it is to set it
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: no flock; the run lock alone guards there
    fcntl = None  # type: ignore[assignment]


def _lock_fd(fd: int, *, wait: bool) -> bool:
    """Take an exclusive flock on ``fd``; False when another process holds it (``wait``
    False). Always True where there is no flock."""
    if fcntl is None:  # pragma: no cover - Windows
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
    except OSError as exc:
        if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
            return False
        raise
    return True


def _same_file(fd: int, path: str) -> bool:
    """Whether ``path`` still names the file open as ``fd`` (the clean-up did not remove it)."""
    try:
        on_disk = os.stat(path)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (on_disk.st_dev, on_disk.st_ino) == (held.st_dev, held.st_ino)


def _locked_temporary(target: Path) -> tuple[int, Path]:
    """A new temporary file beside ``target``, open and flocked by this process."""
    while True:
        fd, tmp = tempfile.mkstemp(
            prefix=f".{target.name}.", suffix=TEMP_MARKER + target.suffix, dir=target.parent
        )
        # waits while a clean-up holds it; it unlinks before it lets go
        _lock_fd(fd, wait=True)
        if _same_file(fd, tmp):
            return fd, Path(tmp)
        os.close(fd)  # a clean-up took it in the moment before the lock: make another


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it is renamed over ``path``.

    For writers that want a file name (matplotlib, meshio, pyarrow). On an exception the
    temporary file is removed and ``path`` is left as it was. The temporary is locked while
    it exists (module docstring), so no clean-up removes it under the writer.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_path = _locked_temporary(target)
    try:
        yield tmp_path
        if tmp_path.exists():
            os.chmod(tmp_path, 0o666 & ~current_umask())
        os.replace(tmp_path, target)
    finally:
        try:
            if tmp_path.exists():
                tmp_path.unlink()
        finally:
            os.close(fd)  # releases the lock, after the rename or the removal


@contextlib.contextmanager
def atomic_open(
    path: str | os.PathLike[str], mode: str = "w", encoding: str | None = "utf-8"
) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path`` for writing; rename it over ``path`` on success."""
    binary = "b" in mode
    with atomic_path(path) as tmp, open(tmp, mode, encoding=None if binary else encoding) as handle:
        yield handle
        handle.flush()
        os.fsync(handle.fileno())


def remove_stale_temporaries(folder: Path) -> list[Path]:
    """Remove the temporary files that interrupted atomic writes left below ``folder``.

    Only names made by :func:`atomic_path` match, and only those no live writer holds locked
    (module docstring): safe while other processes write into ``folder``. Returns what was
    removed.
    """
    removed = []
    for root, _dirs, files in os.walk(folder):
        for name in files:
            if is_temporary_name(name):
                stale = Path(root) / name
                if _remove_if_unheld(stale):
                    removed.append(stale)
    return removed


def _remove_if_unheld(stale: Path) -> bool:
    """Remove a temporary file unless a live writer holds its lock; held while removing, so a
    writer that locks it next finds it gone (``_locked_temporary``)."""
    try:
        fd = os.open(stale, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError:  # gone (renamed into place), or not ours to open
        return False
    try:
        if not _lock_fd(fd, wait=False) or not _same_file(fd, str(stale)):
            return False
        stale.unlink()
        return True
    except FileNotFoundError:
        return False
    finally:
        os.close(fd)
