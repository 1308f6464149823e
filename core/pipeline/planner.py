"""Plan a scene: walk back from the requested outputs to the steps that make them.

Only the steps the outputs need are planned, in dependency order (stdlib ``graphlib``), so a
scene asking only for unit-cell data never runs shear or drape steps.
"""

from __future__ import annotations

import difflib
import graphlib
from typing import TYPE_CHECKING

from preform._moved import RETIRED_OUTPUTS
from preform.registry import LazyLoadError, Registry
from preform.step import Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene


class PlanError(ValueError):
    """The outputs cannot be planned; ``problems`` are (index in outputs or None, message)."""

    def __init__(self, problems: list[tuple[int | None, str]]) -> None:
        self.problems = problems
        super().__init__("; ".join(m for _, m in problems))


def providers(registry: Registry) -> dict[str, str]:
    """Which step (by name) provides each product; no step module is imported for it."""
    return registry.providers()


def requirements(step: Step, scene: Scene) -> tuple[str, ...]:
    """What a step needs for this scene (some steps need more when the scene searches)."""
    extra = step.extra_requires(scene) if step.extra_requires is not None else ()
    return tuple(step.requires) + tuple(extra)


def plan(scene: Scene, registry: Registry) -> list[Step]:
    """The steps to run, in order, for the scene's outputs."""
    by_product = providers(registry)
    problems: list[tuple[int | None, str]] = []
    needed: dict[str, Step] = {}
    graph: dict[str, set[str]] = {}

    def visit(product: str, index: int, chain: tuple[str, ...]) -> None:
        name = by_product.get(product)
        if name is None and product in RETIRED_OUTPUTS:
            problems.append((index, RETIRED_OUTPUTS[product]))
            return
        if name is None:
            close = difflib.get_close_matches(product, by_product, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            via = f" (needed by {' <- '.join(reversed(chain))})" if chain else ""
            problems.append(
                (
                    index,
                    f"unknown output {product!r}{via}{hint}; available "
                    f"outputs: {', '.join(sorted(by_product))}",
                )
            )
            return
        try:  # a lazily registered step is imported here, when a plan first needs it
            step = registry.step(name)
        except LazyLoadError as exc:
            problems.append((index, str(exc)))
            return
        for section in step.scene_sections:
            if scene.section(section) is None:
                problems.append(
                    (
                        index,
                        f"output {scene.outputs[index]!r} needs the scene "
                        f"section {section!r} (for step {step.name!r})",
                    )
                )
        if step.name in needed:
            return
        needed[step.name] = step
        deps = requirements(step, scene)
        graph[step.name] = set()
        for dep in deps:
            visit(dep, index, (*chain, product))
            if dep in by_product:
                graph[step.name].add(by_product[dep])

    for index, output in enumerate(scene.outputs):
        visit(output, index, ())
    if problems:
        # keep one message per distinct problem
        unique = list(dict.fromkeys(problems))
        raise PlanError(unique)
    # sorted insertion: the order must not depend on set iteration (the hash seed), so that
    # every process plans the same scene the same way
    sorter: graphlib.TopologicalSorter[str] = graphlib.TopologicalSorter()
    for name in sorted(graph):
        sorter.add(name, *sorted(graph[name]))
    try:
        order = list(sorter.static_order())
    except graphlib.CycleError as exc:
        raise PlanError([(None, f"steps depend on each other in a cycle: {exc.args[1]}")]) from None
    return [needed[name] for name in order]


def explain(scene: Scene, registry: Registry) -> list[str]:
    """Human-readable plan lines."""
    lines = []
    for step in plan(scene, registry):
        reqs = ", ".join(requirements(step, scene)) or "-"
        lines.append(
            f"{step.name} (v{step.version}): needs {reqs} -> provides {', '.join(step.provides)}"
        )
    return lines
