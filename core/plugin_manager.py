"""Plugin manager: entry-point discovery, per-plugin failure records, registration.

Loading is per plugin. A plugin that fails to import, implements a misspelled hook, or registers
something invalid is recorded (distribution, version, error) and removed; every other plugin
keeps working. ``PREFORM_LOAD_PLUGINS`` (comma list; set but empty = none) and
``PREFORM_DISABLE_PLUGINS`` select entry points by name.

Containment: every call into plugin code (its import, each registration hook,
``preform_register_commands``, each ``preform_check_material``) goes through
:func:`call_plugin`. Any exception there, ``SystemExit`` included, is recorded against the plugin
and never escapes; only ``KeyboardInterrupt`` propagates, so Ctrl-C during a slow plugin import
still stops the program. Whatever the plugin writes to stdout (``print`` or ``os.write(1, ...)``)
is kept off stdout, where it would corrupt ``--json`` and ``schema`` output, and forwarded to
stderr, each line prefixed with ``plugin NAME:``.

Precedence: preform's own plugins (entry points whose module is under ``preform.``, shipped by
the ``preform`` distribution) are loaded before any third-party plugin, and their names always
win: a third-party plugin that registers a name a built-in holds fails as a whole, with an error
naming the thing, the name and the built-in owner; one registered before a built-in (by code) is
displaced by it. Between third-party plugins, the one loaded first keeps the name.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.metadata as metadata
import io
import os
import sys
import tempfile
import threading
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pluggy

from preform import hookspecs
from preform.registry import REGISTRARS, NameConflict, RegistrationError, Registry

ENTRY_POINT_GROUP = "preform"
hookimpl = pluggy.HookimplMarker("preform")

#: Longest plugin output forwarded to stderr per call, and longest recorded error [characters].
MAX_FORWARDED_OUTPUT = 64 * 1024
MAX_ERROR_LENGTH = 2000
#: Runtime problems kept per plugin record (a hook failing on every fabric would repeat).
MAX_PROBLEMS = 20


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
    #: Why the plugin is not loaded (import, registration or conflict); None when it works.
    error: str | None = None
    #: Shipped with preform: its names take precedence over every other plugin's.
    builtin: bool = False
    #: Failures of hooks called after loading (e.g. ``preform_check_material`` raising); the
    #: plugin stays loaded, each failure was reported where it happened.
    problems: list[str] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "distribution": self.distribution,
            "version": self.version,
            "origin": self.origin,
            "module": self.module,
            "builtin": self.builtin,
            "registered": self.registered,
            "error": self.error,
            "problems": self.problems,
        }

    def add_problem(self, message: str) -> None:
        if message not in self.problems and len(self.problems) < MAX_PROBLEMS:
            self.problems.append(message)


def _short_error(exc: BaseException) -> str:
    if type(exc) in (RegistrationError, NameConflict):
        # preform's own refusal (not a plugin's subclass, whose __str__ could be anything):
        # the message says it all, the class path would be noise
        text = str(exc)
    else:
        import traceback  # for a failure only: off the path of a good start

        # format_exception_only survives an exception whose __str__ itself raises
        text = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    if len(text) > MAX_ERROR_LENGTH:
        text = text[:MAX_ERROR_LENGTH] + f"... [{len(text) - MAX_ERROR_LENGTH} more characters]"
    return text


def selected_by_environment(name: str) -> bool:
    """Whether the environment variables let the entry point ``name`` load."""
    load = os.environ.get("PREFORM_LOAD_PLUGINS")
    if load is not None:
        wanted = {n.strip() for n in load.split(",") if n.strip()}
        if name not in wanted:
            return False
    disabled = {n.strip() for n in os.environ.get("PREFORM_DISABLE_PLUGINS", "").split(",")}
    return name not in disabled


def is_builtin_module(module: str | None) -> bool:
    """Whether ``module`` is one of preform's own (``preform`` or under ``preform.``)."""
    return module is not None and (module == "preform" or module.startswith("preform."))


# -- containment ------------------------------------------------------------------------------

# One capture at a time per process: stdout (sys.stdout and fd 1) is process-wide, so two
# threads swapping it concurrently would restore each other's copies.
_CAPTURE_LOCK = threading.RLock()


class _KeptOpen(io.StringIO):
    """The stand-in for sys.stdout during plugin code; a plugin closing it loses nothing."""

    def close(self) -> None:
        pass


