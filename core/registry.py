"""Typed registrars: what plugins register, checked on the way in, attributed to its plugin.

Each kind of thing has a registrar whose ``add`` validates the object at once, so a plugin that
registers something invalid fails (and is reported) while every other plugin keeps working.

Lazy registration: steps, exporters, shear laws and surfaces may instead be registered by
import path (``add_lazy``), so that starting the plugin host imports none of their modules
(``preform --help`` and ``materials list`` would otherwise import every drape, search and
export module). What the registry lists and checks between plugins is given in the call and
checked at once: the name and, for a step, the products it provides and the scene sections it
owns (the conflicts between plugins are found at registration, as for an ordinary step). The object itself is
imported when first asked for (``Registry.step``, ``shear_law_type``, ``surface_type``: a run
that plans the step, a fabric whose ``shear_law`` block names the law, a scene's tool) and is
then checked as ``add`` would have checked it, and against what was declared. A lazy entry that
cannot be loaded raises :class:`LazyLoadError` naming the plugin, the entry and its import path,
and is recorded among the plugin's problems; every other entry keeps working.
"""

from __future__ import annotations

import importlib
import inspect
import typing
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, Generic, NamedTuple, TypeVar

if TYPE_CHECKING:
    # imported where a check needs them: the plugin host starts (``preform --help``) without
    # pydantic or the fabric models, and ``materials list`` without the step contract (it
    # registers steps by import path and never loads one)
    from pydantic import BaseModel

    from preform.material import FabricBase
    from preform.step import Step


class RegistrationError(ValueError):
    """A plugin tried to register something invalid or already taken."""


class LazyLoadError(RegistrationError):
    """A lazily registered entry could not be imported, or is not what its plugin declared."""


class NameConflict(RegistrationError):
    """A plugin tried to register a name (or a step product) that another plugin holds.

    ``owner`` is the plugin holding it: the host uses it to let a built-in plugin displace a
    third-party one that was registered before it (built-in names always win).
    """

    def __init__(self, message: str, *, kind: str, name: str, owner: str) -> None:
        super().__init__(message)
        self.kind = kind
        self.name = name
        self.owner = owner


# The registry's records are named tuples, not frozen dataclasses: as immutable and compared by
# value, but a dataclass execs its generated methods when its class is created, which every
# command pays at start-up (some 3.5 M instructions per class on Python 3.11, issue 15l).


class Entry(NamedTuple):
    """One registered thing, with the plugin that provided it."""

    kind: str
    name: str
    obj: Any
    plugin: str
    version: str


class ShearLawType(NamedTuple):
    """A registered shear law: its params model (the YAML block) and its builder."""

    name: str
    params: type[BaseModel]
    build: Callable[..., Any]


class SurfaceType(NamedTuple):
    """A registered tool surface: its params model (the scene's tool block) and its builder."""

    name: str
    params: type[BaseModel]
    build: Callable[..., Any]


class LazyStep(NamedTuple):
    """A step (or exporter) registered by import path, before its module is imported.

    ``target`` is ``"package.module:ATTRIBUTE"``; the attribute is the ``Step`` itself or a
    sequence of steps holding the one named ``name``. ``provides`` is what the step declares
    it provides: the registry checks product conflicts with it, and the planner finds the step
    by it, without importing the module.
    """

    name: str
    provides: tuple[str, ...]
    target: str
    writes_files: bool = False
    #: The scene sections the step owns (``Step.sections``), declared like ``provides``.
    sections: tuple[str, ...] = ()


class LazyArchitecture(NamedTuple):
    """An architecture registered by the import path of its fabric model (``"package.module:
    ATTRIBUTE"``), imported when a library first has a fabric of its tag."""

    name: str
    model: str


class LazyTagged(NamedTuple):
    """A shear law or surface registered by import paths (``"package.module:ATTRIBUTE"``) of its
    params model and its builder, imported when the law or surface is first asked for."""

    name: str
    params: str
    build: str


def _check_target(what: str, target: Any) -> str:
    """An import path ``"package.module:attribute"`` (checked for shape, not imported)."""
    if not isinstance(target, str) or target.count(":") != 1:
        raise RegistrationError(
            f"{what}: import path must be a string 'package.module:attribute', got {target!r}"
        )
    module, attribute = target.split(":")
    parts = [*module.split("."), attribute]
    if not all(p.isidentifier() for p in parts):
        raise RegistrationError(
            f"{what}: import path {target!r} is not 'package.module:attribute' "
            "(dotted identifiers, one colon)"
        )
    return target


