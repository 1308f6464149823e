"""Fixtures for the hostile-run tests: a plugin whose cases misbehave on purpose, installed as a
third-party distribution (entry point in a temporary site directory, as pip would), so worker
processes find it exactly as they would a user's plugin."""

from __future__ import annotations

import contextlib
import importlib
import os
import signal
import subprocess
import sys
import textwrap
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

RUNTOY = '''
"""Fabrics whose single step does what their ``fate`` says: the faults of a real run."""
import math
import os
import signal
import time
from pathlib import Path
from typing import Literal

from pydantic import Field

from preform import CaseFailure, FabricBase, Step, hookimpl


class RunToy(FabricBase):
    architecture: Literal["runtoy"]
    work_s: float = Field(default=0.0, ge=0, description="Time the step takes [s].")
    fate: Literal[
        "ok", "raise", "exit", "segv", "kill", "hang", "nan", "partial", "sysexit", "failure",
        "spin"
    ] = "ok"


def run_work(ctx):
    pid_log = os.environ.get("RUNTOY_PIDS")
    if pid_log:
        with open(pid_log, "a") as f:
            f.write(f"{os.getpid()}\\n")
    order_log = os.environ.get("RUNTOY_ORDER")
    if order_log:
        with open(order_log, "a") as f:
            f.write(f"{ctx.fabric.name}\\n")
    fate = ctx.fabric.fate
    time.sleep(ctx.fabric.work_s)
    if fate == "raise":
        raise ValueError("this fabric's step always raises")
    if fate == "exit":
        os._exit(7)
    if fate == "segv":
        os.kill(os.getpid(), signal.SIGSEGV)
    if fate == "kill":
        os.kill(os.getpid(), signal.SIGKILL)
    if fate == "hang":
        while True:
            time.sleep(0.05)
    if fate == "spin":
        while True:
            pass
    if fate == "sysexit":
        raise SystemExit(4)
    if fate == "failure":
        raise CaseFailure("the drape placed no cell")
    value = math.nan if fate == "nan" else 2.0 * ctx.fabric.work_s + 1.0
    if fate == "partial":
        ctx.partial("the net stopped at a crease", covered_fraction=0.25)
    ctx.summary["work_value"] = value
    ctx.summary["fabric_fate"] = fate
    return {"work": value}


def write_work_txt(ctx):
    (ctx.case_dir / "work.txt").write_text(repr(ctx.products["work"]))
    return {"work_txt": "work.txt"}


@hookimpl
def preform_register_architectures(register):
    register.add(RunToy)


@hookimpl
def preform_register_steps(register):
    register.add(Step("work", ("work",), (), os.environ.get("RUNTOY_STEP_VERSION", "1"), run_work))


@hookimpl
def preform_register_exporters(register):
    register.add(Step("work_txt", ("work_txt",), ("work",), "1", write_work_txt,
                      writes_files=True))
'''


def install_distribution(site: Path, dist: str, module: str, source: str, entry: str) -> None:
    """A module plus a ``.dist-info`` with one ``preform`` entry point, as pip would leave."""
    (site / f"{module}.py").write_text(textwrap.dedent(source))
    info = site / f"{dist.replace('-', '_')}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[preform]\n{entry} = {module}\n")


@dataclass
class RunEnv:
    """Where a hostile run happens: library and scene files, its results directory, the
    environment that lets workers find the plugin, and a way to run the real CLI."""

    root: Path
    env: dict[str, str]

    @property
    def out(self) -> Path:
        return self.root / "out"

    def library(self, *entries: str, name: str = "lib.yaml") -> Path:
        path = self.root / name
        path.write_text("".join(entries))
        return path

    def scene(self, name: str = "work-scene", outputs: str = "[work_txt]", extra: str = "") -> Path:
        path = self.root / f"scene-{abs(hash(name)) % 10**8}.yaml"
        path.write_text(f"name: {name!r}\noutputs: {outputs}\n{extra}")
        return path

    def command(self, library: Path, scene: Path, *args: str) -> list[str]:
        return [
            sys.executable,
            "-m",
            "preform",
            "pipeline",
            "run",
            str(library),
            "--no-bundled",  # LIBRARY adds to the bundled library
            "--scene",
            str(scene),
            "--out",
            str(self.out),
            *args,
        ]

    def run(
        self, library: Path, scene: Path, *args: str, timeout: float = 120
    ) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            self.command(library, scene, *args),
            env=self.env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )

    def start(self, library: Path, scene: Path, *args: str) -> subprocess.Popen[str]:
        with interruptible_children():
            return subprocess.Popen(
                self.command(library, scene, *args),
                env=self.env,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )


@contextlib.contextmanager
def interruptible_children() -> Iterator[None]:
    """Start children with SIGINT at its default, as from a terminal, however pytest was
    started: a shell starts a background job (``pytest &``, a CI runner) with SIGINT ignored,
    the ignore is inherited through exec, and Python then installs no KeyboardInterrupt
    handler, so an interrupt test would see preform (rightly) ignore the signal. A handled
    signal is reset to its default in the child on exec, so handling it here for the moment
    of the fork is enough."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.fixture
def runenv(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[RunEnv]:
    site = tmp_path / "site"
    site.mkdir()
    install_distribution(site, "preform-runtoy", "runtoy", RUNTOY, "runtoy")
    monkeypatch.syspath_prepend(str(site))
    importlib.invalidate_caches()
    sys.modules.pop("runtoy", None)
    env = {
        **os.environ,
        "PYTHONPATH": str(site),
        "PREFORM_LOAD_PLUGINS": "core,runtoy",
        "RUNTOY_PIDS": str(tmp_path / "pids.log"),
    }
    env.pop("PREFORM_LIBRARY", None)
    work = tmp_path / "work"
    work.mkdir()
    yield RunEnv(work, env)
    sys.modules.pop("runtoy", None)
