"""Where cases run: an executor per engine, nothing home-made.

``serial`` runs each case in this process when it is submitted (debugging, exact tracebacks;
a case that crashes the interpreter ends the run there, which docs/engines.md says);
``process`` is a local pool of worker processes (the default), built on ``pebble`` because it
does what ``concurrent.futures.ProcessPoolExecutor`` cannot: a worker that dies (segfault,
``os._exit``, the OOM killer) fails only its own case and is replaced, and a case past its time
limit is stopped by killing its worker. ``dask`` hands cases to a Dask cluster through
``Client.submit`` (optional extra ``preform[dask]``); there a time limit is enforced by the
runner, which cancels the case and restarts its worker, and by the case itself between steps.

Every engine gives back ``concurrent.futures.Future`` objects, and :meth:`Engine.stop` ends
everything at once (Ctrl-C). Worker processes watch their parent and exit when it is gone, so a
``kill -9`` of the main process does not leave them computing into the results directory.

Worker start-up is paid once per pool, not once per worker: where the platform has it, the
process pool forks its workers from a ``forkserver`` that imported preform, the plugins' step
modules and the libraries the planned steps import lazily (``Engine`` ``preload``) before the
first case; each worker then takes the parent's current ``sys.path`` and environment and runs
the runner's warm-up (building its plugin host) once. Elsewhere (Windows) workers are spawned
and each pays its imports itself.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future
from typing import Any, TypeVar

T = TypeVar("T")

ENGINES = ("serial", "process", "dask")

#: How often a worker checks that its parent process is still alive [s].
PARENT_POLL_S = 0.2


class CaseTimeout(BaseException):
    """Raised inside a case that ran past its time limit (a BaseException, so the case's own
    ``except Exception`` handlers cannot swallow it)."""


class Engine:
    """An executor of cases, how many cases to keep in flight, and a way to stop at once."""

    #: Cases the runner keeps submitted at a time (more only queue, and a queued case would
    #: have to be cancelled on an interrupt).
    capacity: int = 1
    #: Cases the engine computes at the same time (its worker processes or threads).
    workers: int = 1
    #: Whether ``submit(..., timeout_s=)`` is enforced by the engine itself.
    enforces_timeout: bool = False

    def submit(self, fn: Callable[..., T], *args: Any, timeout_s: float | None = None) -> Future[T]:
        raise NotImplementedError  # each engine below implements it

    def abandon(self, future: Future[Any]) -> None:
        """Stop one case the runner gave up on (past its time limit), if the engine can."""
        future.cancel()

    def stop(self) -> None:
        """Stop every running and queued case now (interrupt)."""

    def close(self) -> None:
        """Release the engine's resources after a normal end."""


class SerialExecutor(Executor):
    """Runs each submitted call at once, in this process; the future is already done."""

    def submit(self, fn: Callable[..., T], /, *args: Any, **kwargs: Any) -> Future[T]:
        future: Future[T] = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except (Exception, CaseTimeout) as exc:  # delivered through the future, like any executor
            future.set_exception(exc)
        return future


def _raise_timeout(_signum: int, _frame: Any) -> None:
    raise CaseTimeout()


def can_alarm() -> bool:
    """Whether this thread can stop its own call at a time limit (SIGALRM: the main thread of
    a process, where the platform has it)."""
    return hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def time_limit(timeout_s: float | None) -> Iterator[None]:
    """Raise ``CaseTimeout`` in this thread after ``timeout_s`` [s] (SIGALRM; no limit with
    None or where ``can_alarm`` is false). It interrupts Python code; a single long call into
    compiled code ends before it fires."""
    if timeout_s is None or not can_alarm():
        yield
        return
    previous = signal.signal(signal.SIGALRM, _raise_timeout)
    signal.setitimer(signal.ITIMER_REAL, timeout_s)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


