"""The process pool pays worker start-up once and still behaves like fresh workers.

Workers are forked from a fork server that imported preform before the first case (issue 15);
a fork server started by an earlier run holds that moment's environment and ``sys.path``, so
each worker takes the parent's current ones. The warm-up runs once per worker, before its
first case.
"""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from preform.pipeline import engines
from preform.pipeline.engines import ProcessEngine, open_engine
from preform.pipeline.preload import WORKER_PRELOAD, worker_preload

# Test modules are imported by path (--import-mode=importlib): what workers run lives in a
# module written to a folder that only this test puts on sys.path.
PROBE = """
import gc, os, sys

WARMED = []


def note_warm_up(tag):
    WARMED.append(os.getpid())
    os.environ["PREFORM_TEST_WARMED"] = tag


def worker_view(_):
    return {
        "pid": os.getpid(),
        "value": os.environ.get("PREFORM_TEST_ENGINE"),
        "path": sys.path[:1],
        "full_path": list(sys.path),
        "warmed": list(WARMED),
        "tag": os.environ.get("PREFORM_TEST_WARMED"),
        "runner_loaded": "preform.pipeline.runner" in sys.modules,
        "gc_enabled": gc.isenabled(),
        "gc_frozen": gc.get_freeze_count(),
    }
"""


