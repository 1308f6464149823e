"""Fixtures for the hostile-plugin tests: install third-party plugin distributions (entry points
in a temporary site directory, as pip would) and run the real CLI against them.

Imported by ``test_plugins_hostile.py`` by path (the tests run with ``--import-mode=importlib``
and ``tests/hostile/conftest.py`` belongs to other tests).
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from preform.plugin_manager import PluginHost, reset_default_host


def _framework_conftest() -> Any:
    """``tests/framework/conftest.py`` (its distribution installer), loaded under its own name."""
    name = "preform_tests_framework_conftest"
    if name not in sys.modules:
        path = Path(__file__).parents[1] / "framework" / "conftest.py"
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


install_distribution = _framework_conftest().install_distribution

#: A well-behaved third-party plugin's lint, to show it keeps working beside a broken one.
GOOD_LINT = """
from preform import hookimpl

@hookimpl
def preform_check_material(material):
    return [(("name",), "good plugin saw " + material.name)]
"""


class Site:
    """A site directory on ``sys.path`` (and workers' PYTHONPATH) receiving plugin
    distributions; each plugin is module ``hp_<entry point>`` of distribution
    ``preform-hostile-<entry point>`` unless told otherwise."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.modules: list[str] = []

    def install(
        self,
        entry_point: str,
        source: str,
        *,
        module: str | None = None,
        dist: str | None = None,
        version: str = "6.6.6",
    ) -> str:
        module = module or f"hp_{entry_point.replace('-', '_')}"
        install_distribution(
            self.path,
            dist or f"preform-hostile-{entry_point}",
            version,
            {module: source},
            {entry_point: module},
        )
        self.modules.append(module)
        sys.modules.pop(module, None)
        importlib.invalidate_caches()
        return module


@pytest.fixture
def site(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Site]:
    """An empty plugin site; every entry point (built-in and installed here) is discovered."""
    path = tmp_path / "site"
    path.mkdir()
    monkeypatch.syspath_prepend(str(path))
    inherited = os.environ.get("PYTHONPATH")
    monkeypatch.setenv(
        "PYTHONPATH", os.pathsep.join([str(path), *([inherited] if inherited else [])])
    )
    for var in ("PREFORM_LOAD_PLUGINS", "PREFORM_DISABLE_PLUGINS", "PREFORM_LIBRARY"):
        monkeypatch.delenv(var, raising=False)
    reset_default_host(None)
    s = Site(path)
    try:
        yield s
    finally:
        reset_default_host(None)
        for module in s.modules:
            sys.modules.pop(module, None)
        importlib.invalidate_caches()


def discover() -> PluginHost:
    """A fresh host that discovers every entry point, as a CLI process or a worker does."""
    host = PluginHost()
    host.discover()
    return host


@dataclass
class Run:
    exit_code: int
    stdout: str
    stderr: str
    exception: BaseException | None

    def json(self) -> Any:
        return json.loads(self.stdout)


def invoke(args: list[str]) -> Run:
    """``preform ARGS`` in-process, as ``main`` runs it: plugins are discovered and their
    commands added inside the runner's isolation, so their output is captured too."""
    from preform.cli import build_cli

    reset_default_host(None)
    runner = CliRunner()
    with runner.isolation() as (out, err, _):
        group = build_cli()
        sys.stdout.flush()
        sys.stderr.flush()
        build_out = out.getvalue().decode()
        build_err = err.getvalue().decode()
    result = runner.invoke(group, args)
    return Run(
        result.exit_code, build_out + result.stdout, build_err + result.stderr, result.exception
    )


def run_preform(
    args: list[str], cwd: Path, timeout: float = 120
) -> subprocess.CompletedProcess[str]:
    """``preform ARGS`` in a real process (stdout proven clean at the file-descriptor level)."""
    env = dict(os.environ)
    return subprocess.run(
        [sys.executable, "-c", "from preform.cli import main; main()", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def assert_contained(run: Run) -> None:
    """No traceback anywhere, and no exception escaped but click's own exit."""
    assert "Traceback" not in run.stdout + run.stderr, run.stdout + run.stderr
    assert run.exception is None or isinstance(run.exception, SystemExit), repr(run.exception)


def dedent(source: str) -> str:
    return textwrap.dedent(source)
