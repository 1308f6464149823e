"""Scenes changed on the way in: a ``--fidelity`` preset from the command line, or keyword
arguments of the Python API (``preform.scene(..., generator_angle_deg=80)``).

A change is applied to the scene's *data*, before it is validated and before cases are made, so
the changed scene is validated exactly as a file saying the same would be (located errors
included), and the change is part of every case's input hash: a ``--fidelity fine`` run never
reuses a ``standard`` result, and the summary records the preset in force.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from preform.pipeline.scene import Scene, SceneError, load_scene, validate_scene_data
from preform.registry import Registry
from preform.yamlsource import SourceError, YamlSourceError, load_yaml, load_yaml_text

#: A path into scene data (``("start", "generator_angle_deg")``) and the value to put there;
#: ``None`` removes the key.
Changes = Mapping[tuple[str, ...], Any]


def changed_data(data: Mapping[str, Any], changes: Changes) -> dict[str, Any]:
    """A deep copy of ``data`` with ``changes`` applied (sections created as needed)."""
    out: dict[str, Any] = copy.deepcopy(dict(data))
    for path, value in changes.items():
        where = out
        for key in path[:-1]:
            section = where.get(key)
            if not isinstance(section, dict):
                section = {}
                where[key] = section
            where = section
        if value is None:
            where.pop(path[-1], None)
        else:
            where[path[-1]] = value
    return out


def load_scene_changed(
    path: str | Path, registry: Registry, changes: Changes | None = None
) -> tuple[Scene, dict[str, Any]]:
    """``load_scene`` with ``changes`` applied to the file's data before validation.

    Errors stay located in the file; a value that only the change put there is located at its
    closest ancestor that the file has.
    """
    if not changes:
        return load_scene(path, registry)
    try:
        docs = load_yaml(path)
    except YamlSourceError as exc:
        raise SceneError(exc.errors) from None
    if len(docs) != 1:
        return load_scene(path, registry)  # raises the located "one document" error
    data = changed_data(docs[0].data, changes) if isinstance(docs[0].data, dict) else docs[0].data
    doc = dataclasses.replace(docs[0], data=data)
    return validate_scene_data(doc, data, registry), data


def scene_from_mapping(
    data: Mapping[str, Any],
    registry: Registry,
    *,
    base_dir: str | Path = ".",
    label: str = "<scene>",
) -> tuple[Scene, dict[str, Any]]:
    """Validate scene data given as a mapping (the Python API); relative paths in it (a tool
    mesh) resolve against ``base_dir``. Errors are located in the mapping's YAML rendering,
    named ``label``."""
    import yaml

    plain = copy.deepcopy(dict(data))
    try:
        text = yaml.safe_dump(plain, sort_keys=False)
    except yaml.YAMLError as exc:
        raise SceneError([SourceError(label, 1, 1, "", f"not plain data: {exc}")]) from None
    (doc,) = load_yaml_text(text, label)
    scene = validate_scene_data(doc, doc.data, registry)
    return scene.located_at(str(Path(base_dir).resolve())), doc.data


def with_fidelity(preset: str | None) -> dict[tuple[str, ...], Any]:
    """The change a ``--fidelity`` preset makes: the scene's ``fidelity`` replaced. Knobs the
    scene sets by hand (``ply.node_spacing_mm``, ``numerics``, ``search`` steps) still win over
    any preset, as they do over the scene's own."""
    return {("fidelity",): preset} if preset is not None else {}