@pytest.fixture
def probe(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Any:
    folder = tmp_path / "probe_site"
    folder.mkdir()
    (folder / "preform_engine_probe.py").write_text(textwrap.dedent(PROBE))
    monkeypatch.syspath_prepend(str(folder))
    import importlib

    return importlib.import_module("preform_engine_probe"), str(folder)


def run_on_pool(module: Any, n: int) -> list[dict[str, Any]]:
    engine = ProcessEngine(
        2,
        preload=("preform.pipeline.runner",),
        warm_up=("preform_engine_probe:note_warm_up", ("w",)),
    )
    try:
        futures = [engine.submit(module.worker_view, i) for i in range(n)]
        return [f.result(timeout=120) for f in futures]
    finally:
        engine.close()


def test_workers_see_the_parents_current_environment_and_path(probe, monkeypatch):
    module, folder = probe
    first = run_on_pool(module, 2)
    monkeypatch.setenv("PREFORM_TEST_ENGINE", "second")
    second = run_on_pool(module, 4)
    assert all(v["value"] is None for v in first)
    assert all(v["value"] == "second" for v in second)
    assert all(v["path"] == [folder] for v in first + second)


def test_the_warm_up_runs_once_per_worker_before_its_first_case(probe):
    module, _ = probe
    views = run_on_pool(module, 6)
    for view in views:
        # the warm-up ran in this very process, once, and set what the case then sees
        assert view["warmed"] == [view["pid"]]
        assert view["tag"] == "w"
        assert view["runner_loaded"]
    assert 1 <= len({v["pid"] for v in views}) <= 2


@pytest.mark.skipif(
    "forkserver" not in multiprocessing.get_all_start_methods(),
    reason="no fork server on this platform",
)
def test_workers_compute_with_the_collector_on_and_the_servers_imports_frozen(probe):
    """The fork server pauses the garbage collector for its imports and freezes what they made
    before it forks (preform.collector): a worker computes with the collector on (its cases'
    cyclic garbage is freed), and its collections skip the objects it shares with the server."""
    module, _ = probe
    for view in run_on_pool(module, 4):
        assert view["gc_enabled"]
        # the server's imports (preform's runner, numpy, pydantic...) are frozen: far more
        # objects than the few a worker's own start makes before the preload ends
        assert view["gc_frozen"] > 10_000


@pytest.mark.skipif(
    "forkserver" not in multiprocessing.get_all_start_methods(),
    reason="no fork server on this platform",
)
def test_the_fork_server_pauses_the_collector_first_and_resumes_it_last():
    """The order the server imports in: a module between the two markers is imported with the
    collector off, in any order the caller gives them."""
    from multiprocessing import forkserver

    server = forkserver._forkserver
    before = list(server._preload_modules)  # what set_forkserver_preload was given
    try:
        engines.pool_context(("b.module", engines.PRELOAD_END, "a.module"))
        preload = list(server._preload_modules)
    finally:  # a server this process starts later imports what the suite asked for
        server._preload_modules = before
    assert preload == [engines.PRELOAD_BEGIN, "a.module", "b.module", engines.PRELOAD_END]


def test_the_runner_asks_for_its_own_modules_and_the_lazy_libraries():
    preload = worker_preload()
    assert "preform.pipeline.runner" in WORKER_PRELOAD
    own = preload[: -len(WORKER_PRELOAD)]
    assert preload[len(own) :] == WORKER_PRELOAD
    assert all(m == "preform" or m.startswith("preform.") for m in own)


def test_the_fork_server_starts_before_the_command_imports_numpy_or_pydantic():
    """`preform pipeline run` starts the server first, so its imports overlap the command's
    own (scene and summary models, library): the module doing it imports neither."""
    code = (
        "import sys; import preform.cli, preform.pipeline.preload; "
        "print(sorted({'numpy', 'pydantic'} & set(sys.modules)))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


@pytest.mark.skipif(
    "forkserver" not in multiprocessing.get_all_start_methods(),
    reason="no fork server on this platform",
)
def test_the_pool_forks_from_a_fork_server():
    assert engines.pool_context().get_start_method() == "forkserver"


@pytest.mark.skipif(
    "forkserver" not in multiprocessing.get_all_start_methods(),
    reason="no fork server on this platform",
)
def test_the_fork_server_is_gone_when_the_command_exits():
    """The command's exit stops its fork server at once (a server left to itself finalises
    numpy & co. after the command has gone, and a pipe reading the command's output waits for
    it); a pool opened after a stop forks from a new server."""
    script = textwrap.dedent(
        """
        import multiprocessing, os, sys
        from multiprocessing import forkserver
        from preform.pipeline.engines import stop_fork_server
        from preform.pipeline.preload import start_workers_early

        start_workers_early()
        context = multiprocessing.get_context("forkserver")
        child = context.Process(target=os.getpid)
        child.start(); child.join()
        first = forkserver._forkserver._forkserver_pid
        stop_fork_server()
        try:
            os.kill(first, 0)  # signal 0: only asks whether the process exists
        except ProcessLookupError:
            pass  # gone, as it must be
        else:
            sys.exit("the stopped server still runs")
        child = context.Process(target=os.getpid)
        child.start(); child.join()
        assert child.exitcode == 0, child.exitcode
        second = forkserver._forkserver._forkserver_pid
        assert second not in (None, first), (first, second)
        print(second, flush=True)  # left running: the exit must stop it
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    server = int(done.stdout.split()[-1])
    # no wait: stopped (and reaped) before the command's own exit
    with pytest.raises(ProcessLookupError):
        os.kill(server, 0)


def test_a_warm_up_that_fails_fails_the_case_not_the_caller(probe):
    module, _ = probe
    engine = open_engine("process", workers=1, warm_up=("builtins:int", ("not a number",)))
    try:
        future = engine.submit(module.worker_view, 0)
        with pytest.raises(Exception):  # noqa: B017 - pebble's word for a broken initializer
            future.result(timeout=120)
    finally:
        engine.stop()
    assert sys.modules.get("preform_engine_probe") is module


def test_every_preform_module_the_workers_preload_exists():
    """The preload skips a name that does not import (an optional library not installed): a
    preform module renamed or moved would silently drop out of it, and every worker would pay
    its import in its first case again."""
    import importlib

    own = [m for m in WORKER_PRELOAD if m.startswith("preform.")]
    assert own, "the workers preload none of preform's modules"
    for module in own:
        importlib.import_module(module)


# -- Dask: a LocalCluster's workers are forked from the same fork server ------------------------

DASK_PROBE = """
import os


def die():
    os._exit(3)
"""


def dask_engine(workers: int = 1) -> Any:
    pytest.importorskip("distributed")
    return open_engine(
        "dask",
        workers=workers,
        preload=("preform.pipeline.runner",),
        warm_up=("preform_engine_probe:note_warm_up", ("dask",)),
    )


def test_dask_workers_take_the_parents_state_set_after_the_fork_server_started(probe, monkeypatch):
    module, folder = probe
    # the fork server holds the environment of its start (an earlier run, the command line's
    # early start): the variable and the probe's folder come after it
    engines.start_fork_server(("preform.pipeline.runner",))
    monkeypatch.setenv("PREFORM_TEST_ENGINE", "set later")
    engine = dask_engine(workers=2)
    try:
        views = [engine.submit(module.worker_view, i).result(timeout=120) for i in range(4)]
    finally:
        engine.close()
    for view in views:
        assert view["value"] == "set later"
        # the parent's path, in its order (Dask puts its scratch folder first, for upload_file)
        parent = [p for p in sys.path if p]
        assert [p for p in view["full_path"] if p in parent] == parent
        assert folder in view["full_path"]
        # prepared once, in this very worker process, before its first task
        assert view["warmed"] == [view["pid"]] and view["tag"] == "dask"
        assert view["runner_loaded"]
        # forked from the fork server after its imports: collector on, their objects frozen
        assert view["gc_enabled"] and view["gc_frozen"] > 10_000
    assert os.getpid() not in {v["pid"] for v in views}


def test_a_restarted_dask_worker_is_prepared_like_the_first(probe, monkeypatch, tmp_path):
    module, folder = probe
    (Path(folder) / "preform_engine_probe_die.py").write_text(textwrap.dedent(DASK_PROBE))
    monkeypatch.setenv("PREFORM_TEST_ENGINE", "kept")
    import importlib

    die = importlib.import_module("preform_engine_probe_die").die
    engine = dask_engine(workers=1)
    try:
        first = engine.submit(module.worker_view, 0).result(timeout=120)
        with pytest.raises(Exception, match=r"died"):
            engine.submit(die).result(timeout=120)
        engine._client.wait_for_workers(1, timeout=120)
        again = engine.submit(module.worker_view, 1).result(timeout=120)
    finally:
        engine.close()
    assert again["pid"] != first["pid"]  # a new worker process, started by its nanny
    assert again["warmed"] == [again["pid"]] and again["tag"] == "dask"
    assert again["value"] == "kept" and folder in again["full_path"]


ORPHAN_CHECK = """
import os, sys, time
from preform.pipeline import engines

engines.start_local_dask_engine(2, ("preform.pipeline.runner",))
engine = engines._EARLY_DASK[2].result(timeout=120)  # up, but never taken by a run
print(" ".join(str(p) for p in engine._client.run(os.getpid).values()), flush=True)
"""


def _process_alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_a_cluster_opened_ahead_and_never_used_leaves_no_worker_behind(tmp_path):
    pytest.importorskip("distributed")
    import subprocess
    import time

    proc = subprocess.run(
        [sys.executable, "-c", ORPHAN_CHECK], capture_output=True, text=True, timeout=180
    )
    assert proc.returncode == 0, proc.stderr
    pids = [int(p) for p in proc.stdout.split()]
    assert len(pids) == 2
    deadline = time.monotonic() + 10
    while any(_process_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_process_alive(p) for p in pids), pids


def test_open_engine_takes_the_cluster_opened_ahead_once(probe):
    pytest.importorskip("distributed")
    module, _ = probe
    engines.start_local_dask_engine(1, ("preform.pipeline.runner",))
    ahead = engines._EARLY_DASK[1]
    engine = dask_engine(workers=1)
    try:
        assert engine is ahead.result()
        view = engine.submit(module.worker_view, 0).result(timeout=120)
        # prepared again for this run: its warm-up ran in the worker before the task
        assert view["warmed"] == [view["pid"]] and view["tag"] == "dask"
        assert 1 not in engines._EARLY_DASK  # taken: the next run opens its own
    finally:
        engine.close()


def test_a_remote_cluster_is_warmed_keeps_its_environment_and_is_left_running(probe, monkeypatch):
    """``--scheduler``: the workers are someone else's (here threads of a cluster this test
    runs): they warm up, keep their own environment, and stay up after the run; the warm-up
    is no longer asked of workers that join later."""
    pytest.importorskip("distributed")
    from distributed import Client, LocalCluster

    from preform.pipeline.dask_worker import PrepareWorker

    module, _ = probe
    monkeypatch.setenv("PREFORM_TEST_WARMED", "")  # the warm-up sets it in this process
    with LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster:
        engine = open_engine(
            "dask",
            scheduler=cluster.scheduler_address,
            warm_up=("preform_engine_probe:note_warm_up", ("remote",)),
        )
        try:
            view = engine.submit(module.worker_view, 0).result(timeout=120)
        finally:
            engine.close()
        assert view["tag"] == "remote" and view["pid"] in view["warmed"]
        assert PrepareWorker.name not in cluster.scheduler.worker_plugins
        with Client(cluster) as client:  # still serving
            assert client.submit(sum, [1, 2]).result(timeout=60) == 3
