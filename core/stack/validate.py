"""Located problems of a scene's ``layup`` section, found before anything runs.

The fields' own checks are the section model's (``preform.pipeline.layup_section``); here what
needs the scene around them: a ``start`` that sets what each ply sets, a ply's start point off
the tool, per-ply outputs that cannot be planned, and scene outputs that would drape the
case's one fabric outside the stack.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from preform.stack.plies import ply_scene

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene
    from preform.registry import Registry
    from preform.yamlsource import SourceError

MM = 1e-3


def layup_problems(scene: Scene, registry: Registry, err: Any) -> list[SourceError]:
    """Every problem of the layup section, each located (``err(path, label, message)``)."""
    from preform.drape.steps import start_problem
    from preform.pipeline.planner import PlanError, plan

    layup = scene.layup
    assert layup is not None
    errors: list[SourceError] = []
    start = scene.start
    if start is not None:
        for key in sorted(start.model_fields_set & {"orientation_deg", "generator_angle_deg"}):
            if getattr(start, key) == type(start).model_fields[key].default:
                continue  # the default, said again (a dumped scene), changes nothing
            errors.append(
                err(
                    ("start", key),
                    f"start.{key}",
                    f"with a layup each ply gives its own {key.replace('_deg', '')} "
                    f"(layup.plies[k].{key}); remove start.{key}",
                )
            )
        if start.generators == "polyline":
            errors.append(
                err(
                    ("start", "generators"),
                    "start.generators",
                    "a layup's plies are draped from geodesic or plan generators at their own "
                    "orientation; polyline generators fix one ply's paths",
                )
            )
    surface = None
    preflight = getattr(scene.tool, "preflight", None)
    if preflight is not None:
        surface, _ = preflight(scene.base_dir, scene.limits)
    for k, ply in enumerate(layup.plies):
        if surface is not None and ply.start_point_mm is not None:
            x, y = ply.start_point_mm
            problem = start_problem(surface, (x * MM, y * MM))
            if problem is not None:
                label = f"layup.plies[{k}].start_point_mm"
                errors.append(
                    err(
                        ("layup", "plies", k, "start_point_mm"),
                        label,
                        problem.replace("start.point_mm", label),
                    )
                )
    if errors:
        return errors
    # the per-ply outputs, planned on the first ply's scene (every ply's plans the same steps
    # but for the search, which a least-energy ply adds)
    searching = [k for k, p in enumerate(layup.plies) if p.generator_angle_deg == "least_energy"]
    for k in dict.fromkeys([0, *searching[:1]]):
        try:
            plan(ply_scene(scene, k, registry), registry)
        except PlanError as exc:
            for index, message in exc.problems:
                where: tuple[str | int, ...] = ("layup", "ply_outputs")
                label = "layup.ply_outputs"
                if index is not None:
                    where, label = (*where, index), f"{label}[{index}]"
                errors.append(err(where, label, message))
        except ValueError as exc:
            errors.append(err(("layup", "plies", k), f"layup.plies[{k}]", str(exc)))
    for index, output in enumerate(scene.outputs):
        try:
            steps = plan(scene.model_copy(update={"outputs": [output]}), registry)
        except PlanError:
            continue  # said by the scene's own plan
        if any(step.name == "drape" for step in steps):
            errors.append(
                err(
                    ("outputs", index),
                    f"outputs[{index}]",
                    f"with a layup, {output!r} is an output of each ply: list it in "
                    "layup.ply_outputs (the scene's outputs are the stack's: layup, stack_csv, "
                    "stack_thickness_png, stack_sections)",
                )
            )
    return errors
