"""What a Dask worker runs when it starts, and again each time it is restarted, before any case.

The Dask engine (``preform.pipeline.engines.DaskEngine``) registers :class:`PrepareWorker` with
its client: Dask runs its ``setup`` on every worker of the cluster, on every worker that joins
later, and on a worker its nanny restarts after a crash or a case past its time limit, before
that worker takes a task. So a restarted worker is as warm as the first ones, and on a
``LocalCluster`` it takes this process's state whatever process it was forked from: its
workers are forked from the process pool's fork server (``engines.pool_context``), which holds
the environment of the moment it started, not of the moment a worker is forked.

Imports ``distributed``: only the Dask engine imports this module.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import sys
from typing import Any

from distributed import WorkerPlugin

from preform.pipeline.engines import WarmUp, run_warm_up, take_parent_state


class PrepareWorker(WorkerPlugin):
    """Take the ``preform`` process's state (``LocalCluster`` only), import ``preload`` and run
    ``warm_up`` on each (re)started worker.

    ``parent`` is ``(pid, environ, sys_path)`` of the ``preform`` process for workers on this
    machine: the worker exits when that process is gone (a ``kill -9`` leaves nothing computing
    into the results directory) and takes its environment and ``sys.path`` (plugins found
    through ``PYTHONPATH`` or ``PREFORM_LOAD_PLUGINS`` set after the fork server started). None
    for a remote cluster, whose workers keep their own environment.
    """

    #: One per cluster: registering it again (a second run on the same cluster) replaces it.
    name = "preform-prepare-worker"

    def __init__(
        self,
        preload: tuple[str, ...],
        warm_up: WarmUp | None,
        parent: tuple[int, dict[str, str], list[str]] | None = None,
    ) -> None:
        self.preload = preload
        self.warm_up = warm_up
        self.parent = parent

    async def setup(self, worker: Any) -> None:
        if self.parent is not None:
            take_parent_state(*self.parent)
            # Dask's own entry: files sent with ``Client.upload_file`` are imported from there
            local = getattr(worker, "local_directory", None)
            if local and local not in sys.path:
                sys.path.insert(0, local)
        # the imports and plugin hosts take up to seconds: off the worker's event loop, which
        # must keep answering the scheduler (a blocked loop is reported as unresponsive)
        await asyncio.get_running_loop().run_in_executor(None, self.warm)

    def warm(self) -> None:
        """Import ``preload`` (what is not installed is skipped) and run the warm-up. A failure
        here is not the worker's: the case that needs what failed meets it again and records
        it in words, as it would in the ``preform`` process."""
        for module in self.preload:
            with contextlib.suppress(ImportError):
                importlib.import_module(module)
        with contextlib.suppress(Exception):
            run_warm_up(self.warm_up)