class SerialEngine(Engine):
    """In this process, one case at a time, with ``time_limit``.
    A crash of this process ends the run; what finished is already recorded."""

    capacity = 1

    def __init__(self) -> None:
        self._executor = SerialExecutor()
        self.enforces_timeout = can_alarm()

    def submit(self, fn: Callable[..., T], *args: Any, timeout_s: float | None = None) -> Future[T]:
        with time_limit(timeout_s):
            return self._executor.submit(fn, *args)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else (pid reused): not our parent
        return False
    return True


#: The parents this process watches already (``watch_parent``).
_WATCHED: set[int] = set()


def watch_parent(parent_pid: int) -> None:
    """Worker initializer: exit at once when the main process is gone (kill -9, crash).

    A daemon thread polls; when the worker is re-parented (its parent, the main process or the
    fork server, died) or the main process no longer exists, its results would go nowhere and it
    might still write into the results directory, so it ends itself.
    """
    if parent_pid in _WATCHED:  # a Dask worker prepared again (a later run's warm-up)
        return
    _WATCHED.add(parent_pid)
    own_parent = os.getppid()

    def watch() -> None:
        while True:
            if os.getppid() != own_parent or not _alive(parent_pid):
                os._exit(1)
            time.sleep(PARENT_POLL_S)

    threading.Thread(target=watch, name="preform-parent-watch", daemon=True).start()


#: A worker's warm-up: ``"module:function"`` and its (picklable) arguments, run once when the
#: worker starts, before its first case. By name, so it is imported only after the worker took
#: the parent's ``sys.path``.
WarmUp = tuple[str, tuple[Any, ...]]


def run_warm_up(warm_up: WarmUp | None) -> None:
    """Import the warm-up's function and call it."""
    if warm_up is None:
        return
    import importlib

    target, args = warm_up
    module, function = target.split(":")
    getattr(importlib.import_module(module), function)(*args)


def start_worker(
    parent_pid: int,
    environ: dict[str, str],
    sys_path: list[str],
    warm_up: WarmUp | None = None,
) -> None:
    """Process-pool initializer: take the parent's state (``take_parent_state``), then warm
    up."""
    take_parent_state(parent_pid, environ, sys_path)
    run_warm_up(warm_up)


def take_parent_state(parent_pid: int, environ: dict[str, str], sys_path: list[str]) -> None:
    """In a worker on this machine: watch the parent (``watch_parent``) and take its current
    environment and ``sys.path`` (a fork server started earlier holds older ones); the
    directories on it may have gained modules since the fork server read them, so the import
    system's caches are dropped."""
    import importlib
    import sys

    watch_parent(parent_pid)
    os.environ.clear()
    os.environ.update(environ)
    sys.path[:] = sys_path
    importlib.invalidate_caches()


#: Imported first and last by the fork server: they pause and resume the garbage collector
#: around its imports (``preform.collector``).
PRELOAD_BEGIN = "preform.pipeline.preload_begin"
PRELOAD_END = "preform.pipeline.preload_end"


def pool_context(preload: tuple[str, ...] = ()) -> Any:
    """The multiprocessing context of the process pool: ``forkserver`` importing ``preload``
    once (only the first pool of a process sets it: the server then lives as long as the
    process), or ``spawn`` where there is no fork server."""
    import multiprocessing

    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    # not '__main__': the main module may be a test runner or a script without a guard. The
    # server imports them in this order: the garbage collector is paused for its imports and
    # resumed before the first fork (preform.collector).
    modules = sorted(set(preload) - {PRELOAD_BEGIN, PRELOAD_END})
    context.set_forkserver_preload([PRELOAD_BEGIN, *modules, PRELOAD_END])
    return context


def start_fork_server(preload: tuple[str, ...]) -> None:
    """Start the process pool's fork server now, importing ``preload``, so that its imports
    overlap what this process does before it opens the pool (a no-op where there is none, or
    when it already runs: the first start fixes what it imported)."""
    import multiprocessing

    if "forkserver" not in multiprocessing.get_all_start_methods():
        return
    from multiprocessing import forkserver

    pool_context(preload)
    with _server_deaf_to_interrupts():
        forkserver.ensure_running()