#: Temporary files that caught a finished plugin call's raw output, emptied, for the next call:
#: creating one costs ~0.15 ms and a listing makes some 30 contained calls. A stack, because a
#: contained call may run inside another (a registration hook importing a lazy entry), and each
#: level needs its own file. A forked child starts with none (the parent's share its offsets).
_FREE_TRAPS: list[Any] = []
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_FREE_TRAPS.clear)


def _flush_stdout() -> None:
    for stream in (sys.stdout, sys.__stdout__):
        with contextlib.suppress(Exception):
            if stream is not None:
                stream.flush()


@contextlib.contextmanager
def _stdout_to_stderr(plugin: str) -> Iterator[None]:
    """Keep what the block writes to stdout off stdout; forward it to stderr, line by line
    prefixed with ``plugin NAME:``.

    Python-level writes go to a buffer (``redirect_stdout``); raw writes to file descriptor 1
    (``os.write(1, ...)``, C extensions) go to a temporary file swapped onto fd 1 for the block.
    If fd 1 cannot be swapped (closed, no temporary directory) only Python-level writes are
    caught. Output of other threads during the block is caught too, and attributed to the
    plugin: plugin calls happen while loading and validating, not while results are written.
    """
    with _CAPTURE_LOCK:
        buffer = _KeptOpen()
        saved_fd: int | None = None
        trap: Any = None
        # Flush what the program already wrote, so it is not taken for the plugin's output.
        _flush_stdout()
        try:
            trap = _FREE_TRAPS.pop() if _FREE_TRAPS else tempfile.TemporaryFile()
            saved_fd = os.dup(1)
            os.dup2(trap.fileno(), 1)
        except OSError:
            if trap is not None:
                trap.close()
            if saved_fd is not None:
                os.close(saved_fd)
            trap, saved_fd = None, None
        try:
            with contextlib.redirect_stdout(buffer):
                yield
        finally:
            raw = b""
            if saved_fd is not None:
                # what the plugin left in Python's buffers of the real stdout belongs to it too
                _flush_stdout()
                os.dup2(saved_fd, 1)
                os.close(saved_fd)
                trap.seek(0)
                raw = trap.read(MAX_FORWARDED_OUTPUT + 1)
                trap.seek(0)
                trap.truncate()
                _FREE_TRAPS.append(trap)
            text = buffer.getvalue() + raw.decode("utf-8", errors="replace")
            _forward(plugin, text)


def _forward(plugin: str, text: str) -> None:
    if not text.strip():
        return
    if len(text) > MAX_FORWARDED_OUTPUT:
        text = text[:MAX_FORWARDED_OUTPUT] + "\n[... more output dropped]"
    stderr = sys.stderr
    if stderr is None:
        return
    with contextlib.suppress(Exception):
        for line in text.splitlines():
            stderr.write(f"plugin {plugin}: {line}\n")
        stderr.flush()


def call_plugin(
    plugin: str, function: Callable[..., Any], *args: Any, **kwargs: Any
) -> tuple[Any, BaseException | None]:
    """Call plugin code contained: returns (result, None), or (None, the exception).

    Everything but ``KeyboardInterrupt`` is caught, ``SystemExit`` and other BaseExceptions
    included: a plugin must never end the program or stop the other plugins. Its stdout goes to
    stderr (see ``_stdout_to_stderr``).
    """
    with _stdout_to_stderr(plugin):
        try:
            return function(*args, **kwargs), None
        except KeyboardInterrupt:
            raise
        except BaseException as exc:
            return None, exc


def _call_impl(impl: Any, **kwargs: Any) -> tuple[Any, BaseException | None]:
    """Call one hook implementation with the arguments it declares (as pluggy does)."""
    args = [kwargs[name] for name in impl.argnames]
    return call_plugin(impl.plugin_name, impl.function, *args)


