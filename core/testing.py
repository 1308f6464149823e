"""pytest plugin for preform and for third-party plugin repositories (entry point ``pytest11``).

Fixture ``preform_plugins``: a plugin host with entry-point discovery blocked, installed as the
process-wide host for the duration of one test. Register exactly the plugins the test needs::

    def test_my_law(preform_plugins):
        preform_plugins.register(my_plugin_module)          # your plugin, for this test only
        preform_plugins.load_builtins("core", "woven")       # and any built-ins you need
        lib = preform_plugins.library(["my-fabrics.yaml"], bundled=False)

The sandbox applies the same rules as a real installation: a plugin that fails (import,
registration, a name conflict) is recorded, not raised (``preform_plugins.register(...)``
returns its record; check ``record.error``), and built-in names win in whatever order plugins
are added, so a plugin registering a built-in's name is unloaded when the built-in loads.
"""

from __future__ import annotations

import importlib.metadata as metadata
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest

from preform.plugin_manager import ENTRY_POINT_GROUP, PluginHost, PluginRecord, reset_default_host


class PluginSandbox:
    """A PluginHost that only knows the plugins a test registers."""

    def __init__(self) -> None:
        self.host = PluginHost()

    @property
    def registry(self) -> Any:
        return self.host.registry

    def register(
        self, plugin: Any, name: str | None = None, version: str = "0.0.test"
    ) -> PluginRecord:
        """Register a plugin (module or object with hookimpls) for this test."""
        label: str = name or getattr(plugin, "__name__", None) or type(plugin).__name__
        return self.host.add(plugin, label, version=version)

    def load_builtins(self, *names: str) -> None:
        """Load preform's own plugins by entry-point name (all of them when none is given)."""
        eps = {
            ep.name: ep
            for ep in metadata.entry_points(group=ENTRY_POINT_GROUP)
            if ep.value.startswith("preform.")
        }
        for name in names or tuple(sorted(eps)):
            self.host.add_modules([(name, eps[name].value.split(":")[0])])

    def library(self, paths: Sequence[str | Path] = (), *, bundled: bool = False) -> Any:
        from preform.library import load_library

        return load_library(paths, bundled=bundled, env=False, registry=self.registry)


@pytest.fixture
def preform_plugins(monkeypatch: pytest.MonkeyPatch) -> Iterator[PluginSandbox]:
    """A plugin host with discovery blocked, used by preform for the length of one test."""
    monkeypatch.setenv("PREFORM_LOAD_PLUGINS", "")
    monkeypatch.delenv("PREFORM_LIBRARY", raising=False)
    sandbox = PluginSandbox()
    reset_default_host(sandbox.host)
    try:
        yield sandbox
    finally:
        reset_default_host(None)