def import_target(target: str) -> Any:
    """The object an import path ``"package.module:attribute"`` names (imports its module)."""
    module, attribute = target.split(":")
    value = getattr(importlib.import_module(module), attribute, _MISSING)
    if value is _MISSING:
        raise AttributeError(f"module {module!r} has no attribute {attribute!r}")
    return value


_MISSING = object()
_LAZY = (LazyStep, LazyArchitecture, LazyTagged)


def _literal_tag(model: type[BaseModel], field: str) -> str:
    """The single value of a ``Literal[...]`` discriminator field, or a RegistrationError."""
    info = model.model_fields.get(field)
    if info is None:
        raise RegistrationError(f"{model.__name__} has no field {field!r}")
    args = typing.get_args(info.annotation)
    if typing.get_origin(info.annotation) is not typing.Literal or len(args) != 1:
        raise RegistrationError(
            f"{model.__name__}.{field} must be a Literal of one string (the tag), "
            f"got {info.annotation!r}"
        )
    tag = args[0]
    if not isinstance(tag, str) or not tag:
        raise RegistrationError(f"{model.__name__}.{field} tag must be a non-empty string")
    return tag


T = TypeVar("T")


class Registry:
    """All registered things, by kind and name."""

    KINDS = ("architectures", "shear_laws", "surfaces", "steps", "exporters")

    def __init__(self) -> None:
        self._entries: dict[str, dict[str, Entry]] = {kind: {} for kind in self.KINDS}
        #: The plugin manager's hook relay, for collecting hooks (set by the PluginHost).
        self.hook: Any = None
        #: The PluginHost that fills this registry (set by it): the library calls plugin
        #: hooks through it, so each call is contained and attributed.
        self.host: Any = None
        #: Plugins shipped with preform; their names cannot be taken by any other plugin.
        self.builtin_plugins: set[str] = set()
        #: Why a lazy entry could not be loaded, by (kind, name): asked again, it fails the same
        #: way without importing again.
        self._load_failures: dict[tuple[str, str], str] = {}

    # -- reading ------------------------------------------------------------------------------
    def entries(self, kind: str) -> dict[str, Entry]:
        return self._entries[kind]

    def names(self, kind: str) -> list[str]:
        return sorted(self._entries[kind])

    def get(self, kind: str, name: str) -> Any:
        """The registered object, imported first if it was registered lazily."""
        try:
            entry = self._entries[kind][name]
        except KeyError:
            known = ", ".join(self.names(kind)) or "none"
            label = kind.rstrip("s").replace("_", " ")
            raise KeyError(f"unknown {label} {name!r}; registered: {known}") from None
        if isinstance(entry.obj, _LAZY):
            entry = self._load(entry)
        return entry.obj

    def step(self, name: str) -> Step:
        """The step or exporter ``name`` (its module imported now if registered lazily)."""
        kind = "exporters" if name in self._entries["exporters"] else "steps"
        step: Step = self.get(kind, name)
        return step

    def providers(self, declared: str = "provides") -> dict[str, str]:
        """Which step (by name) provides each product, or with ``declared="sections"`` owns
        each scene section, without importing any step module."""
        return {
            name: entry.name
            for kind in ("steps", "exporters")
            for entry in self._entries[kind].values()
            for name in getattr(entry.obj, declared)
        }

    def load_all(self) -> list[str]:
        """Import every lazy entry now; the messages of those that do not load (each is also
        recorded among its plugin's problems)."""
        failures = []
        for kind in self.KINDS:
            for name in list(self._entries[kind]):
                try:
                    self.get(kind, name)
                except LazyLoadError as exc:
                    failures.append(str(exc))
        return failures

    def is_loaded(self, kind: str, name: str) -> bool:
        """Whether the entry's object is imported (False while a lazy entry waits)."""
        return not isinstance(self._entries[kind][name].obj, _LAZY)

    def _load(self, entry: Entry) -> Entry:
        """Import a lazy entry, check it as its registrar would, and keep the loaded entry.

        The import is plugin code: it runs contained by the host (its output kept off stdout,
        any exception caught) and a failure is recorded against the plugin, then raised as a
        LazyLoadError naming the plugin, the entry and the import path.
        """
        lazy = entry.obj
        label = f"{entry.kind[:-1].replace('_', ' ')} {entry.name!r}"
        where = f"plugin {entry.plugin!r}: {label}"
        failure = self._load_failures.get((entry.kind, entry.name))
        if failure is not None:
            raise LazyLoadError(failure)

        def load() -> Any:
            if isinstance(lazy, LazyStep):
                step = _pick_step(import_target(lazy.target), lazy.name, lazy.target)
                _check_step(step, entry.kind)
                for what, does, declared, got in (
                    ("providing", "provides", lazy.provides, step.provides),
                    ("owning the scene sections", "owns", lazy.sections, step.sections),
                ):
                    if set(declared) != set(got):
                        raise RegistrationError(
                            f"registered as {what} {sorted(declared)}, but the step at "
                            f"{lazy.target} {does} {sorted(got)}"
                        )
                return step
            if isinstance(lazy, LazyArchitecture):
                model = import_target(lazy.model)
                tag = _check_architecture(model)
                if tag != lazy.name:
                    raise RegistrationError(
                        f"registered as {lazy.name!r}, but {lazy.model} has architecture "
                        f"Literal[{tag!r}]"
                    )
                return model
            params, build = import_target(lazy.params), import_target(lazy.build)
            tag_field = "law" if entry.kind == "shear_laws" else "surface"
            _check_tagged(label.split(" ")[0], lazy.name, params, tag_field, build)
            made = ShearLawType if entry.kind == "shear_laws" else SurfaceType
            return made(lazy.name, params, build)

        if self.host is not None:
            obj, exc = self.host.call_contained(entry.plugin, load)
        else:
            try:
                obj, exc = load(), None
            except Exception as error:
                obj, exc = None, error
        if exc is not None:
            target = (
                lazy.target
                if isinstance(lazy, LazyStep)
                else lazy.model
                if isinstance(lazy, LazyArchitecture)
                else f"{lazy.params}, {lazy.build}"
            )
            message = f"{where} could not be loaded from {target}: {_error_text(exc)}"
            self._load_failures[(entry.kind, entry.name)] = message
            if self.host is not None:
                self.host.record_problem(entry.plugin, message)
            raise LazyLoadError(message) from exc
        loaded = Entry(entry.kind, entry.name, obj, entry.plugin, entry.version)
        self._entries[entry.kind][entry.name] = loaded
        return loaded

    def architecture(self, tag: str) -> type[FabricBase]:
        model: type[FabricBase] = self.get("architectures", tag)
        return model

    def shear_law_type(self, name: str) -> ShearLawType:
        law: ShearLawType = self.get("shear_laws", name)
        return law

    def surface_type(self, name: str) -> SurfaceType:
        surface: SurfaceType = self.get("surfaces", name)
        return surface

    def all_steps(self) -> Iterator[Step]:
        """Every step and exporter, importing each lazily registered one (use ``providers``
        and ``step`` to reach only the steps a run needs)."""
        for kind in ("steps", "exporters"):
            for name in list(self._entries[kind]):
                yield self.get(kind, name)

    def by_plugin(self, plugin: str) -> dict[str, list[str]]:
        out: dict[str, list[str]] = {}
        for kind, entries in self._entries.items():
            names = sorted(n for n, e in entries.items() if e.plugin == plugin)
            if names:
                out[kind] = names
        return out

    # -- writing (through registrars) ----------------------------------------------------------
    def describe_owner(self, plugin: str, requester: str) -> str:
        """How a conflict names the plugin that holds a name."""
        if plugin == requester:
            return "this same plugin (registered twice)"
        if plugin in self.builtin_plugins:
            return f"built-in plugin {plugin!r} (preform's own names cannot be taken over)"
        return f"plugin {plugin!r}, loaded earlier"

    def _namespace(self, kind: str) -> tuple[str, ...]:
        # Steps and exporters share one namespace: the planner and the per-step timings key
        # on the step name whatever its kind.
        return ("steps", "exporters") if kind in ("steps", "exporters") else (kind,)

    def _add(self, entry: Entry) -> None:
        for kind in self._namespace(entry.kind):
            existing = self._entries[kind].get(entry.name)
            if existing is not None:
                label = entry.kind[:-1].replace("_", " ")
                raise NameConflict(
                    f"{label} {entry.name!r} is already registered by "
                    f"{self.describe_owner(existing.plugin, entry.plugin)}",
                    kind=entry.kind,
                    name=entry.name,
                    owner=existing.plugin,
                )
        self._entries[entry.kind][entry.name] = entry

    def remove_plugin(self, plugin: str) -> None:
        """Undo everything a plugin registered (used when its registration fails midway)."""
        for kind, entries in self._entries.items():
            for name in [n for n, e in entries.items() if e.plugin == plugin]:
                del entries[name]
                self._load_failures.pop((kind, name), None)


