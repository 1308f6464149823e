"""When Python's cyclic garbage collector runs: not while a process starts.

Starting up (importing numpy, matplotlib, numba, pydantic and preform's modules, building the
plugin host, reading the library) makes some 10⁵ objects that live as long as the process. The
collector examines every tracked object at least once after it is made, whatever its
thresholds, and gains nothing here: start-up leaves little garbage. Measured on this project's
machine (2 cores; ``python benchmarks/bench_startup.py`` and
``python benchmarks/bench_study.py``, README section k, "fourth round"): 18-21 ms of
``preform materials list``'s ~200 ms were collections, and 0.26-0.31 s of the ~1.1 s a process
pool's fork server spends importing and loading numba's target (391 collections).

So the collector is paused while a process starts and resumed when its work begins, the
pattern the CPython documentation gives for ``gc.freeze`` (disable early, freeze before the
work or the fork, enable after):

- the ``preform`` command's entry point pauses it first thing (:func:`pause_for_startup`) and
  ``preform.cli`` resumes it once the command to run is known and imported
  (:func:`end_startup`), before its body runs, so a command (a plugin's too) computes with the
  collector on;
- so do the later phases of its start-up (:func:`startup_phase`): importing the library's
  modules and reading it, and for ``pipeline run`` the scenes and the plan, work bounded by
  the files read;
- a process pool's fork server imports :mod:`preform.pipeline.preload_begin` first and
  :mod:`preform.pipeline.preload_end` last, so its workers are forked with the collector on.

Pausing without freezing would only defer the cost: the first collection after it examines
everything the pause let accumulate. So resuming freezes what start-up made (``gc.freeze``):
later collections of a long run skip those objects, and a forked worker's collections do not
write into pages it shares with the fork server. Start-up's few cyclic garbage objects are
frozen with them, never freed: a full collection to free them (measured 0.2 s after a fork
server's preload) costs more than the pause saves, and what they hold did not show in the peak
memory of the command (309-314 MB in a serial run, before and after) or of the fork server
(139-140 MB).
"""

from __future__ import annotations

import contextlib
import gc
from collections.abc import Iterator

#: Whether this process is the ``preform`` command: its entry point paused the collector
#: (:func:`pause_for_startup`), so the later phases of its start-up may pause it again.
_COMMAND_PROCESS = False
#: Whether the collector is off because start-up paused it (until :func:`end_startup`).
_PAUSED = False
#: :func:`startup_phase` blocks open now.
_PHASES = 0


def pause_for_startup() -> None:
    """The ``preform`` command's entry point: disable the collector until :func:`end_startup`,
    if it is on (a caller that turned it off itself keeps it off)."""
    global _COMMAND_PROCESS
    _COMMAND_PROCESS = True
    pause()


def pause() -> None:
    """Disable the collector until :func:`end_startup`, if it is on (a process pool's fork
    server, for its imports: ``preform.pipeline.preload_begin``)."""
    global _PAUSED
    if gc.isenabled():
        gc.disable()
        _PAUSED = True


def end_startup() -> None:
    """Freeze the objects start-up made and enable the collector again, if start-up paused it;
    else nothing (called again, or never paused)."""
    global _PAUSED
    if _PAUSED:
        _PAUSED = False
        gc.freeze()
        gc.enable()


@contextlib.contextmanager
def startup_phase() -> Iterator[None]:
    """A later phase of the ``preform`` command's start-up (importing the library's modules
    and reading it, the scenes, the plan): the collector is off inside the block, and what
    the block made is frozen when it ends (:func:`end_startup`). Only in the command's own
    process: elsewhere (the Python API, a test invoking a command in its process) nothing
    changes, since freezing would keep that process's garbage for good."""
    global _PHASES
    if not _COMMAND_PROCESS:
        yield
        return
    if _PHASES == 0:
        pause()
    _PHASES += 1
    try:
        yield
    finally:
        _PHASES -= 1
        if _PHASES == 0:  # a phase inside another (the library read while planning) ends with it
            end_startup()
