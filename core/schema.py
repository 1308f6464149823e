"""JSON Schemas of library and scene files, built from what plugins registered."""

from __future__ import annotations

from typing import Annotated, Any, Union

from pydantic import Field, TypeAdapter, create_model

from preform.pipeline.scene import Scene
from preform.registry import LazyLoadError, Registry


def _union(models: list[Any], tag: str) -> Any:
    if not models:
        return Any
    if len(models) == 1:
        return models[0]
    return Annotated[Union[tuple(models)], Field(discriminator=tag)]  # noqa: UP007


def library_schema(registry: Registry) -> dict[str, Any]:
    """Schema of a library file: one entry or a list of entries."""
    laws = _union([registry.shear_law_type(n).params for n in registry.names("shear_laws")], "law")
    entries = []
    for tag in registry.names("architectures"):
        model = registry.architecture(tag)
        entries.append(
            create_model(  # the entry as the user writes it, with its law typed
                model.__name__, __base__=model, shear_law=(laws | None, None)
            )
        )
    entry = _union(entries, "architecture")
    # the union is built at run time from the registry, which static typing cannot follow
    file_form: Any = Union[entry, list[entry]]  # type: ignore[valid-type]  # noqa: UP007
    schema = TypeAdapter(file_form).json_schema()
    schema["title"] = "preform materials library file"
    return schema


def scene_schema(registry: Registry) -> dict[str, Any]:
    """Schema of a scene file: the scene's fields, its tool by the registered surfaces, and
    the sections plugins' steps own (``Step.sections``) by their models."""
    tools = _union([registry.surface_type(n).params for n in registry.names("surfaces")], "surface")
    sections: dict[str, Any] = {}
    for key, owner in registry.providers("sections").items():
        if key in Scene.model_fields:
            continue
        try:
            section = registry.step(owner).sections[key]
        except LazyLoadError:  # a plugin that cannot load: its section is any mapping
            section = None
        sections[key] = ((section or dict[str, Any]) | None, None)
    model = create_model("Scene", __base__=Scene, tool=(tools | None, None), **sections)
    schema = model.model_json_schema()
    schema["title"] = "preform scene file"
    return schema