class Registrar(Generic[T]):
    """Base of the typed registrars handed to plugin hooks."""

    kind: str = ""

    def __init__(self, registry: Registry, plugin: str, version: str) -> None:
        self._registry = registry
        self._plugin = plugin
        self._version = version

    def _put(self, name: str, obj: T) -> None:
        self._registry._add(Entry(self.kind, name, obj, self._plugin, self._version))


class ArchitectureRegistrar(Registrar["type[FabricBase] | LazyArchitecture"]):
    kind = "architectures"

    def add(self, model: type[FabricBase]) -> None:
        """Register a fabric model; its ``architecture`` Literal is the YAML tag."""
        self._put(_check_architecture(model), model)

    def add_lazy(self, tag: str, *, model: str) -> None:
        """Register a fabric model by import path (``"package.module:ATTRIBUTE"``) under its
        YAML tag; it is imported, and checked as ``add`` checks it, when first asked for."""
        label = f"architecture {_check_name('architecture', tag)!r}"
        self._put(tag, LazyArchitecture(tag, _check_target(label, model)))


def _check_architecture(model: Any) -> str:
    """A subclass of FabricBase with an ``architecture`` Literal; its tag."""
    from preform.material import FabricBase

    if not (inspect.isclass(model) and issubclass(model, FabricBase)):
        raise RegistrationError(f"{model!r} is not a subclass of preform.FabricBase")
    return _literal_tag(model, "architecture")


