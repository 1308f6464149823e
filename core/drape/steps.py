"""Pipeline steps of the drape: build the tool, drape the ply, export the draped pattern.

The drape step uses the scene's generator angle, or the minimum-energy search's optimum when
the scene has a ``search`` section. Scenes give mm and degrees; everything here is SI.

The steps say what their result is worth (``preform.drape.judging.verdict``, ``docs/results.md``): a
non-finite energy or a net without a cell raises ``CaseFailure``; a net that does not cover the
ply where it lies over the tool marks the case partial with the covered fraction and why; cells
past the law's locking, stitch-failure or packing angle, or outside its data range, are counted
and said in words; a drape whose energy comes mostly from cells past jamming or stitch failure
(where the fabric would wrinkle) is partial too (``preform.drape.judging.wrinkling``). A ply too large for ``limits.max_nodes`` is refused before any array exists.
"""

from __future__ import annotations

import dataclasses
import inspect
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from preform.base import fidelity
from preform.base.limits import MAX_POLYGON_VERTICES
from preform.base.status import CaseFailure
from preform.drape.engine.fields import cell_fields, energy_field, summary
from preform.drape.engine.net import DrapeError, drape
from preform.drape.engine.part import HeightCut, Part, PlanPolygon, combine
from preform.drape.engine.ply import MAX_COUNT, PlyOutline
from preform.drape.engine.polygon import outline_problem
from preform.drape.engine.result import DrapeResult, EnergyField
from preform.drape.engine.settings import DrapeSettings
from preform.drape.judging.verdict import (
    coverage,
    fabric_law_range,
    first_nonfinite_energy,
    shear_limit_notes,
)
from preform.drape.judging.wrinkling import Wrinkling, wrinkle_limits, wrinkling
from preform.shear.surrogate import surrogate
from preform.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene
    from preform.yamlsource import Document, SourceError

MM = 1e-3
#: Memory one net node costs while draping, roughly [bytes] (positions, statuses, residuals,
#: cell fields and temporaries); used to say what a refused ply would have needed.
BYTES_PER_NODE = 130


@dataclass(frozen=True)
class DrapedPly:
    """The ``drape`` product: the net and its strain energy under the fabric's law."""

    result: DrapeResult
    energy: EnergyField


def build_surface(scene: Scene, registry: Any) -> Any:
    """The scene's tool surface [m]. The tool's preflight (file type and size of a mesh,
    against ``limits.max_mesh_mb``) runs first, so nothing unsafe is read."""
    tool = scene.tool
    preflight = getattr(tool, "preflight", None)
    if preflight is not None:
        built, problems = preflight(scene.base_dir, scene.limits)
        if problems:
            raise CaseFailure("; ".join(f"tool: {message}" for _, message in problems))
        if built is not None:
            return built
    build = registry.surface_type(tool.surface).build
    try:
        # Builders that take the scene's limits get them (the mesh reader caps its read).
        inspect.signature(build).bind(tool, scene.base_dir, scene.limits)
        args: tuple[Any, ...] = (tool, scene.base_dir, scene.limits)
    except TypeError:
        args = (tool, scene.base_dir)
    try:
        return build(*args)
    except (ValueError, OSError) as error:
        # Readers and builders say what is wrong with the tool in words (file:line for meshes).
        raise CaseFailure(f"tool: {error}") from None


def ply_outline(scene: Scene) -> PlyOutline:
    """The scene's ply outline in the flat [m]."""
    ply = scene.ply
    if ply is None:
        raise ValueError("a drape needs the scene section 'ply'")
    if ply.outline_mm is not None:
        return PlyOutline.polygon(np.asarray(ply.outline_mm, dtype=float) * MM)
    size = ply.size_mm or (1000.0, 1000.0)
    return PlyOutline.rectangle(
        (size[0] * MM, size[1] * MM), offset_m=(-ply.offset_mm[0] * MM, -ply.offset_mm[1] * MM)
    )


