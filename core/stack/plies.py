"""One drape scene per ply of a layup (``preform.pipeline.layup_section``): the scene's tool,
part, ply size, node spacing, fidelity and limits with the ply's start, orientation, generator
angle, part outline and outputs set. Scenes are mm and degrees, as everywhere."""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

from preform.pipeline.layup_section import layup_of

if TYPE_CHECKING:
    from preform.pipeline.layup_section import LayupPly, LayupSection
    from preform.pipeline.scene import Scene
    from preform.registry import Registry


def plan_orientation_deg(layup: LayupSection, ply: LayupPly) -> float:
    """Plan direction of the ply's first fibre family at its start [deg from x]: the
    reference direction plus the ply angle (``preform.pipeline.layup_section``)."""
    return float(layup.reference_direction_deg) + float(ply.orientation_deg)


def ply_scene_data(scene: Scene, index: int) -> dict[str, Any]:
    """The drape scene data of ply ``index`` (0 on the tool side) of ``scene``'s layup."""
    layup = layup_of(scene)
    ply = layup.plies[index]
    # the plugin steps' sections too: a plugin step among the ply outputs reads its own
    data = scene.model_dump(mode="json", exclude_none=True) | scene.plugin_sections_data()
    data = copy.deepcopy(data)
    data.pop("layup", None)
    data["name"] = f"{scene.name}/{layup.ply_names()[index]}"
    start = data.get("start") or {}
    point = ply.start_point_mm if ply.start_point_mm is not None else start.get("point_mm")
    data["start"] = {
        "point_mm": list(point) if point is not None else [0.0, 0.0],
        "orientation_deg": plan_orientation_deg(layup, ply),
        "generators": start.get("generators", "geodesic"),
    }
    if ply.generator_angle_deg == "least_energy":
        data["search"] = data.get("search") or {}
    else:
        data["start"]["generator_angle_deg"] = float(ply.generator_angle_deg)
        data.pop("search", None)
    data.setdefault("ply", {})
    if ply.part_outline_mm is not None:
        part = dict(data.get("part") or {})
        part["plan_outline_mm"] = [list(p) for p in ply.part_outline_mm]
        data["part"] = part
    if ply.thickness_mm is not None:
        export = dict(data.get("export") or {})
        export["nominal_thickness_mm"] = float(ply.thickness_mm)
        data["export"] = export
    data["outputs"] = list(layup.ply_outputs)
    data.pop("materials", None)
    return data


def ply_scene(scene: Scene, index: int, registry: Registry) -> Scene:
    """Ply ``index``'s drape scene, validated as a scene (its tool block against the
    registered surfaces), resolving paths against the layup scene's folder."""
    from preform.pipeline.scene import scene_from_data

    return scene_from_data(ply_scene_data(scene, index), scene.base_dir, registry)


def ply_plans(scene: Scene, registry: Registry) -> list[str]:
    """Human-readable plan lines of each ply of the scene's layup (each ply runs its own plan
    inside the layup step); none without a layup."""
    from preform.pipeline.planner import plan

    lines = []
    for k, name in enumerate(layup_of(scene).ply_names() if scene.layup else ()):
        steps = plan(ply_scene(scene, k, registry), registry)
        names = ", ".join(s.name for s in steps if s.name != "surface")
        under = "the tool offset by the plies below" if k else "the tool"
        lines.append(f"  layup ply {name}: {names} (on {under})")
    return lines