def _check_callable(build: Any, what: str, arity: int) -> None:
    if not callable(build):
        raise RegistrationError(f"{what}: build must be callable, got {build!r}")
    try:
        inspect.signature(build).bind(*([None] * arity))
    except TypeError as exc:
        raise RegistrationError(f"{what}: build must accept {arity} arguments ({exc})") from None


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, RegistrationError):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def _pick_step(value: Any, name: str, target: str) -> Any:
    """The step named ``name`` at an import path: the object itself, or one of a sequence."""
    from preform.step import Step

    if isinstance(value, list | tuple):
        found = [s for s in value if getattr(s, "name", None) == name]
        if len(found) != 1:
            raise RegistrationError(
                f"{target} is a sequence holding {len(found)} steps named {name!r} (needs one)"
            )
        return found[0]
    if isinstance(value, Step) and value.name != name:
        raise RegistrationError(f"the step at {target} is named {value.name!r}, not {name!r}")
    return value


def _check_step(step: Any, kind: str) -> None:
    """What every step must be, whether added directly or loaded from an import path."""
    from preform.step import Step

    if not isinstance(step, Step):
        raise RegistrationError(f"{step!r} is not a preform.Step")
    if not step.provides:
        raise RegistrationError(f"step {step.name!r} provides nothing")
    if not callable(step.run) or getattr(step.run, "__name__", "") == "<lambda>":
        raise RegistrationError(
            f"step {step.name!r}: run must be a module-level function (picklable)"
        )
    if kind == "exporters" and not step.writes_files:
        raise RegistrationError(f"exporter {step.name!r} must have writes_files=True")
    from pydantic import BaseModel

    for key, model in step.sections.items():
        is_model = model is None or (isinstance(model, type) and issubclass(model, BaseModel))
        if not (isinstance(key, str) and key.isidentifier() and is_model):
            raise RegistrationError(f"step {step.name!r}: section {key!r} needs a pydantic model")


def _check_tagged(what: str, name: str, params: Any, tag_field: str, build: Any) -> None:
    """A params model tagged ``tag_field: Literal[name]`` and a two-argument builder."""
    from pydantic import BaseModel

    label = f"{what} {name!r}"
    if not (inspect.isclass(params) and issubclass(params, BaseModel)):
        raise RegistrationError(f"{label}: params must be a pydantic model")
    tag = _literal_tag(params, tag_field)
    if tag != name:
        raise RegistrationError(f"{label}: params.{tag_field} is Literal[{tag!r}]")
    _check_callable(build, label, 2)


def _check_name(what: str, name: Any) -> str:
    if not isinstance(name, str) or not name:
        raise RegistrationError(f"{what} name must be a non-empty string, got {name!r}")
    return name


