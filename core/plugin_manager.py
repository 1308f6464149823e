"""Plugin manager: entry-point discovery, per-plugin failure records, registration.

Loading is per plugin. A plugin that fails to import, implements a misspelled hook, or registers
something invalid is recorded (distribution, version, error) and removed; every other plugin
keeps working. ``PREFORM_LOAD_PLUGINS`` (comma list; set but empty = none) and
``PREFORM_DISABLE_PLUGINS`` select entry points by name.
"""

from __future__ import annotations

import importlib
import importlib.metadata as metadata
import os
import traceback
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import pluggy

from preform import hookspecs
from preform.registry import REGISTRARS, Registry

ENTRY_POINT_GROUP = "preform"
hookimpl = pluggy.HookimplMarker("preform")


@dataclass
class PluginRecord:
    """What ``preform plugins list`` shows for one plugin."""

    name: str
    distribution: str | None
    version: str | None
    #: Where it came from: "entry point" or "registered" (by code, e.g. a test).
    origin: str
    #: Importable module path, so worker processes can load the same plugin.
    module: str | None = None
    registered: dict[str, list[str]] = field(default_factory=dict)
    error: str | None = None

    def as_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "distribution": self.distribution,
            "version": self.version,
            "origin": self.origin,
            "module": self.module,
            "registered": self.registered,
            "error": self.error,
        }


def _short_error(exc: BaseException) -> str:
    lines = traceback.format_exception_only(type(exc), exc)
    return "".join(lines).strip()


def selected_by_environment(name: str) -> bool:
    """Whether the environment variables let the entry point ``name`` load."""
    load = os.environ.get("PREFORM_LOAD_PLUGINS")
    if load is not None:
        wanted = {n.strip() for n in load.split(",") if n.strip()}
        if name not in wanted:
            return False
    disabled = {n.strip() for n in os.environ.get("PREFORM_DISABLE_PLUGINS", "").split(",")}
    return name not in disabled


class PluginHost:
    """The plugin manager, the registry it fills, and a record per plugin."""

    def __init__(self) -> None:
        self.pm = pluggy.PluginManager("preform")
        self.pm.add_hookspecs(hookspecs)
        self.registry = Registry()
        self.registry.hook = self.pm.hook
        self.records: dict[str, PluginRecord] = {}

    # -- loading ------------------------------------------------------------------------------
    def discover(self, group: str = ENTRY_POINT_GROUP) -> None:
        """Load every entry point of ``group`` that the environment selects, one at a time."""
        for ep in sorted(metadata.entry_points(group=group), key=lambda e: e.name):
            if not selected_by_environment(ep.name) or ep.name in self.records:
                continue
            dist = ep.dist
            record = PluginRecord(
                name=ep.name,
                distribution=dist.metadata["Name"] if dist is not None else None,
                version=dist.version if dist is not None else None,
                origin="entry point",
                module=ep.value.split(":")[0],
            )
            try:
                plugin = ep.load()
            except Exception as exc:  # a broken plugin must never stop the others
                record.error = f"failed to import: {_short_error(exc)}"
                self.records[ep.name] = record
                continue
            self._register(plugin, record)

    def add(
        self, plugin: Any, name: str, *, version: str | None = None, module: str | None = None
    ) -> PluginRecord:
        """Register a plugin object directly (tests, embedding); returns its record."""
        if module is None and isinstance(plugin, type(os)):
            module = plugin.__name__
        record = PluginRecord(
            name=name, distribution=None, version=version, origin="registered", module=module
        )
        self._register(plugin, record)
        return record

    def add_modules(self, modules: Iterable[tuple[str, str]]) -> None:
        """Register plugins by importable module path: ``[(name, "pkg.module"), ...]``."""
        for name, module in modules:
            if name in self.records:
                continue
            record = PluginRecord(name, None, None, "registered", module)
            try:
                plugin = importlib.import_module(module)
            except Exception as exc:
                record.error = f"failed to import: {_short_error(exc)}"
                self.records[name] = record
                continue
            self._register(plugin, record)

    def _register(self, plugin: Any, record: PluginRecord) -> None:
        if record.name in self.records:
            raise ValueError(f"a plugin named {record.name!r} is already loaded")
        self.records[record.name] = record
        try:
            self.pm.register(plugin, name=record.name)
        except Exception as exc:  # pluggy validates hookimpl signatures here
            record.error = f"invalid plugin: {_short_error(exc)}"
            return
        # pluggy accepts implementations of hooks nobody declared (for late specs); here such an
        # implementation is a misspelling, and it fails this plugin only.
        misspelled = [
            hook_name
            for hook_name, caller in vars(self.pm.hook).items()
            if getattr(caller, "spec", True) is None
            and any(i.plugin_name == record.name for i in caller.get_hookimpls())
        ]
        if misspelled:
            self.pm.unregister(name=record.name)
            record.error = (
                "unknown hook implementation(s): "
                + ", ".join(sorted(misspelled))
                + " (misspelled? see preform.hookspecs)"
            )
            return
        self._run_registrations(record)

    def _run_registrations(self, record: PluginRecord) -> None:
        version = record.version or "0"
        try:
            for hook_name, registrar_type in REGISTRARS.items():
                for impl in getattr(self.pm.hook, hook_name).get_hookimpls():
                    if impl.plugin_name == record.name:
                        impl.function(register=registrar_type(self.registry, record.name, version))
        except Exception as exc:
            self.registry.remove_plugin(record.name)
            self.pm.unregister(name=record.name)
            record.error = f"registration failed: {_short_error(exc)}"
            return
        record.registered = self.registry.by_plugin(record.name)

    # -- reading ------------------------------------------------------------------------------
    def plugin_modules(self) -> list[tuple[str, str]]:
        """(name, module) of every working plugin, for re-loading in worker processes."""
        return [(r.name, r.module) for r in self.records.values() if r.error is None and r.module]

    def register_commands(self, cli: Any) -> None:
        """Let each plugin add click commands; a failing plugin is recorded, not fatal."""
        for impl in self.pm.hook.preform_register_commands.get_hookimpls():
            try:
                impl.function(cli=cli)
            except Exception as exc:
                record = self.records.get(impl.plugin_name)
                if record is not None:
                    record.error = f"register_commands failed: {_short_error(exc)}"


_default_host: PluginHost | None = None


def default_host() -> PluginHost:
    """The process-wide host with every entry-point plugin loaded (created on first use)."""
    global _default_host
    if _default_host is None:
        host = PluginHost()
        host.discover()
        _default_host = host
    return _default_host


def reset_default_host(host: PluginHost | None = None) -> None:
    """Replace the process-wide host (tests)."""
    global _default_host
    _default_host = host
