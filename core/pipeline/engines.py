"""Where cases run: ``concurrent.futures`` executors, nothing home-made.

``serial`` runs each case when it is submitted (debugging, exact tracebacks), ``process`` is a
local process pool (the default), ``dask`` hands cases to a Dask cluster through
``Client.get_executor()`` (optional extra ``preform[dask]``).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from typing import Any, TypeVar

T = TypeVar("T")

ENGINES = ("serial", "process", "dask")


class SerialExecutor(Executor):
    """Runs each submitted call at once, in this process; the future is already done."""

    def submit(self, fn: Callable[..., T], /, *args: Any, **kwargs: Any) -> Future[T]:
        future: Future[T] = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # delivered through the future, like any executor
            future.set_exception(exc)
        return future


@contextlib.contextmanager
def open_executor(
    engine: str, *, workers: int | None = None, scheduler: str | None = None
) -> Iterator[Executor]:
    """An executor for ``engine``, closed on exit."""
    if engine == "serial":
        yield SerialExecutor()
    elif engine == "process":
        n = workers or max(1, os.cpu_count() or 1)
        # spawn: safe with threads in the parent, and each worker sees the parent's current
        # sys.path and environment (plugins installed since start-up included); the import
        # cost is paid once per worker, not per case
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=n, mp_context=ctx) as pool:
            yield pool
    elif engine == "dask":
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise RuntimeError(
                'the dask engine needs the optional extra: pip install "preform[dask]"'
            ) from None
        if scheduler:
            client = Client(scheduler)
            cluster = None
        else:
            cluster = LocalCluster(
                n_workers=workers or 2,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
            )
            client = Client(cluster)
        try:
            yield client.get_executor()
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    else:
        raise ValueError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
