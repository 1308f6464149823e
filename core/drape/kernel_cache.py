"""Compiled kernels' caches kept in step with every source they were compiled from.

numba keys a kernel's on-disk cache (``cache=True``) on the kernel's own source file only, its
modification time and size. A kernel that inlines a function of another module, or reads one
of its constants (node and cell statuses, surface kinds: numba freezes globals into the machine
code), keeps running the old code from its cache after that other file changed, a silent wrong
number for whoever edits the kernels. (An installed copy is safe: installing writes every file
anew, and the caches are made after.) So each kernel module names the preform modules compiled
into it (``COMPILED_IN``) and calls :func:`drop_stale` when imported, before any kernel runs:
its cached kernels older than one of those modules, followed through their own
``COMPILED_IN``, are removed, and numba compiles them again, once.

Only the caches numba keeps beside the sources (``__pycache__``, its place for a writable
tree) are looked at; caches elsewhere (``NUMBA_CACHE_DIR``, a read-only install) are numba's.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterable
from pathlib import Path


def compiled_in(modules: Iterable[str]) -> set[str]:
    """``modules`` and, through each one's ``COMPILED_IN``, every module compiled into them
    (imported modules, by name)."""
    seen: set[str] = set()
    todo = list(modules)
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        todo += list(getattr(sys.modules.get(name), "COMPILED_IN", ()))
    return seen


def drop_stale(module: str) -> list[Path]:
    """Remove the cache files (index ``.nbi`` and data ``.nbc``) of kernel module ``module``
    (its name; imported, with a ``COMPILED_IN``) that are older than a module compiled into it;
    returns what was removed."""
    own = sys.modules[module]
    source = Path(str(own.__file__))
    sources = compiled_in(getattr(own, "COMPILED_IN", ())) - {module}
    newest = 0.0
    for name in sources:
        path = getattr(sys.modules.get(name), "__file__", None)
        if path is None:
            continue
        with contextlib.suppress(OSError):
            newest = max(newest, os.stat(path).st_mtime)
    removed: list[Path] = []
    cache = source.parent / "__pycache__"
    try:
        indexes = sorted(cache.glob(f"{source.stem}.*.nbi"))
    except OSError:
        return removed
    for index in indexes:
        try:
            stale = index.stat().st_mtime < newest
        except OSError:  # another process removed it meanwhile
            continue
        if not stale:
            continue
        # numba names a kernel's data files after its index: <index stem>.<n>.nbc
        for path in [index, *cache.glob(f"{index.name[: -len('.nbi')]}.*.nbc")]:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
                removed.append(path)
    return removed