#: Set in the fork server's environment when it starts with SIGINT ignored only for its
#: imports: ``preload_end`` then gives it Python's usual handler back.
SIGINT_AFTER_PRELOAD = "PREFORM_PRELOAD_RESTORES_SIGINT"


def prepare_fork_server() -> None:
    """In the fork server, after its imports (``preload_end``): give SIGINT Python's usual
    handler back if it was started deaf to it (``_server_deaf_to_interrupts``; the server
    ignores SIGINT by itself from here on, and its workers take this handler), and quiet the
    start of a worker whose pool gave up on it.

    A worker forked from the server first reads its process object from the pool. When the
    pool is closing meanwhile (the run's last case passed its time limit and its worker was
    replaced just as the run ended), that read fails (the pipe hung up, the pool's semaphores
    are gone: an ``OSError`` or ``EOFError``) and the fork server's child printed the
    traceback, often cut short by the pool's SIGTERM (issue 25, item 8). Nothing waits for
    that worker; the pool that still wanted it sees it die either way.
    """
    import sys

    if os.environ.pop(SIGINT_AFTER_PRELOAD, None) == "1":
        signal.signal(signal.SIGINT, signal.default_int_handler)
    server = os.getpid()
    python_hook = sys.excepthook

    def quiet_abandoned_start(kind: type[BaseException], exc: BaseException, tb: Any) -> None:
        if os.getpid() != server and issubclass(kind, OSError | EOFError):
            return  # a forked worker that could not take its process object from its pool
        python_hook(kind, exc, tb)

    sys.excepthook = quiet_abandoned_start