def node_budget_problem(outline: PlyOutline, spacing_mm: float, max_nodes: int) -> str | None:
    """Why a ply at ``spacing_mm`` needs too many nodes for ``limits.max_nodes``, or None."""
    ni, nj = outline.grid_shape(spacing_mm * MM)
    needed = ni * nj
    if needed <= max_nodes:
        return None
    if MAX_COUNT in (ni, nj):
        count = "more than 1e+18 net nodes"
        memory = "more memory than any machine has"
    else:
        count = f"{ni:,} × {nj:,} = {float(needed):.3g} net nodes"
        memory = f"about {_bytes(float(needed) * BYTES_PER_NODE)} of memory"
    return (
        f"the ply needs {count} at node spacing {spacing_mm:g} mm, more than "
        f"limits.max_nodes = {max_nodes:,} ({memory}); use a larger ply.node_spacing_mm or a "
        "smaller ply, or raise limits.max_nodes in the scene if the machine has the memory"
    )


def ply_too_coarse_problem(outline: PlyOutline, spacing_mm: float) -> str | None:
    """Why a ply at ``spacing_mm`` has no cell at all (fewer than 2 nodes along a fibre)."""
    ni, nj = outline.grid_shape(spacing_mm * MM)
    if ni >= 2 and nj >= 2:
        return None
    lo, hi = outline.vertices.min(axis=0) / MM, outline.vertices.max(axis=0) / MM
    return (
        f"the node spacing {spacing_mm:g} mm leaves the ply ({hi[0] - lo[0]:g} × "
        f"{hi[1] - lo[1]:g} mm) with {ni} × {nj} node(s), so the net has no cell; use a node "
        "spacing well below the ply's size"
    )


