"""Compile the drape kernels once per install, in one process, saying so.

The kernels (``*_kernels.py``) are compiled by numba at their first call and cached by content
(``preform.base.kernel_cache``). Left to themselves, the first run after an install compiled
them silently in every worker at once: both workers of a two-core run spent the same ~20 s of
processor time compiling the same kernels. :func:`ensure_compiled`, which ``preform pipeline
run`` calls before its cases start, does it once instead: when the kernels of these sources are
not yet known to be compiled, one process takes a lock, prints one line on stderr
("compiling drape kernels, once per install, ~N s"), compiles them by running a small
least-energy case of the default study (on two cores or more with a helper process that
compiles, meanwhile, the kernels the case calls after its drape), marks the key compiled and
prints the time it took; any other process that asks meanwhile waits for the lock and then
loads the kernels from the cache. Afterwards the check costs reading and hashing the kernels'
sources (10-30 ms at load 11), and no numba import.

The small case compiles every kernel the default study calls; a study that calls others (a
mesh tool's queries, a run that marches generators on another tool) compiles those at their
first call, once per install as before, through the same cache.

An installed copy has done this when its wheel was built (``pip install .`` runs
``python -m preform.commands.kernel_compile --ship`` on the built tree: the compile is part of the
install, with pip's other build output): the kernels and their marker are shipped in the package
(``kernel_cache.shipped_root``), and a user's first run finds the marker there, checks that it
was compiled for this processor (:func:`host_processor`) and takes the kernels into its cache
instead of compiling. A source checkout (``pip install -e .``) compiles at its first run.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from preform.base.kernel_cache import (
    CACHE_ENV,
    WARMED,
    cache_root,
    load_compiled,
    shipped_root,
    source_key,
)

#: The estimate [s] printed before the first compile on a machine that has not compiled
#: them before (later compiles print the last one's time): the default study's kernels took
#: 19-45 s of one core on the shared two-core machine of benchmarks/README.md, section (p).
TYPICAL_COMPILE_S = 25.0

#: The small case that compiles them: the default study's scene and a fabric of the bundled
#: library, at a coarse spacing (the signatures, not the sizes, decide what is compiled).
_WARM_FABRIC = "E-BX-318"
_WARM_SPACING_MM = 30.0
_WARM_OUTPUTS = ["energy_vs_angle", "optimum", "drape", "cells_csv"]

#: The helper process (:func:`_start_helper`): this module (by name: as ``python -m`` it is
#: ``__main__``) with this flag and the pid of the process it helps.
HELPER_MODULE = "preform.commands.kernel_compile"
HELPER_FLAG = "--helper"
#: Compile into the package's own folder (``kernel_cache.shipped_root``): the wheel build's step.
SHIP_FLAG = "--ship"


def compiled_key() -> str:
    """The key of the default study's kernels as the sources now stand (16 hex digits)."""
    keys = "\0".join(f"{module}={source_key(module)}" for module in WARMED)
    return hashlib.sha256(keys.encode()).hexdigest()[:16]


def ready_marker(root: Path | None = None) -> Path:
    """The file whose presence says these sources' kernels are compiled (it holds the
    seconds the compile took)."""
    return (root or cache_root()) / f"compiled-{compiled_key()}"


def ensure_compiled(stream: IO[str] | None = None) -> float | None:
    """Compile the default study's kernels unless they are known to be (see the module
    docstring); lines for the user go to ``stream`` (None: silent). Returns the seconds spent
    compiling, or None when nothing was compiled here."""
    root = cache_root()
    marker = ready_marker(root)
    if marker.exists() or _take_shipped(marker):
        return None
    root.mkdir(parents=True, exist_ok=True)
    with _one_at_a_time(root / f"lock-{marker.name}", stream):
        if marker.exists():  # compiled by the process we waited for
            return None
        ran, seconds = _compile(root, stream)
        if ran:  # compiled here, or all loaded (compiled earlier at first use): known now
            marker.write_text(f"{seconds or 0.0:.1f}\n")
        if seconds is not None:
            (root / "last-compile-seconds").write_text(f"{seconds:.1f}\n")
    return seconds


def host_processor() -> str:
    """What numba keys a compiled kernel by besides its types: the target triple, the
    processor's name and features (as numba's codegen asks llvmlite; numba not imported)."""
    import llvmlite.binding as llvm

    features = llvm.get_host_cpu_features().flatten()
    return f"{llvm.get_process_triple()} {llvm.get_host_cpu_name()} {features}"


def _take_shipped(marker: Path) -> bool:
    """Whether the package ships these sources' kernels compiled for this processor (its
    marker's second line); if so the user's marker is written, and each kernel module copies
    its shipped kernels into the user's cache when imported (``kernel_cache.cache_by_content``)."""
    shipped = shipped_root() / marker.name
    if shipped == marker or not shipped.exists():
        return False
    lines = shipped.read_text().splitlines()
    if lines[1:2] != [host_processor()]:
        return False
    with contextlib.suppress(OSError):
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.write_text(f"{lines[0]}\n")
    return True


def ship(stream: IO[str] | None) -> None:
    """Compile the default study's kernels into the package's own folder, marked with the
    processor they were compiled for (the wheel build calls it on the built tree)."""
    root = shipped_root()
    shutil.rmtree(root, ignore_errors=True)  # an earlier build's keys
    os.environ[CACHE_ENV] = str(root)
    ensure_compiled(stream)
    marker = ready_marker(root)
    if not marker.exists():
        raise RuntimeError("the drape kernels could not be compiled for the package")
    marker.write_text(f"{marker.read_text().strip()}\n{host_processor()}\n")
    for scratch in [*root.glob("lock-*"), root / "last-compile-seconds"]:
        scratch.unlink(missing_ok=True)


