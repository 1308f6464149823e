"""Typed registrars: what plugins register, checked on the way in, attributed to its plugin.

Each kind of thing has a registrar whose ``add`` validates the object at once, so a plugin that
registers something invalid fails (and is reported) while every other plugin keeps working.
"""

from __future__ import annotations

import inspect
import typing
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from pydantic import BaseModel

from preform.material import FabricBase
from preform.step import Step


class RegistrationError(ValueError):
    """A plugin tried to register something invalid or already taken."""


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


@dataclass(frozen=True)
class Entry:
    """One registered thing, with the plugin that provided it."""

    kind: str
    name: str
    obj: Any
    plugin: str
    version: str


@dataclass(frozen=True)
class ShearLawType:
    name: str
    params: type[BaseModel]
    build: Callable[..., Any]


@dataclass(frozen=True)
class SurfaceType:
    name: str
    params: type[BaseModel]
    build: Callable[..., Any]


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

    # -- reading ------------------------------------------------------------------------------
    def entries(self, kind: str) -> dict[str, Entry]:
        return self._entries[kind]

    def names(self, kind: str) -> list[str]:
        return sorted(self._entries[kind])

    def get(self, kind: str, name: str) -> Any:
        try:
            return self._entries[kind][name].obj
        except KeyError:
            known = ", ".join(self.names(kind)) or "none"
            label = kind.rstrip("s").replace("_", " ")
            raise KeyError(f"unknown {label} {name!r}; registered: {known}") from None

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
        for kind in ("steps", "exporters"):
            for entry in self._entries[kind].values():
                yield entry.obj

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
        for entries in self._entries.values():
            for name in [n for n, e in entries.items() if e.plugin == plugin]:
                del entries[name]


class Registrar(Generic[T]):
    """Base of the typed registrars handed to plugin hooks."""

    kind: str = ""

    def __init__(self, registry: Registry, plugin: str, version: str) -> None:
        self._registry = registry
        self._plugin = plugin
        self._version = version

    def _put(self, name: str, obj: T) -> None:
        self._registry._add(Entry(self.kind, name, obj, self._plugin, self._version))


class ArchitectureRegistrar(Registrar[type[FabricBase]]):
    kind = "architectures"

    def add(self, model: type[FabricBase]) -> None:
        """Register a fabric model; its ``architecture`` Literal is the YAML tag."""
        if not (inspect.isclass(model) and issubclass(model, FabricBase)):
            raise RegistrationError(f"{model!r} is not a subclass of preform.FabricBase")
        fabric_model: type[FabricBase] = model
        self._put(_literal_tag(fabric_model, "architecture"), fabric_model)


def _check_callable(build: Any, what: str, arity: int) -> None:
    if not callable(build):
        raise RegistrationError(f"{what}: build must be callable, got {build!r}")
    try:
        inspect.signature(build).bind(*([None] * arity))
    except TypeError as exc:
        raise RegistrationError(f"{what}: build must accept {arity} arguments ({exc})") from None


def _check_tagged(what: str, name: str, params: Any, tag_field: str, build: Any) -> None:
    """A params model tagged ``tag_field: Literal[name]`` and a two-argument builder."""
    label = f"{what} {name!r}"
    if not (inspect.isclass(params) and issubclass(params, BaseModel)):
        raise RegistrationError(f"{label}: params must be a pydantic model")
    tag = _literal_tag(params, tag_field)
    if tag != name:
        raise RegistrationError(f"{label}: params.{tag_field} is Literal[{tag!r}]")
    _check_callable(build, label, 2)


class ShearLawRegistrar(Registrar[ShearLawType]):
    kind = "shear_laws"

    def add(self, name: str, params: type[BaseModel], build: Callable[..., Any]) -> None:
        """Register a law: ``params`` validates the YAML block (``law: Literal[name]``);
        ``build(params, fabric)`` returns an object satisfying ``preform.ShearLaw``."""
        _check_tagged("shear law", name, params, "law", build)
        self._put(name, ShearLawType(name, params, build))


class SurfaceRegistrar(Registrar[SurfaceType]):
    kind = "surfaces"

    def add(self, name: str, params: type[BaseModel], build: Callable[..., Any]) -> None:
        """Register a tool surface: ``params`` validates the scene's ``tool`` block
        (``surface: Literal[name]``); ``build(params, base_dir)`` returns a Surface [m]."""
        _check_tagged("surface", name, params, "surface", build)
        self._put(name, SurfaceType(name, params, build))


class StepRegistrar(Registrar[Step]):
    kind = "steps"

    def add(self, step: Step) -> None:
        """Register a pipeline step."""
        if not isinstance(step, Step):
            raise RegistrationError(f"{step!r} is not a preform.Step")
        if not step.provides:
            raise RegistrationError(f"step {step.name!r} provides nothing")
        if not callable(step.run) or getattr(step.run, "__name__", "") == "<lambda>":
            raise RegistrationError(
                f"step {step.name!r}: run must be a module-level function (picklable)"
            )
        for product in step.provides:
            for kind in ("steps", "exporters"):
                for other in self._registry.entries(kind).values():
                    if product in other.obj.provides:
                        raise NameConflict(
                            f"step {step.name!r}: product {product!r} is already provided by "
                            f"step {other.name!r} of "
                            f"{self._registry.describe_owner(other.plugin, self._plugin)}",
                            kind="products",
                            name=product,
                            owner=other.plugin,
                        )
        self._put(step.name, step)


class ExporterRegistrar(StepRegistrar):
    kind = "exporters"

    def add(self, step: Step) -> None:
        """Register an exporter (a step with ``writes_files=True``)."""
        if isinstance(step, Step) and not step.writes_files:
            raise RegistrationError(f"exporter {step.name!r} must have writes_files=True")
        super().add(step)


REGISTRARS: dict[str, type[Registrar[Any]]] = {
    "preform_register_architectures": ArchitectureRegistrar,
    "preform_register_shear_laws": ShearLawRegistrar,
    "preform_register_surfaces": SurfaceRegistrar,
    "preform_register_steps": StepRegistrar,
    "preform_register_exporters": ExporterRegistrar,
}
