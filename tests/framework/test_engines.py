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
import os, sys

WARMED = []


def note_warm_up(tag):
    WARMED.append(os.getpid())
    os.environ["PREFORM_TEST_WARMED"] = tag


def worker_view(_):
    return {
        "pid": os.getpid(),
        "value": os.environ.get("PREFORM_TEST_ENGINE"),
        "path": sys.path[:1],
        "warmed": list(WARMED),
        "tag": os.environ.get("PREFORM_TEST_WARMED"),
        "runner_loaded": "preform.pipeline.runner" in sys.modules,
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
            os.kill(first, 0)
            sys.exit("the stopped server still runs")
        except ProcessLookupError:
            pass
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