#: What a drape imports at its first call besides the kernels: the labelling of fold and
#: wrinkle patches (``preform.drape.judging.wrinkling``; 0.2-0.8 s to import).
DRAPE_LIBRARIES = ("scipy.ndimage",)


def load_for_serial_run(cases: Any) -> None:
    """Load the default study's kernels (and ``DRAPE_LIBRARIES``) into this process before a
    serial run's first case when any case drapes (its scene names a tool): numba's loading
    (~0.5 s of one core, quiet) is then the run's one-off cost, not its first case's."""
    if any("tool" in (getattr(case, "scene_data", None) or {}) for case in cases):
        import importlib

        for module in DRAPE_LIBRARIES:
            importlib.import_module(module)
        load_compiled(WARMED)


def _say(stream: IO[str] | None, line: str) -> None:
    if stream is not None:
        print(f"preform: {line}", file=stream, flush=True)


@contextlib.contextmanager
def _one_at_a_time(path: Path, stream: IO[str] | None) -> Iterator[None]:
    """Hold an exclusive lock on ``path`` (a file) while compiling; where the platform has
    no ``fcntl`` (Windows) processes may compile side by side, as before."""
    try:
        import fcntl
    except ImportError:
        yield
        return
    with path.open("a") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            _say(stream, "waiting for another process compiling the drape kernels")
            fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _estimate(root: Path) -> float:
    with contextlib.suppress(OSError, ValueError):
        return float((root / "last-compile-seconds").read_text())
    return TYPICAL_COMPILE_S


def _compile(root: Path, stream: IO[str] | None) -> tuple[bool, float | None]:
    """Run the small case, saying so when numba starts compiling. Returns whether it ran
    through (when it failed, the kernels it did not reach compile at their first call, as
    before) and the seconds from the first compile to its end (None: nothing compiled,
    everything came from the cache)."""
    from numba.core import event

    started: list[float] = []

    class FirstCompile(event.Listener):
        def on_start(self, event: Any) -> None:
            if not started:
                started.append(time.perf_counter())
                estimate = _estimate(root)
                _say(stream, f"compiling drape kernels, once per install, ~{estimate:.0f} s")

        def on_end(self, event: Any) -> None:
            # numba's Listener asks for both; the time is said once all kernels are compiled
            pass

    helper = _start_helper()
    try:
        with event.install_listener("numba:compile", FirstCompile()):
            _small_case()
    except Exception as exc:  # the run's own cases meet it again and record it
        _say(stream, f"drape kernels not compiled ahead ({type(exc).__name__}: {exc})")
        return False, None
    finally:
        if helper is not None:
            helper.terminate()  # what it still does is no longer needed here
            helper.wait()
    if not started:
        return True, None
    seconds = time.perf_counter() - started[0]
    _say(stream, f"drape kernels compiled in {seconds:.1f} s (cache: {root})")
    return True, seconds


def _start_helper() -> subprocess.Popen[bytes] | None:
    """On two cores or more, a second process that compiles the kernels the small case
    calls after its drape (shear fields, coverage, the shear-law surrogate) while this one
    compiles the drape's fill: its drape runs the fill as plain Python (:func:`_help`). What
    it compiles first is loaded from the cache here; what this process reaches first, the
    helper compiles in vain (its results are the same). Nothing depends on it: this process
    runs the whole small case either way."""
    if (os.cpu_count() or 1) < 2:
        return None
    with contextlib.suppress(OSError):
        return subprocess.Popen(
            [sys.executable, "-m", HELPER_MODULE, HELPER_FLAG, str(os.getpid())],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    return None


def _help() -> None:
    """The helper's work: one drape of the small case's scene and fabric with the net
    kernels run as Python (their numba dispatchers swapped for the functions they compile),
    so it compiles no fill and goes on at once to the kernels after the drape."""
    from numba.core.registry import CPUDispatcher

    from preform.drape.kernels import net_kernels

    for name, value in list(vars(net_kernels).items()):
        if isinstance(value, CPUDispatcher):
            setattr(net_kernels, name, value.py_func)
    from preform import api

    # one drape, not the search: the same kernels after it, a fraction of the Python fills
    api.drape(_WARM_FABRIC, node_spacing_mm=_WARM_SPACING_MM, outputs=["drape", "cells_csv"])


def _small_case() -> None:
    import logging

    from preform import api

    quiet = logging.getLogger("preform")
    level = quiet.level
    quiet.setLevel(logging.ERROR)  # its warnings are about the coarse net, not the user's run
    try:
        api.least_energy(
            _WARM_FABRIC, node_spacing_mm=_WARM_SPACING_MM, outputs=list(_WARM_OUTPUTS)
        )
    finally:
        quiet.setLevel(level)


def main() -> None:
    """``python -m preform.commands.kernel_compile``: compile now (e.g. after installing)."""
    if sys.argv[1:2] == [HELPER_FLAG]:
        from preform.pipeline.engines import watch_parent

        if sys.argv[2:]:  # ends with the process it helps (a kill -9 leaves nothing behind)
            watch_parent(int(sys.argv[2]))
        _help()
        return
    if sys.argv[1:2] == [SHIP_FLAG]:
        ship(sys.stderr)
        return
    seconds = ensure_compiled(sys.stderr)
    if seconds is None:
        print(f"preform: drape kernels already compiled ({ready_marker()})", file=sys.stderr)


if __name__ == "__main__":
    main()