@contextlib.contextmanager
def _server_deaf_to_interrupts() -> Iterator[None]:
    """Start the fork server with SIGINT ignored until its imports are done.

    A Ctrl-C reaches every process of the terminal's process group; the server ignores it
    only once its preload is imported, so one during its start-up printed a KeyboardInterrupt
    traceback of its imports beside the run's own message (issue 25, item 8). An ignored
    signal stays ignored through exec, and Python then installs no KeyboardInterrupt handler;
    ``preload_end`` installs it again, so the workers it forks take interrupts as before.
    This process ignores SIGINT only while the server is launched (a fork and exec)."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield  # a thread cannot set handlers; a process ignoring SIGINT passes that on anyway
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ[SIGINT_AFTER_PRELOAD] = "1"
    try:
        yield
    finally:
        os.environ.pop(SIGINT_AFTER_PRELOAD, None)
        signal.signal(signal.SIGINT, previous)


def stop_fork_server() -> None:
    """Stop the fork server at once, when the command ends (nothing is forked any more; a
    no-op where none runs). Left to itself it exits only once this process has gone, and
    finalises the interpreter it preloaded (numpy, matplotlib, numba) first, 0.2-0.7 s, while
    whoever reads the command's output through a pipe (``| tee``, a CI log) waits for it: it
    holds the same stderr. A later pool in this process starts a new server."""
    from multiprocessing import forkserver

    server = forkserver._forkserver
    pid = getattr(server, "_forkserver_pid", None)
    if pid is None:
        return
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGTERM)  # no handler there: it ends without finalising
    # reaps it and forgets it, so that a later pool starts a fresh one (private, 3.8+)
    stop = getattr(server, "_stop", None)
    if callable(stop):
        stop()


class ProcessEngine(Engine):
    """A pebble process pool of ``workers`` processes, forked from a fork server that imported
    ``preload`` (see the module docstring); ``warm_up`` runs once in each worker."""

    enforces_timeout = True

    def __init__(
        self,
        workers: int | None = None,
        *,
        preload: tuple[str, ...] = (),
        warm_up: WarmUp | None = None,
    ) -> None:
        import sys

        from pebble import ProcessPool

        n = workers or max(1, os.cpu_count() or 1)
        self.workers = n
        # here, not in the pool's first start of a worker (maybe in its thread): started here it
        # is deaf to a Ctrl-C during its imports (a no-op when it runs already)
        start_fork_server(preload)
        self.capacity = 2 * n  # one running and one queued per worker keeps them busy
        self._pool = ProcessPool(
            max_workers=n,
            initializer=start_worker,
            initargs=(os.getpid(), dict(os.environ), list(sys.path), warm_up),
            context=pool_context(preload),
        )

    def submit(self, fn: Callable[..., T], *args: Any, timeout_s: float | None = None) -> Future[T]:
        future: Future[T] = self._pool.schedule(fn, args=args, timeout=timeout_s)
        return future

    def stop(self) -> None:
        self._pool.stop()
        self._pool.join(timeout=10)

    def close(self) -> None:
        self._pool.close()
        self._pool.join()


#: What a Dask worker imports before anything of preform's: the fork server a LocalCluster's
#: workers are forked from imports it too when it starts for a Dask run.
DASK_WORKER_PRELOAD = ("distributed", "distributed.nanny", "distributed.worker")


class DaskEngine(Engine):
    """A Dask cluster: a LocalCluster of worker processes, or the scheduler at ``address``.

    A case past its time limit is cancelled and the worker running it restarted (Dask cannot
    stop a running task otherwise). On a LocalCluster a case whose worker dies is failed at
    once (``allowed-failures: 0``) rather than retried on the next worker, which it would kill
    too; a remote scheduler keeps its own setting.

    A LocalCluster's workers are forked from the process pool's fork server where the platform
    has one (``pool_context``: preform and the libraries the cases load are imported once, and a
    worker that ends needs no interpreter shutdown, so the cluster closes at once), and each
    one, restarted ones too, runs ``preform.pipeline.dask_worker.PrepareWorker`` first: it
    takes this process's environment and ``sys.path``, exits when this process is gone, and
    warms up (``prepare``).
    """

    def __init__(
        self,
        workers: int | None = None,
        scheduler: str | None = None,
        *,
        preload: tuple[str, ...] = (),
        warm_up: WarmUp | None = None,
    ) -> None:
        try:
            import dask
            from distributed import Client, LocalCluster
        except ImportError:
            raise RuntimeError(
                'the dask engine needs the optional extra: pip install "preform[dask]"'
            ) from None
        self._cluster: Any = None
        self._config: Any = None
        if scheduler:
            self._client = Client(scheduler)
        else:
            settings: dict[str, Any] = {
                "distributed.scheduler.allowed-failures": 0,
                # the workers' statistical profile (their task thread's stack 100 times a
                # second) is only read on a dashboard, and this cluster has none
                "distributed.worker.profile.enabled": False,
            }
            if pool_context().get_start_method() == "forkserver":
                # started here, not by the first nanny: Dask would have it import only its own
                # modules (a no-op if the command line started it already)
                start_fork_server((*DASK_WORKER_PRELOAD, *preload))
                # read by each nanny whenever it (re)starts its worker: kept for the engine's life
                settings["distributed.worker.multiprocessing-method"] = "forkserver"
            self._config = dask.config.set(settings)
            try:
                self._cluster = LocalCluster(
                    n_workers=workers or 2,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                )
                self._client = Client(self._cluster)
            except BaseException:
                self._config.__exit__(None, None, None)
                raise
        threads = sum(self._client.nthreads().values()) or 1
        self.capacity = self.workers = max(1, threads)
        self._running: dict[Future[Any], Any] = {}
        self.prepare(preload, warm_up)

    def prepare(self, preload: tuple[str, ...], warm_up: WarmUp | None) -> None:
        """Have every worker, and every worker started later, import ``preload`` and run
        ``warm_up`` before its next task; returns when the current workers are done. Waited
        for (a failed warm-up only costs the first case its imports): cases submitted behind a
        busy worker's warm-up could queue two to a worker, and a case that kills its worker
        would take the other one with it (KilledWorker)."""
        import sys

        from preform.pipeline.dask_worker import PrepareWorker

        parent = None
        if self._cluster is not None:  # after the cluster started: the nannies' settings too
            parent = (os.getpid(), dict(os.environ), list(sys.path))
        self._client.register_plugin(PrepareWorker(preload, warm_up, parent))

    def submit(self, fn: Callable[..., T], *args: Any, timeout_s: float | None = None) -> Future[T]:
        remote = self._client.submit(fn, *args, pure=False)
        future: Future[T] = Future()
        future.set_running_or_notify_cancel()

        def deliver(done: Any) -> None:
            self._running.pop(future, None)
            if future.done():
                return
            try:
                future.set_result(done.result())
            except BaseException as exc:  # delivered through the future, like any executor
                future.set_exception(exc)

        self._running[future] = remote
        remote.add_done_callback(deliver)
        return future

    def abandon(self, future: Future[Any]) -> None:
        remote = self._running.pop(future, None)
        if remote is None:
            return
        workers = [w for w, keys in self._client.processing().items() if remote.key in keys]
        self._client.cancel([remote], force=True)
        if workers:
            self._client.restart_workers(workers, raise_for_error=False)

    def stop(self) -> None:
        self._client.cancel(list(self._running.values()), force=True)
        self.close()

    def close(self) -> None:
        try:
            if self._cluster is None:  # a shared cluster: its later workers need not warm up
                from preform.pipeline.dask_worker import PrepareWorker

                with contextlib.suppress(Exception):
                    self._client.unregister_worker_plugin(PrepareWorker.name)
            self._client.close()
            if self._cluster is not None:
                self._cluster.close()
        finally:
            if self._config is not None:
                self._config.__exit__(None, None, None)
                self._config = None


#: LocalClusters opened ahead of their run (``start_local_dask_engine``), by worker count.
_EARLY_DASK: dict[int | None, Future[DaskEngine]] = {}


def start_local_dask_engine(
    workers: int | None, preload: tuple[str, ...], warm_up: WarmUp | None = None
) -> None:
    """Open the LocalCluster of a coming Dask run now, in a thread, so that its start (the fork
    server's imports, the scheduler, the workers, ``warm_up``) overlaps what this process does
    before the run opens its engine; ``open_engine`` then takes it and prepares its workers for
    the run. One at a time; one never taken (the command ended before its run, or had nothing
    to compute) is closed when this process exits."""
    if _EARLY_DASK:
        return
    import atexit

    future: Future[DaskEngine] = Future()

    def open_cluster() -> None:
        try:
            future.set_result(DaskEngine(workers, preload=preload, warm_up=warm_up))
        except BaseException as exc:  # given to whoever takes it; it opens its own instead
            future.set_exception(exc)

    _EARLY_DASK[workers] = future
    threading.Thread(target=open_cluster, name="preform-dask-open", daemon=True).start()
    atexit.register(_close_early_dask)


def _take_early_dask(workers: int | None) -> DaskEngine | None:
    """The LocalCluster opened ahead for ``workers`` workers, once it is up; None if there is
    none or it failed to open."""
    future = _EARLY_DASK.get(workers)
    if future is None:
        return None
    try:
        engine: DaskEngine | None = future.result()
    except Exception:
        engine = None
    # only now: interrupted while it opens, it stays here and is closed at exit
    del _EARLY_DASK[workers]
    return engine


def _close_early_dask() -> None:
    # waits for it to be up (a run with nothing to compute pays its start): Dask's own exit
    # handler would wait as long for a cluster still starting, then close it
    for workers in list(_EARLY_DASK):
        engine = _take_early_dask(workers)
        if engine is not None:
            engine.close()


def open_engine(
    engine: str,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    preload: tuple[str, ...] = (),
    warm_up: WarmUp | None = None,
) -> Engine:
    """The engine named ``engine``; the caller closes (or stops) it. ``preload`` (modules) and
    ``warm_up`` (run once per worker) make a worker's first case as fast as its next ones."""
    if engine == "serial":
        return SerialEngine()
    if engine == "process":
        return ProcessEngine(workers, preload=preload, warm_up=warm_up)
    if engine == "dask":
        early = None if scheduler else _take_early_dask(workers)
        if early is None:
            return DaskEngine(workers, scheduler, preload=preload, warm_up=warm_up)
        early.prepare(preload, warm_up)
        return early
    raise ValueError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