def _check_material_result(result: Any) -> tuple[list[str], str | None]:
    """Messages of a ``preform_check_material`` result, and what was wrong with its shape.

    Only plain data is accepted (``str`` messages, paths of ``str``/``int``), so formatting it
    never runs plugin code outside containment.
    """
    if result is None:
        return [], None
    if not isinstance(result, list | tuple):
        return [], f"returned {type(result).__name__}, expected None or a list"
    messages: list[str] = []
    bad: list[str] = []
    for item in result:
        if isinstance(item, str):
            messages.append(item)
            continue
        if (
            isinstance(item, tuple | list)
            and len(item) == 2
            and isinstance(item[1], str)
            and (
                isinstance(item[0], str)
                or (
                    isinstance(item[0], tuple | list)
                    and all(isinstance(p, str | int) and not isinstance(p, bool) for p in item[0])
                )
            )
        ):
            from preform.validation import format_path

            path = (item[0],) if isinstance(item[0], str) else tuple(item[0])
            where = format_path(path)
            messages.append(f"{where}: {item[1]}" if where else item[1])
            continue
        bad.append(type(item).__name__)
    if bad:
        return messages, (
            f"returned {len(bad)} item(s) that are neither a message (str) nor a "
            f"(path, message) pair: {', '.join(sorted(set(bad)))}"
        )
    return messages, None