def _bytes(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if n < 1000:
            return f"{n:.3g} {unit}"
        n /= 1000
    return f"{n:.3g} EB"


def drape_settings(scene: Scene, surface: Any) -> DrapeSettings:
    """The scene's drape set-up (SI units), its fidelity knobs resolved once against the tool
    (``preform.base.fidelity``) and carried in it, to be recorded as they ran.

    Raises ``CaseFailure`` when the ply would need more than ``limits.max_nodes`` nodes or has
    no cell at the resolved spacing, before anything of its size is allocated."""
    ply, start = scene.ply, scene.start
    if ply is None or start is None:
        raise ValueError("a drape needs the scene sections 'ply' and 'start'")
    knobs = fidelity.resolve(scene, float(surface.size))
    assert knobs.node_spacing_mm is not None
    outline = ply_outline(scene)
    for problem in (
        node_budget_problem(outline, knobs.node_spacing_mm, scene.limits.max_nodes),
        ply_too_coarse_problem(outline, knobs.node_spacing_mm),
    ):
        if problem is not None:
            raise CaseFailure(problem)
    generators: Any = start.generators
    # Polylines set the orientation and angle themselves.
    angles = (np.radians(start.orientation_deg), np.radians(start.generator_angle_deg))
    if start.generators == "polyline":
        from preform.drape.engine.generators import PlanPolylines

        if start.generator_polylines_mm is None:
            raise ValueError("generators: polyline needs start.generator_polylines_mm")
        first, second = (np.asarray(p, dtype=float) * MM for p in start.generator_polylines_mm)
        generators, angles = PlanPolylines(first, second), (None, None)
    return DrapeSettings(
        node_spacing_m=knobs.node_spacing_mm * MM,
        ply=outline,
        start_xy_m=(start.point_mm[0] * MM, start.point_mm[1] * MM),
        orientation_rad=angles[0],
        generator_angle_rad=angles[1],
        generators=generators,
        trim=scene_part(scene, surface),
        tolerance=knobs.solver_tolerance,
        substeps=knobs.generator_substeps,
        fidelity=knobs,
    )


def scene_part(scene: Scene, surface: Any) -> Part | None:
    """The part the scene makes on ``surface`` [m]: its ``part`` section (the intersection of
    the cuts it gives), else the tool's own part (``surface.part()``, e.g. a bare hemisphere
    above its rim), else None (every cell the net puts on the tool counts whole)."""
    section = scene.part
    parts: list[Part] = []
    area = None
    if section is not None:
        if section.z_min_mm is not None:
            parts.append(HeightCut(section.z_min_mm * MM))
        if section.plan_outline_mm is not None:
            parts.append(PlanPolygon(np.asarray(section.plan_outline_mm, dtype=float) * MM))
        if section.faces is not None:
            parts.append(face_part(surface, section.faces))
        if section.area_mm2 is not None:
            area = section.area_mm2 * MM * MM
    if not parts:
        own = getattr(surface, "part", None)
        if own is None:
            return None
        tool_part: Part = own()
        if area is not None:
            tool_part = dataclasses.replace(cast(Any, tool_part), area_m2=area)
        return tool_part
    part = combine(parts)
    assert part is not None
    if area is not None:
        if dataclasses.is_dataclass(part):
            part = dataclasses.replace(cast(Any, part), area_m2=area)
        else:
            part.area_m2 = area
    return part


def face_part(surface: Any, faces: list[int | str]) -> Part:
    """The part of the named or numbered faces of a tool read from a file (``part.faces``)."""
    select = getattr(surface, "face_part", None)
    if select is None:
        raise CaseFailure(
            "part.faces selects faces of a tool read from a file (tool surface: mesh, an "
            f"STL, OBJ, STEP or IGES file); this tool is a {type(surface).__name__}: use "
            "part.z_min_mm or part.plan_outline_mm"
        )
    try:
        part: Part = select(faces)
    except ValueError as error:
        raise CaseFailure(f"part.{error}") from None
    return part


def start_problem(surface: Any, start_xy_m: tuple[float, float]) -> str | None:
    """Why the start point cannot be put on the tool, or None."""
    xy = np.asarray(start_xy_m, dtype=float).reshape(1, 2)
    points, over = surface.point_at_plan(xy)
    if bool(np.asarray(over)[0]) and np.all(np.isfinite(points[0])):
        return None
    (x0, y0, _), (x1, y1, _) = surface.bounds
    return (
        f"the start point (x, y) = ({xy[0, 0] / MM:.6g}, {xy[0, 1] / MM:.6g}) mm is not over "
        f"the tool, whose plan extent is x {x0 / MM:.6g} … {x1 / MM:.6g} mm, "
        f"y {y0 / MM:.6g} … {y1 / MM:.6g} mm; move start.point_mm onto it"
    )


def judge_drape(
    ctx: CaseContext,
    result: DrapeResult,
    energy: EnergyField,
    surface: Any,
    start_xy_m: tuple[float, float],
    part: Part | None = None,
) -> None:
    """Say what a finished drape is worth through the case context (module docstring):
    ``CaseFailure`` for no cell, no cell in the ``part``, or a non-finite energy, ``partial`` for missing coverage or
    for energy mostly from cells where the fabric would wrinkle, warnings for cells past the
    law's limits."""
    if not result.valid.any():
        d_mm = result.node_spacing / MM
        raise CaseFailure(
            f"the drape has no cell ({result.nodes_placed} node(s) placed): at node spacing "
            f"{d_mm:g} mm the net does not fit on the tool (typical length "
            f"{float(surface.size) / MM:.4g} mm); use a node spacing well below the tool's "
            "size, or check that the ply and start point lie over the tool"
        )
    if not np.any(result.part_weight > 0.0):
        raise CaseFailure(empty_part_reason(result, part))
    why = first_nonfinite_energy(result, energy)
    if why is not None:
        raise CaseFailure(why)
    cover = coverage(result, surface, start_xy_m)
    ctx.summary.update(cover.summary())
    # "complete" in a case summary means what the status means: nothing asked is missing (a
    # ply hanging over the tool's edge is complete; DrapeResult.complete would say it is not).
    ctx.summary["complete"] = cover.complete
    if not cover.complete:
        ctx.partial(cover.reason(), cover.covered_fraction)
    elif cover.fold_zones:
        ctx.warn(cover.fold_warning(), cause="fold zones")
    law = ctx.products["shear_law"]
    limits = fabric_law_range(law, ctx.fabric)
    notes, counts = shear_limit_notes(result, energy, limits)
    ctx.summary.update(counts)
    for message, about in notes:
        ctx.warn(message, **about)
    wrinkles = wrinkling(result, energy.energy_density, wrinkle_limits(limits))
    judge_wrinkling(ctx, wrinkles, cover.covered_fraction)


def empty_part_reason(result: DrapeResult, part: Part | None) -> str:
    """Why a drape with cells has none in its part, in words with where the net lies [mm]: a
    part that selects nothing has no energy, extremes or coverage to report (0 J and a
    coverage of 1 would be a wrong ``ok``)."""
    placed = result.nodes[np.all(np.isfinite(result.nodes), axis=-1)] / MM
    lo, hi = placed.min(axis=0), placed.max(axis=0)
    what = part.describe() if part is not None else "the tool's own part"
    return (
        f"the part ({what}) selects nothing of the drape: none of its "
        f"{int(np.count_nonzero(result.valid))} draped cells lies in it (the net spans "
        f"x {lo[0]:.6g} … {hi[0]:.6g} mm, y {lo[1]:.6g} … {hi[1]:.6g} mm, "
        f"z {lo[2]:.6g} … {hi[2]:.6g} mm); check that the part's fields meet each other and "
        "the tool where the ply lies"
    )


def judge_wrinkling(ctx: CaseContext, wrinkles: Wrinkling, covered_fraction: float) -> None:
    """Record a drape's wrinkling (the ``wrinkling`` block and its table columns) and make the
    case partial when its energy comes mostly from cells past a wrinkle limit (the status
    rule, ``preform.drape.judging.wrinkling``); ``covered_fraction`` [-] is the drape's coverage, which
    a partial case records."""
    ctx.summary["wrinkling"] = wrinkles.summary()
    ctx.summary.update(wrinkles.columns())
    if wrinkles.mostly_wrinkle:
        ctx.partial(wrinkles.reason(), covered_fraction)


def record_knobs(ctx: CaseContext, settings: DrapeSettings) -> fidelity.Knobs:
    """Record the fidelity knobs a drape's ``settings`` were resolved with as scalar results of
    the case, and return them."""
    knobs = settings.fidelity
    assert knobs is not None, "settings from drape_settings carry the scene's knobs"
    for key, value in knobs.as_dict().items():
        ctx.summary[key if key == "fidelity" else f"knob_{key}"] = value
    return knobs


def run_surface(ctx: CaseContext) -> dict[str, Any]:
    surface = build_surface(ctx.scene, ctx.registry)
    # A tool read from a file says where it came from (format, unit and whence) and what
    # mesh hygiene repaired (preform.plugins.surfaces.mesh_hygiene): in the summary, and the
    # repairs in words on the console.
    describe = getattr(surface, "summary", None)
    if callable(describe):
        ctx.summary.update(describe())
        hygiene = getattr(surface, "hygiene", None)
        # what was repaired, and what a raised threshold let through unrepaired
        said = [*hygiene.repairs(), *hygiene.cautions()] if hygiene is not None else []
        for line in said:
            ctx.warn(f"tool mesh: {line}", cause="tool mesh")
    return {"surface": surface}


def summed_law(ctx: CaseContext, knobs: fidelity.Knobs) -> Any:
    """The law a drape's energy fields and ``total_energy_J`` are summed with: the law's
    tabulated surrogate unless the fidelity asks for the law itself (energy_table_step_deg 0),
    within its documented error and far cheaper per cell."""
    exact = ctx.products["shear_law"]
    with np.errstate(all="ignore"):
        law = surrogate(exact, knobs.energy_table_step_deg or None)
    if law is not exact and not law.finite:
        law = exact  # a non-finite law is reported by the law itself, at the angle it fails
    return law


def run_drape(ctx: CaseContext) -> dict[str, Any]:
    surface = ctx.products["surface"]
    study = ctx.products.get("energy_vs_angle")  # a search's, resolved for its drapes
    settings = study.settings if study is not None else drape_settings(ctx.scene, surface)
    law = summed_law(ctx, record_knobs(ctx, settings))
    optimum = ctx.products.get("optimum")
    if optimum is not None:
        # the search chose the angle, and may have chosen the orientation, start or generators
        chosen = ("orientation_rad", "start_xy_m", "generators")
        settings = dataclasses.replace(
            settings,
            generator_angle_rad=float(optimum["generator_angle_rad"]),
            **{key: optimum[key] for key in chosen if optimum.get(key) is not None},
        )
    try:
        result = drape(surface, settings)
    except DrapeError as error:
        raise CaseFailure(f"the drape cannot start: {error}") from None
    part = cast(Part | None, settings.trim)  # drape_settings trims to the scene's part
    relaxed = optimum.get("relaxed_nodes") if optimum is not None else None
    if relaxed is not None and np.shape(relaxed) == result.nodes.shape:
        with np.errstate(all="ignore"):
            kinematic = energy_field(result, law)
        # the same sums as the relaxation reported (preform.optimise.search_steps._run_relax)
        ctx.summary["kinematic_total_energy_J"] = kinematic.total_energy
        result = relaxed_result(result, np.asarray(relaxed, dtype=float), part)
        ctx.summary["result_net"] = "relaxed"
    elif optimum is not None:
        ctx.summary["result_net"] = "kinematic"
    with np.errstate(all="ignore"):
        energy = energy_field(result, law)
    ctx.summary.update(summary(result, energy, part))
    if part is not None:
        ctx.summary["part"] = part.describe()
    ctx.summary["generator_angle_deg"] = float(np.degrees(result.generator_angle))
    judge_drape(ctx, result, energy, surface, settings.start_xy_m, part)
    area = getattr(part, "area_m2", None)
    if area is not None:
        # Part area the net does not cover, and how much of it the missing cells explain (by
        # cause, in the coverage summary); the rest lies where the ply does not reach.
        bare = max(0.0, float(area) - float(ctx.summary["part_draped_area_m2"]))
        explained = sum(
            float(v) for k, v in ctx.summary.items() if k.startswith("uncovered_area_m2_")
        )
        ctx.summary["uncovered_part_area_m2"] = bare
        ctx.summary["uncovered_part_area_m2_beyond_ply"] = max(0.0, bare - explained)
    return {"drape": DrapedPly(result, energy)}


def relaxed_result(kinematic: DrapeResult, relaxed_nodes: Any, part: Part | None) -> DrapeResult:
    """The drape result of a relaxed net: the relaxed positions where relaxation moved nodes
    (every corner of a counted cell), the kinematic ones elsewhere, and the cell fields
    recomputed from them. Cells outside the part that touch it mix relaxed and kinematic
    corners; they carry no weight in the part's energy and extremes."""
    nodes = np.where(np.isfinite(relaxed_nodes), relaxed_nodes, kinematic.nodes)
    fields = cell_fields(nodes, kinematic.status, trim=part)
    info = {**kinematic.info, "net": "relaxed"}
    return dataclasses.replace(kinematic, nodes=nodes, info=info, **fields)


def _needs_optimum(scene: Scene) -> tuple[str, ...]:
    return ("optimum",) if scene.search is not None else ()


def scene_problems(scene: Scene, doc: Document, registry: Any) -> list[SourceError]:
    """Problems a scene's tool, ply, start and part have before anything runs, located (the
    drape step's ``check``).

    Cheap checks only: an outline that crosses itself or encloses nothing
    (``preform.drape.engine.polygon``), the ply's node count against ``limits.max_nodes``
    (arithmetic, no array), a node spacing that leaves the ply or the tool without a cell, the
    start point outside the ply or off the tool, generator polylines, a part beside the tool,
    and the tool's own preflight (an analytic tool is built, microseconds; a mesh file is
    checked for existence, type and size, not read).
    """
    outlines = (
        (("ply", "outline_mm"), scene.ply.outline_mm if scene.ply else None),
        (("part", "plan_outline_mm"), scene.part.plan_outline_mm if scene.part else None),
    )
    errors = [
        doc.error(at, problem, at_value=True)
        for at, outline in outlines
        if outline is not None and (problem := outline_problem(outline, "mm")) is not None
    ]
    if errors:
        return errors  # nothing else is defined on an outline without an inside
    surface = None
    preflight = getattr(scene.tool, "preflight", None)
    if preflight is not None:
        surface, problems = preflight(scene.base_dir, scene.limits)
        errors += [doc.error(("tool", *where), message) for where, message in problems]
    errors += _generator_problems(scene, doc)
    if surface is not None:
        errors += _empty_part_problems(scene, surface, doc)
    ply = scene.ply
    if ply is None:
        return errors
    outline = ply_outline(scene)
    spacing_at: tuple[str | int, ...] = ("ply", "node_spacing_mm")
    spacing = ply.node_spacing_mm
    if spacing is None and surface is not None:
        # The preset chooses d from the tool's size: check the ply against that d.
        spacing = fidelity.resolve(scene, float(surface.size)).node_spacing_mm
        spacing_at = ("ply",)
    if spacing is not None:
        problem = node_budget_problem(outline, spacing, scene.limits.max_nodes)
        if problem is not None:
            return [*errors, doc.error(spacing_at, problem)]
        problem = ply_too_coarse_problem(outline, spacing)
        if problem is not None:
            errors.append(doc.error(spacing_at, problem))
        elif surface is not None and spacing * 1e-3 > float(surface.size):
            errors.append(
                doc.error(
                    spacing_at,
                    f"the node spacing {spacing:g} mm is larger than the tool (its typical "
                    f"length is {float(surface.size) * 1e3:.4g} mm), so the net has no cell on "
                    "it; use a spacing well below the tool's size (the standard preset uses "
                    "1/40 of it)",
                ),
            )
    if not bool(outline.contains(np.zeros((1, 2)), 1e-9)[0]):
        at = ("ply", "outline_mm") if ply.outline_mm is not None else ("ply", "offset_mm")
        errors.append(
            doc.error(
                at,
                "the start point (the flat origin) lies outside the ply; the generators run "
                "through it, so it must be fabric",
            )
        )
    if surface is not None and scene.start is not None:
        point = scene.start.point_mm
        problem = start_problem(surface, (point[0] * 1e-3, point[1] * 1e-3))
        if problem is not None:
            errors.append(doc.error(("start", "point_mm"), problem))
    return errors


def _generator_problems(scene: Scene, doc: Document) -> list[SourceError]:
    """Polyline generators without their polylines, or with too few or too many vertices."""
    start = scene.start
    if start is None or start.generators != "polyline":
        return []
    if start.generator_polylines_mm is None:
        return [
            doc.error(
                ("start", "generators"),
                "generators: polyline needs start.generator_polylines_mm (the two plan "
                "polylines, each through the start point)",
            )
        ]
    return [
        doc.error(
            ("start", "generator_polylines_mm", k),
            f"a generator polyline needs 2 to {MAX_POLYGON_VERTICES:,} vertices, got {len(line):,}",
        )
        for k, line in enumerate(start.generator_polylines_mm)
        if not 2 <= len(line) <= MAX_POLYGON_VERTICES
    ]


def _empty_part_problems(scene: Scene, surface: Any, doc: Document) -> list[SourceError]:
    """A ``part`` section that selects nothing of a built (analytic) tool, known from the
    tool's bounds [m]: a height cut above its top, a plan outline wholly beside its plan.
    What only the drape can tell (a cut and an outline that miss each other on the tool, a
    mesh tool's part) fails the case after draping (:func:`judge_drape`)."""
    section = scene.part
    if section is None:
        return []
    (x0, y0, _), (x1, y1, z1) = (tuple(float(c) for c in corner) for corner in surface.bounds)
    errors = []
    # strictly above: a cut at the top of a flat or flat-topped tool (a plane, a frustum)
    # selects its top face; at a dome's apex a point, which the drape then finds empty
    if section.z_min_mm is not None and section.z_min_mm * 1e-3 > z1:
        errors.append(
            doc.error(
                ("part", "z_min_mm"),
                f"the height cut z ≥ {section.z_min_mm:g} mm lies above the tool, whose "
                f"top is at z = {z1 * 1e3:.6g} mm, so the part selects nothing; lower the cut",
            )
        )
    if section.plan_outline_mm is not None:
        xy = np.asarray(section.plan_outline_mm, dtype=float) * 1e-3
        (px0, py0), (px1, py1) = xy.min(axis=0), xy.max(axis=0)
        if px1 <= x0 or px0 >= x1 or py1 <= y0 or py0 >= y1:
            errors.append(
                doc.error(
                    ("part", "plan_outline_mm"),
                    f"the part's plan outline (x {px0 * 1e3:.6g} … {px1 * 1e3:.6g} mm, "
                    f"y {py0 * 1e3:.6g} … {py1 * 1e3:.6g} mm) lies beside the tool, whose plan "
                    f"extent is x {x0 * 1e3:.6g} … {x1 * 1e3:.6g} mm, y {y0 * 1e3:.6g} … "
                    f"{y1 * 1e3:.6g} mm, so the part selects nothing",
                )
            )
    return errors


STEPS = [
    Step(
        "surface",
        ("surface",),
        (),
        "1",
        run_surface,
        "Build the scene's tool surface.",
        scene_sections=("tool",),
    ),
    Step(
        "drape",
        ("drape",),
        ("surface", "shear_law"),
        "2",  # 2: the energy field from the law's table unless the fidelity says exact
        run_drape,
        "Pin-jointed net on the tool, its shear field and strain energy.",
        scene_sections=("tool", "ply", "start"),
        extra_requires=_needs_optimum,
        sections=dict.fromkeys(("tool", "ply", "start", "part")),
        check=scene_problems,
    ),
]
