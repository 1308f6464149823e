"""What a process pool's fork server imports before it forks the workers, and starting it
early: as the first thing ``preform pipeline run`` does, before it imports its own modules
(pydantic models of scenes and summaries, ~0.1-0.2 s), so the server's imports, the longest
step before the first case, start as soon as possible.

Light on purpose: this module imports nothing heavy, so the command can start the server
before it imports anything else.
"""

from __future__ import annotations

from preform.pipeline.engines import (
    DASK_WORKER_PRELOAD,
    start_fork_server,
    start_local_dask_engine,
    stop_fork_server,
)

#: Libraries the default study's steps import when they first run (its figures and cells.csv):
#: a process pool's fork server imports them once, so no worker pays them in its first case.
#: A name that is not installed is skipped. The compiled net kernels (numba, 0.3 s to import)
#: are there because every drape runs them (and loaded, ``preload_end``), and so is
#: ``scipy.ndimage``, which labels a drape's fold and wrinkle patches
#: (``kernel_compile.DRAPE_LIBRARIES``; not the rest of scipy: 2.0 s on a Dask worker); not
#: ``mpl_toolkits.mplot3d``, which only the unit-cell figure uses now that the fibre-pattern
#: figure projects its 3D view itself (issue 15g).
#: Since built-in steps, laws and architectures are registered by import path, the plugin host
#: no longer imports their modules, so the default study's are named here too (the default
#: study 7.3-8.8 s -> 6.4-8.6 s on 2 workers, quiet, alternated runs of ``preform pipeline run
#: --force``). Not pandas: the default study's tables are written without it
#: (``preform.export.csv_columns``), and pandas 3 imports pyarrow's compute module (about
#: 0.5 s) when pyarrow is installed.
WORKER_PRELOAD = (
    "matplotlib.figure",
    "matplotlib.backends.backend_agg",
    "numba",
    "scipy.ndimage",
    "preform.drape.kernels.net_kernels",
    "preform.drape.kernels.generator_kernels",
    "preform.drape.kernels.field_kernels",
    "preform.shear.surrogate_kernels",
    "preform.pipeline.runner",
    "preform.pipeline.core_steps",
    "preform.drape.steps",
    "preform.drape.preform_steps",
    "preform.optimise.search_steps",
    "preform.export.fig_drape",
    "preform.export.tables",
    "preform.export.csv_columns",
    "preform.plugins.surfaces.basic",
    "preform.plugins.woven.model",
    "preform.plugins.woven.shear",
    "preform.plugins.warpknit.model",
    "preform.plugins.warpknit.shear",
)


def worker_preload() -> tuple[str, ...]:
    """Modules a worker pool imports once before its first case: preform's own modules this
    process has loaded (the steps it plans to run) and ``WORKER_PRELOAD``. Plugin modules
    are not among them: a worker loads those in its warm-up, where their failures are
    contained and recorded like in this process."""
    import sys

    own = [m for m in list(sys.modules) if m == "preform" or m.startswith("preform.")]
    return (*sorted(own), *WORKER_PRELOAD)


def start_workers_early(engine: str = "process", workers: int | None = None) -> None:
    """Start the process pool's fork server before the run's library and scenes are read (the
    command line calls it first): meanwhile it imports the runner, preform's own plugins (the
    steps they register) and ``WORKER_PRELOAD``, and the workers of the pool the run opens
    later are forked from it. For ``engine`` dask, the LocalCluster of ``workers`` workers
    forked from it opens too, in a thread (``engines.start_local_dask_engine``). The server is
    stopped when this process exits (``stop_fork_server``), however the command ends (after a
    cluster opened here and never used is closed)."""
    import atexit
    from importlib import metadata

    from preform.plugin_manager import ENTRY_POINT_GROUP

    own_plugins = sorted(
        ep.value.split(":")[0]
        for ep in metadata.entry_points(group=ENTRY_POINT_GROUP)
        if ep.value.startswith("preform.")
    )
    modules = tuple(dict.fromkeys((*own_plugins, *worker_preload())))
    dask = engine == "dask"
    start_fork_server((*DASK_WORKER_PRELOAD, *modules) if dask else modules)
    atexit.register(stop_fork_server)
    if dask:
        # warmed for the command line's plugins (entry points), which its cases will ask for;
        # a cluster never used is closed at exit before the server stops (registered after)
        warm_up = ("preform.pipeline.runner:warm_worker", (((True, ()),),))
        start_local_dask_engine(workers, modules, warm_up)