class PluginHost:
    """The plugin manager, the registry it fills, and a record per plugin."""

    def __init__(self) -> None:
        self.pm = pluggy.PluginManager("preform")
        self.pm.add_hookspecs(hookspecs)
        self.registry = Registry()
        self.registry.hook = self.pm.hook
        self.registry.host = self
        self.records: dict[str, PluginRecord] = {}
        #: Which plugin added each command through ``preform_register_commands``.
        self.command_owners: dict[str, str] = {}

    # -- loading ------------------------------------------------------------------------------
    def discover(self, group: str = ENTRY_POINT_GROUP) -> None:
        """Load every entry point of ``group`` that the environment selects, one at a time:
        preform's own plugins first, then third-party ones, each set by name."""
        candidates = []
        for ep in metadata.entry_points(group=group):
            if not selected_by_environment(ep.name):
                continue
            dist_name, version = _distribution(ep)
            module = ep.value.split(":")[0].strip()
            builtin = is_builtin_module(module) and dist_name in (None, "preform")
            candidates.append((not builtin, ep.name, ep, dist_name, version, module, builtin))
        candidates.sort(key=lambda c: (c[0], c[1], c[3] or "", c[5]))
        for _, name, ep, dist_name, version, module, builtin in candidates:
            existing = self.records.get(name)
            if existing is not None:
                if existing.module == module and existing.distribution == dist_name:
                    continue  # discovered before: this host already has it
                self._refuse_name(name, dist_name, version, module, existing)
                continue
            record = PluginRecord(
                name=name,
                distribution=dist_name,
                version=version,
                origin="entry point",
                module=module,
                builtin=builtin,
            )
            plugin, exc = call_plugin(name, ep.load)
            if exc is not None:  # a broken plugin must never stop the others
                record.error = f"failed to import: {_short_error(exc)}"
                self.records[name] = record
                continue
            self._register(plugin, record)

    def _refuse_name(
        self,
        name: str,
        dist_name: str | None,
        version: str | None,
        module: str,
        existing: PluginRecord,
    ) -> None:
        """Record an entry point whose plugin name is taken by another one (not loaded)."""
        owner = "built-in plugin" if existing.builtin else "plugin"
        key = f"{name} ({dist_name or module})"
        if key in self.records:
            return
        self.records[key] = PluginRecord(
            name=key,
            distribution=dist_name,
            version=version,
            origin="entry point",
            module=module,
            error=(
                f"not loaded: the plugin name {name!r} is already taken by {owner} {name!r} "
                f"({existing.distribution or existing.module}); rename the entry point"
            ),
        )

    def add(
        self, plugin: Any, name: str, *, version: str | None = None, module: str | None = None
    ) -> PluginRecord:
        """Register a plugin object directly (tests, embedding); returns its record."""
        if module is None and isinstance(plugin, type(os)):
            module = plugin.__name__
        record = PluginRecord(
            name=name,
            distribution=None,
            version=version,
            origin="registered",
            module=module,
            builtin=is_builtin_module(module),
        )
        self._register(plugin, record)
        return record

    def add_modules(self, modules: Iterable[tuple[str, str]]) -> None:
        """Register plugins by importable module path: ``[(name, "pkg.module"), ...]``."""
        for name, module in modules:
            if name in self.records:
                continue
            record = PluginRecord(
                name, None, None, "registered", module, builtin=is_builtin_module(module)
            )
            plugin, exc = call_plugin(name, importlib.import_module, module)
            if exc is not None:
                record.error = f"failed to import: {_short_error(exc)}"
                self.records[name] = record
                continue
            self._register(plugin, record)

    def _register(self, plugin: Any, record: PluginRecord) -> None:
        if record.name in self.records:
            raise ValueError(f"a plugin named {record.name!r} is already loaded")
        self.records[record.name] = record
        # pluggy validates hookimpl signatures here, and reads every attribute of the plugin
        # object (a property of a hostile object runs plugin code)
        _, exc = call_plugin(record.name, self.pm.register, plugin, name=record.name)
        if exc is not None:
            with contextlib.suppress(Exception):
                self.pm.unregister(name=record.name)
            record.error = f"invalid plugin: {_short_error(exc)}"
            return
        # pluggy accepts implementations of hooks nobody declared (for late specs); here such an
        # implementation is a misspelling, and it fails this plugin only.
        mine = [
            (hook_name, impl)
            for hook_name, caller in vars(self.pm.hook).items()
            if hasattr(caller, "get_hookimpls")
            for impl in caller.get_hookimpls()
            if impl.plugin_name == record.name
        ]
        misspelled = sorted(
            {h for h, _ in mine if getattr(getattr(self.pm.hook, h), "spec", True) is None}
        )
        if misspelled:
            self.pm.unregister(name=record.name)
            record.error = (
                "unknown hook implementation(s): "
                + ", ".join(misspelled)
                + " (misspelled? see preform.hookspecs)"
            )
            return
        # preform calls each implementation itself (to contain and attribute it), so a wrapper,
        # which only works inside pluggy's own call loop, would silently do nothing.
        wrappers = sorted({h for h, i in mine if i.hookwrapper or getattr(i, "wrapper", False)})
        if wrappers:
            self.pm.unregister(name=record.name)
            record.error = (
                "hook wrappers are not supported: " + ", ".join(wrappers) + " (use plain hooks)"
            )
            return
        if record.builtin:
            self.registry.builtin_plugins.add(record.name)
        self._run_registrations(record)

    def _registration_error(self, record: PluginRecord) -> BaseException | None:
        """Call the plugin's registration hooks once; the first failure, or None."""
        version = record.version or "0"
        for hook_name, registrar_type in REGISTRARS.items():
            for impl in getattr(self.pm.hook, hook_name).get_hookimpls():
                if impl.plugin_name != record.name:
                    continue
                registrar = registrar_type(self.registry, record.name, version)
                _, exc = _call_impl(impl, register=registrar)
                if exc is not None:
                    return exc
        return None

    def _run_registrations(self, record: PluginRecord) -> None:
        # A built-in plugin meeting a name held by a third-party plugin (one added by code
        # before it) displaces that plugin and tries again: built-in names always win. Each
        # round removes one plugin, so this ends.
        while True:
            exc = self._registration_error(record)
            if exc is None:
                record.registered = self.registry.by_plugin(record.name)
                return
            self.registry.remove_plugin(record.name)
            owner = self.records.get(exc.owner) if isinstance(exc, NameConflict) else None
            if (
                record.builtin
                and owner is not None
                and not owner.builtin
                and owner.name != record.name
                and isinstance(exc, NameConflict)
            ):
                self._displace(owner, record, exc)
                continue
            with contextlib.suppress(Exception):
                self.pm.unregister(name=record.name)
            record.error = f"registration failed: {_short_error(exc)}"
            return

    def _displace(self, loser: PluginRecord, builtin: PluginRecord, conflict: NameConflict) -> None:
        """Unload a third-party plugin that holds a built-in plugin's name."""
        self.registry.remove_plugin(loser.name)
        with contextlib.suppress(Exception):
            self.pm.unregister(name=loser.name)
        thing = conflict.kind[:-1].replace("_", " ")
        loser.registered = {}
        loser.error = (
            f"registration failed: {thing} {conflict.name!r} belongs to built-in plugin "
            f"{builtin.name!r} (preform's own names cannot be taken over); plugin unloaded"
        )

    # -- calling hooks ------------------------------------------------------------------------
    def call_contained(
        self, plugin: str, function: Callable[..., Any], *args: Any
    ) -> tuple[Any, BaseException | None]:
        """Call plugin code on behalf of the registry (a lazy entry's import): contained and
        attributed as every other call into a plugin (see ``call_plugin``)."""
        return call_plugin(plugin, function, *args)

    def record_problem(self, plugin: str, message: str) -> None:
        """Note a failure of a loaded plugin's code (it stays loaded; the failure was raised
        where it happened), shown by ``plugins list``."""
        record = self.records.get(plugin)
        if record is not None:
            record.add_problem(message)

    def plugin_modules(self) -> list[tuple[str, str]]:
        """(name, module) of every working plugin, for re-loading in worker processes."""
        return [(r.name, r.module) for r in self.records.values() if r.error is None and r.module]

    def register_commands(self, cli: Any) -> None:
        """Let each plugin add click commands; a failing plugin is recorded, not fatal.

        A plugin may add new commands only: replacing a built-in command or another plugin's
        fails the plugin (the original is put back), as does raising. A failed plugin is
        unloaded as a whole, commands it added included, so what it registered is not used
        half-working.
        """
        for impl in self.pm.hook.preform_register_commands.get_hookimpls():
            record = self.records.get(impl.plugin_name)
            if record is None or record.error is not None:
                continue
            before = dict(cli.commands)
            _, exc = _call_impl(impl, cli=cli)
            added = {n: c for n, c in cli.commands.items() if before.get(n) is not c}
            problem = None
            if exc is not None:
                problem = f"register_commands failed: {_short_error(exc)}"
            else:
                for command_name in sorted(n for n in added if n in before):
                    holder = self.command_owners.get(command_name)
                    owner = f"plugin {holder!r}, loaded earlier" if holder else "preform itself"
                    problem = (
                        f"register_commands failed: command {command_name!r} is already "
                        f"provided by {owner}"
                    )
                    break
            if problem is None:
                for command_name in added:
                    self.command_owners[command_name] = record.name
                continue
            # put the group back as it was before this plugin
            for command_name in added:
                del cli.commands[command_name]
            cli.commands.update({n: c for n, c in before.items() if n in added})
            self.unload(record.name, problem)

    def unload(self, name: str, error: str) -> None:
        """Take a loaded plugin out (registry and hooks) and record why."""
        self.registry.remove_plugin(name)
        with contextlib.suppress(Exception):
            self.pm.unregister(name=name)
        record = self.records[name]
        record.registered = {}
        record.error = error

    def check_material(self, material: Any) -> list[str]:
        """Every plugin's ``preform_check_material`` warnings on one fabric.

        Each implementation is called on its own: one that raises, or returns something that is
        not None or a list of messages / (path, message) pairs, becomes a warning naming the
        plugin and the fabric (and a problem on its record), while the others still run.
        """
        out: list[str] = []
        fabric_name = getattr(material, "name", "?")
        for impl in self.pm.hook.preform_check_material.get_hookimpls():
            result, exc = _call_impl(impl, material=material)
            problem: str | None
            if exc is not None:
                problem = (
                    f"plugin {impl.plugin_name}: check_material hook failed on fabric "
                    f"{fabric_name!r}: {_short_error(exc)}"
                )
                messages: list[str] = []
            else:
                messages, shape = _check_material_result(result)
                problem = (
                    f"plugin {impl.plugin_name}: check_material hook {shape} on fabric "
                    f"{fabric_name!r}"
                    if shape
                    else None
                )
            out += messages
            if problem is not None:
                out.append(problem)
                record = self.records.get(impl.plugin_name)
                if record is not None:
                    record.add_problem(problem)
        return out


def _distribution(ep: metadata.EntryPoint) -> tuple[str | None, str | None]:
    """(name, version) of an entry point's distribution; None for what its metadata lacks.

    One parse of the distribution's metadata per distribution and process (each entry point
    carries its own Distribution object; preform's four share one): parsing is the slow part
    of discovery.
    """
    dist = getattr(ep, "dist", None)
    if dist is None:
        return None, None
    key = str(getattr(dist, "_path", "")) or None
    if key is not None and key in _DISTRIBUTIONS:
        return _DISTRIBUTIONS[key]
    try:
        meta = dist.metadata
    except Exception:
        meta = None
    name = version = None
    with contextlib.suppress(Exception):
        name = meta["Name"] if meta is not None else None
    with contextlib.suppress(Exception):
        version = meta["Version"] if meta is not None else None
    found = (str(name) if name else None), (str(version) if version else None)
    if key is not None:
        _DISTRIBUTIONS[key] = found
    return found


#: (name, version) by distribution path, filled by ``_distribution``.
_DISTRIBUTIONS: dict[str, tuple[str | None, str | None]] = {}


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
