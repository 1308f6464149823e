"""Atomic file writes: a reader (or a resumed run) never sees a half-written result file.

A write goes to a temporary file beside the target, named so that preform (and only preform)
recognises it later: ``.<target name>.<8 random chars>.preform-tmp<target suffix>``. The suffix
stays last because writers such as matplotlib, meshio and pyarrow pick the format from it. A
process killed mid-write leaves such a file behind; :func:`remove_stale_temporaries` removes
exactly these, and never a user's file that merely looks temporary. The finished file gets the
permissions of an ordinary new file under the process's umask (``mkstemp`` would leave 0600).
"""

from __future__ import annotations

import contextlib
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


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it is renamed over ``path``.

    For writers that want a file name (matplotlib, meshio, pyarrow). On an exception the
    temporary file is removed and ``path`` is left as it was.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{target.name}.", suffix=TEMP_MARKER + target.suffix, dir=target.parent
    )
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        if tmp_path.exists():
            os.chmod(tmp_path, 0o666 & ~current_umask())
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


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

    Only names made by :func:`atomic_path` match; call it only while no other preform process
    writes into ``folder`` (the run lock). Returns what was removed.
    """
    removed = []
    for root, _dirs, files in os.walk(folder):
        for name in files:
            if is_temporary_name(name):
                stale = Path(root) / name
                with contextlib.suppress(FileNotFoundError):
                    stale.unlink()
                    removed.append(stale)
    return removed