class _TaggedRegistrar(Registrar[Any]):
    """Shear laws and surfaces: a name, a params model tagged with it, a builder."""

    what = ""
    tag_field = ""

    def add_lazy(self, name: str, *, params: str, build: str) -> None:
        """Register by import paths (``"package.module:ATTRIBUTE"``) of the params model and the
        builder; both are imported, and checked as ``add`` checks them, when first asked for."""
        label = f"{self.what} {_check_name(self.what, name)!r}"
        self._put(
            name,
            LazyTagged(name, _check_target(label, params), _check_target(label, build)),
        )


class ShearLawRegistrar(_TaggedRegistrar):
    kind = "shear_laws"
    what = "shear law"

    def add(self, name: str, params: type[BaseModel], build: Callable[..., Any]) -> None:
        """Register a law: ``params`` validates the YAML block (``law: Literal[name]``);
        ``build(params, fabric)`` returns an object satisfying ``preform.ShearLaw``."""
        _check_tagged("shear law", name, params, "law", build)
        self._put(name, ShearLawType(name, params, build))


class SurfaceRegistrar(_TaggedRegistrar):
    kind = "surfaces"
    what = "surface"

    def add(self, name: str, params: type[BaseModel], build: Callable[..., Any]) -> None:
        """Register a tool surface: ``params`` validates the scene's ``tool`` block
        (``surface: Literal[name]``); ``build(params, base_dir)`` returns a Surface [m]."""
        _check_tagged("surface", name, params, "surface", build)
        self._put(name, SurfaceType(name, params, build))


class StepRegistrar(Registrar["Step | LazyStep"]):
    kind = "steps"

    def add(self, step: Step) -> None:
        """Register a pipeline step."""
        _check_step(step, self.kind)
        self._check_products(step.name, step.provides, tuple(step.sections))
        self._put(step.name, step)

    def add_lazy(
        self,
        name: str,
        *,
        provides: tuple[str, ...] | list[str],
        target: str,
        sections: tuple[str, ...] | list[str] = (),
    ) -> None:
        """Register a step by import path without importing it: ``target`` is
        ``"package.module:ATTRIBUTE"``, the ``Step`` or a sequence of steps holding the one
        named ``name``; ``provides`` is what it provides and ``sections`` the scene sections it
        owns (both checked for conflicts now, and against the step when it is imported, on
        first use)."""
        label = f"{self.kind[:-1]} {_check_name(self.kind[:-1], name)!r}"
        for what, names, least in (("provides", provides, 1), ("sections", sections, 0)):
            if isinstance(names, str) or not (
                isinstance(names, tuple | list)
                and len(names) >= least
                and all(isinstance(p, str) and p for p in names)
            ):
                raise RegistrationError(
                    f"{label}: {what} must be a {'non-empty ' * least}list of names, got {names!r}"
                )
        self._check_products(name, tuple(provides), tuple(sections))
        lazy = LazyStep(
            name,
            tuple(provides),
            _check_target(label, target),
            self.kind == "exporters",
            tuple(sections),
        )
        self._put(name, lazy)

    def _check_products(
        self, name: str, provides: tuple[str, ...], sections: tuple[str, ...]
    ) -> None:
        """A product or scene section held by another step is a conflict."""
        for kind in ("steps", "exporters"):
            for other in self._registry.entries(kind).values():
                for what, mine, theirs in (
                    ("product", provides, other.obj.provides),
                    ("scene section", sections, other.obj.sections),
                ):
                    for taken in set(mine) & set(theirs):
                        raise NameConflict(
                            f"step {name!r}: {what} {taken!r} is already "
                            f"{'provided' if what == 'product' else 'owned'} by "
                            f"step {other.name!r} of "
                            f"{self._registry.describe_owner(other.plugin, self._plugin)}",
                            kind="products" if what == "product" else "sections",
                            name=taken,
                            owner=other.plugin,
                        )


class ExporterRegistrar(StepRegistrar):
    """Exporters: steps with ``writes_files=True`` (checked by ``add``, and on loading a lazy
    one)."""

    kind = "exporters"


REGISTRARS: dict[str, type[Registrar[Any]]] = {
    "preform_register_architectures": ArchitectureRegistrar,
    "preform_register_shear_laws": ShearLawRegistrar,
    "preform_register_surfaces": SurfaceRegistrar,
    "preform_register_steps": StepRegistrar,
    "preform_register_exporters": ExporterRegistrar,
}
