"""Located problems of a scene's ``layup`` section, found before anything runs.

The fields' own checks are the section model's (``preform.pipeline.layup_section``); here what
needs more (the layup step's ``check``): a ply's part outline that crosses itself, a ``start``
that sets what each ply sets, a ply's start point off the tool, per-ply outputs that cannot be
planned, and scene outputs that would drape the case's one fabric outside the stack.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from preform.drape.engine.polygon import outline_problem
from preform.stack.plies import ply_scene

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene
    from preform.registry import Registry
    from preform.yamlsource import Document, SourceError

MM = 1e-3


def layup_problems(scene: Scene, doc: Document, registry: Registry) -> list[SourceError]:
    """Every problem of the layup section, each located in ``doc``."""
    from preform.drape.steps import start_problem
    from preform.pipeline.planner import PlanError, plan

    layup = scene.layup
    assert layup is not None
    errors = [
        doc.error(("layup", "plies", k, "part_outline_mm"), problem, at_value=True)
        for k, ply in enumerate(layup.plies)
        if ply.part_outline_mm is not None
        and (problem := outline_problem(ply.part_outline_mm, "mm")) is not None
    ]
    if errors:
        return errors  # a ply's scene is not defined on an outline without an inside
    start = scene.start
    if start is not None:
        for key in sorted(start.model_fields_set & {"orientation_deg", "generator_angle_deg"}):
            if getattr(start, key) == type(start).model_fields[key].default:
                continue  # the default, said again (a dumped scene), changes nothing
            errors.append(
                doc.error(
                    ("start", key),
                    f"with a layup each ply gives its own {key.replace('_deg', '')} "
                    f"(layup.plies[k].{key}); remove start.{key}",
                )
            )
        if start.generators == "polyline":
            errors.append(
                doc.error(
                    ("start", "generators"),
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
                at = ("layup", "plies", k, "start_point_mm")
                label = f"layup.plies[{k}].start_point_mm"
                errors.append(doc.error(at, problem.replace("start.point_mm", label)))
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
                errors.append(doc.error(where if index is None else (*where, index), message))
        except ValueError as exc:
            errors.append(doc.error(("layup", "plies", k), str(exc)))
    for index, output in enumerate(scene.outputs):
        try:
            steps = plan(scene.model_copy(update={"outputs": [output]}), registry)
        except PlanError:
            continue  # said by the scene's own plan
        if any(step.name == "drape" for step in steps):
            errors.append(
                doc.error(
                    ("outputs", index),
                    f"with a layup, {output!r} is an output of each ply: list it in "
                    "layup.ply_outputs (the scene's outputs are the stack's: layup, stack_csv, "
                    "stack_thickness_png, stack_sections)",
                )
            )
    return errors
