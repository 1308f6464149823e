"""``preform scenes``: the bundled scenes, one scene in full, and the outputs a scene may ask for."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from preform.command_line import echo_json, fail, json_option


def _registry() -> Any:
    from preform.plugin_manager import default_host

    return default_host().registry


def _first_comment(path: Path) -> str:
    """The first sentence of the file's leading comment (the bundled files describe themselves
    there, so the scene's data, and with it the input hash of its cases, stays as it was)."""
    lines = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if not line.startswith("#"):
            break
        lines.append(line.lstrip("#").strip())
    text = " ".join(lines)
    end = text.find(". ")
    return text[: end + 1] if end >= 0 else text


def bundled_scenes() -> list[dict[str, Any]]:
    """Name, description, outputs and file of every bundled scene, by name."""
    from preform.pipeline.scene import DEFAULT_SCENE, bundled_scene_dir, load_scene

    registry = _registry()
    rows = []
    for path in sorted(bundled_scene_dir().glob("*.yaml")):
        scene, _ = load_scene(path, registry)
        rows.append(
            {
                "name": path.stem,
                "default": path.stem == DEFAULT_SCENE,
                "description": scene.description or _first_comment(path),
                "outputs": list(scene.outputs),
                "file": str(path),
            }
        )
    return rows


def scene_outputs() -> list[dict[str, Any]]:
    """Every output a scene may list under ``outputs``: the products of the registered steps
    and exporters, with what each needs and whether it writes files. A lazily registered step
    that cannot be loaded is left out, with a warning on stderr naming its plugin."""
    from preform.registry import LazyLoadError

    registry = _registry()
    rows = []
    for kind in ("steps", "exporters"):
        for entry in list(registry.entries(kind).values()):
            try:  # imports a lazily registered step's module
                step = registry.step(entry.name)
            except LazyLoadError as exc:
                click.echo(f"warning: {exc}", err=True)
                continue
            for product in step.provides:
                rows.append(
                    {
                        "output": product,
                        "step": step.name,
                        "writes_files": bool(step.writes_files),
                        "requires": list(step.requires),
                        "scene_sections": list(step.scene_sections),
                        "description": step.description,
                        "plugin": entry.plugin,
                    }
                )
    return sorted(rows, key=lambda r: (r["writes_files"], r["output"]))


@click.group("scenes")
def scenes() -> None:
    """The bundled scenes and the outputs a scene may ask for."""


@scenes.command("list")
@json_option
def scenes_list(as_json: bool) -> None:
    """The bundled scenes, usable by name in `pipeline run --scene NAME`."""
    rows = bundled_scenes()
    if as_json:
        echo_json(rows)
        return
    for row in rows:
        mark = " (default)" if row["default"] else ""
        click.echo(f"{row['name']}{mark}: {row['description']}")
        click.echo(f"    outputs: {', '.join(row['outputs'])}")


@scenes.command("show")
@click.argument("scene")
@json_option
def scenes_show(scene: str, as_json: bool) -> None:
    """A scene (bundled name or file): its YAML, the fidelity knobs in force and its plan."""
    from preform.base import fidelity
    from preform.pipeline.planner import explain
    from preform.pipeline.scene import (
        SceneError,
        load_scene,
        missing_scene_message,
        resolve_scene_path,
    )
    from preform.stack.plies import ply_plans

    registry = _registry()
    path = resolve_scene_path(scene)
    if not path.is_file():
        fail([f"error: {missing_scene_message(scene)}"])
    try:
        loaded, data = load_scene(path, registry)
    except SceneError as exc:
        fail([*exc.errors, f"{len(exc.errors)} error(s) in the scene."])
    knobs = fidelity.resolve(loaded).as_dict()
    doc = {
        "name": loaded.name,
        "file": str(path),
        "data": data,
        "fidelity": knobs,
        "plan": explain(loaded, registry) + ply_plans(loaded, registry),
    }
    if as_json:
        echo_json(doc)
        return
    click.echo(f"# {path}")
    click.echo(path.read_text(encoding="utf-8").rstrip())
    click.echo(f"# fidelity knobs in force ({knobs['fidelity']}; node spacing from the tool when")
    click.echo("# not set): " + ", ".join(f"{k} {v}" for k, v in knobs.items() if k != "fidelity"))
    click.echo("# plan:")
    for line in doc["plan"]:
        click.echo(f"#   {line}")


@scenes.command("outputs")
@json_option
def scenes_outputs(as_json: bool) -> None:
    """Every output a scene may list under `outputs:`, what it needs, what it writes."""
    rows = scene_outputs()
    if as_json:
        echo_json(rows)
        return
    width = max(len(r["output"]) for r in rows)
    for row in rows:
        files = "file " if row["writes_files"] else "value"
        needs = ", ".join(row["requires"]) or "-"
        click.echo(f"{row['output']:<{width}}  {files}  needs {needs}: {row['description']}")
