"""Pipeline steps of a layup: drape every ply on the tool offset by the plies below, then the
stack's maps, figure and solver sections.

The ``layup`` step runs each ply as a drape case of its own (``preform.stack.plies``: the
scene with the ply's start, orientation, angle, outline and outputs) inside the layup's case,
with the same planned steps a ``pipeline run`` of that scene would run, writing the ply's
outputs and ``summary.json`` into a sub-folder named after the ply. Ply k (from 0 at the tool)
lies on the tool offset by plies 0 … k−1 (``preform.drape.engine.offset``):

- an analytic tool is offset exactly by one distance, the sum of the plies' area-weighted mean
  thicknesses over their parts (``offset_mm`` of the ply); where a ply below varies in
  thickness (a locked, thickened region) or stops short (a drop-off), that mean is what the
  next ply sees, and a warning says how far the ply's thickness strays from it (a mesh tool is
  offset place by place);
- a mesh tool's vertices move along their normals by the stack's thickness at each vertex
  (``preform.stack.maps``), drop-offs and thickened regions included; an offset that folds
  over itself (a concave radius below the stack's thickness) fails the case there, in words.

What the stack is worth: a ply that fails stops the stack (the plies above it cannot be
placed) and fails the case naming the ply; a partial ply makes the stack partial with the ply's
reasons; ply warnings are the stack's, prefixed with the ply. ``ok`` only when every ply is.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from preform.base.status import CaseFailure, CaseStatus
from preform.stack.maps import PlyLayer, StackMaps, reference_ply, stack_at, stations
from preform.stack.plies import layup_of, ply_scene
from preform.stack.validate import layup_problems
from preform.step import CaseContext, Step

MM = 1e-3


@dataclass(frozen=True)
class Stack:
    """The ``layup`` product: the draped plies (tool side first) and the stack read at its
    stations. ``plies_products`` keeps each ply's case products (its ``drape``, ``thickness``,
    ``mesh_mapping`` when asked)."""

    layers: tuple[PlyLayer, ...]
    maps: StackMaps
    plies_products: tuple[dict[str, Any], ...]
    #: How the tool was offset for the plies above the first (``preform.drape.engine.offset``).
    offset_method: str


def _thickness_model(ply_ctx: CaseContext) -> Any:
    model = ply_ctx.products.get("thickness")
    if model is None:
        from preform.drape.properties.thickness import thickness_model

        export = ply_ctx.scene.export
        nominal = export.nominal_thickness_mm if export is not None else None
        model = thickness_model(ply_ctx.fabric, nominal)
    return model


def _layer(ply_ctx: CaseContext, name: str, orientation_deg: float, offset_mm: float) -> PlyLayer:
    """The stack's view of a draped ply (thickness, fraction and wrinkling per cell)."""
    from preform.drape.judging.verdict import fabric_law_range
    from preform.drape.judging.wrinkling import wrinkle_limits

    draped = ply_ctx.products["drape"]
    result = draped.result
    model = _thickness_model(ply_ctx)
    if model.reference_mm is None:
        raise CaseFailure(
            f"ply {name}: the thickness of {ply_ctx.fabric.name} is not known ({model.reference}), "
            "so the plies above it cannot be placed; give the ply's thickness_mm"
        )
    valid = np.asarray(result.valid, dtype=bool)
    shear = np.where(valid, np.asarray(result.shear, dtype=float), 0.0)
    thickness = np.where(valid, float(model.reference_mm) * model.ratio(shear), np.nan)
    if model.response is not None:
        fraction = np.where(valid, model.response.at(shear)[1], np.nan)
    else:
        # a fabric without a sheared cell keeps its fibre volume fraction (the model's name)
        built = dict(ply_ctx.fabric.derived()).get("fibre_volume_fraction")
        value = float(built) if isinstance(built, int | float) else np.nan
        fraction = np.where(valid, value, np.nan)
    law = ply_ctx.products["shear_law"]
    wrinkles = np.zeros(shear.shape, dtype=bool)
    for limit in wrinkle_limits(fabric_law_range(law, ply_ctx.fabric)):
        wrinkles |= limit.past(shear)
    return PlyLayer(
        name=name,
        fabric=ply_ctx.fabric.name,
        orientation_deg=orientation_deg,
        result=result,
        thickness_mm=thickness,
        fibre_volume_fraction=fraction,
        wrinkles=wrinkles & valid,
        nominal_thickness_mm=float(model.reference_mm),
        offset_mm=offset_mm,
        status=CaseStatus.OK.value if not ply_ctx.partial_reasons else CaseStatus.PARTIAL.value,
    )


def _run_ply(ply_ctx: CaseContext) -> dict[str, float]:
    """Run the planned steps of a ply's scene in its context (as ``execute_case`` does);
    returns each step's time [s]. Raises what the steps raise."""
    from preform.pipeline.planner import plan
    from preform.pipeline.runner import non_finite_values

    times: dict[str, float] = {}
    for step in plan(ply_ctx.scene, ply_ctx.registry):
        if all(p in ply_ctx.products for p in step.provides):
            continue  # the offset tool is given
        t0 = time.perf_counter()
        out = dict(step.run(ply_ctx))
        bad = non_finite_values(ply_ctx.summary)
        if bad:
            raise CaseFailure(f"step {step.name!r} gave non-finite numbers: " + "; ".join(bad[:10]))
        ply_ctx.products.update(out)
        if step.writes_files:
            for product in step.provides:
                value = out[product]
                ply_ctx.files.extend([value] if isinstance(value, str) else list(value))
        times[step.name] = time.perf_counter() - t0
    return times


def _offset_for(
    tool: Any, layers: list[PlyLayer], mesh_points_mm: Any
) -> tuple[Any, float, str, list[str]]:
    """The tool under the next ply: (surface, largest offset [mm], method, warnings)."""
    from preform.drape.engine.offset import OffsetError, is_mesh, offset_tool

    if not layers:
        return tool, 0.0, "none (the tool itself)", []
    notes: list[str] = []
    try:
        if is_mesh(tool):
            below = stack_at(layers, mesh_points_mm).total_thickness_mm
            made = offset_tool(tool, below * MM)
        else:
            h_mm = sum(layer.mean_thickness_mm() for layer in layers)
            for layer in layers:
                lo, hi = layer.thickness_range_mm()
                mean = layer.mean_thickness_mm()
                if hi - lo > 0.01 * mean:
                    notes.append(
                        f"ply {layer.name} varies in thickness over its part ({lo:.4g} … "
                        f"{hi:.4g} mm); the analytic tool under the plies above is offset by "
                        f"its mean {mean:.4g} mm (give the tool as a mesh for a per-place "
                        "offset)"
                    )
            made = offset_tool(tool, h_mm * MM)
    except OffsetError as error:
        raise CaseFailure(str(error)) from None
    return made.surface, made.distance_max_m / MM, made.method, notes


def run_layup(ctx: CaseContext) -> dict[str, Any]:
    from preform.pipeline.rundir import write_json
    from preform.pipeline.runner import folder_name

    scene = ctx.scene
    layup = layup_of(scene)
    fabrics = ctx.products.get("layup_fabrics") or {ctx.fabric.name: ctx.fabric}
    tool = ctx.products["surface"]
    names = layup.ply_names()
    mesh_points = np.asarray(tool.vertices, dtype=float) / MM if hasattr(tool, "vertices") else None
    layers: list[PlyLayer] = []
    kept: list[dict[str, Any]] = []
    records: list[dict[str, Any]] = []
    method = "none"
    for k, ply in enumerate(layup.plies):
        name = names[k]
        try:
            surface, offset_mm, how, notes = _offset_for(tool, layers, mesh_points)
        except CaseFailure as unplaced:
            ctx.summary["plies"] = records
            raise CaseFailure(
                f"ply {k + 1} of {len(layup.plies)} ({name}) cannot be placed: {unplaced}"
            ) from None
        if k:
            method = how
        for note in notes:
            ctx.warn(note)
        folder = folder_name(name)
        ply_ctx = CaseContext(
            fabric=fabrics[ply.fabric],
            scene=ply_scene(scene, k, ctx.registry),
            registry=ctx.registry,
            case_dir=ctx.case_dir / folder,
        )
        ply_ctx.case_dir.mkdir(parents=True, exist_ok=True)
        ply_ctx.products["surface"] = surface
        ply_ctx.summary["offset_mm"] = offset_mm
        record: dict[str, Any] = {
            "ply": k + 1,
            "name": name,
            "fabric": ply.fabric,
            "orientation_deg": float(ply.orientation_deg),
            "offset_mm": offset_mm,
        }
        started = time.perf_counter()
        error: str | None = None
        try:
            record["step_times_s"] = _run_ply(ply_ctx)
            ply_ctx.products["thickness"] = _thickness_model(ply_ctx)
            layers.append(_layer(ply_ctx, name, float(ply.orientation_deg), offset_mm))
            status = layers[-1].status
        except CaseFailure as exc:
            status, error = CaseStatus.FAILED.value, str(exc)
        record.update(
            status=status,
            error=error,
            reasons=list(ply_ctx.partial_reasons),
            warnings=list(ply_ctx.warnings),
            wall_time_s=time.perf_counter() - started,
            files=list(ply_ctx.files),
        )
        for key in ("generator_angle_deg", "total_energy_J", "max_abs_shear_deg"):
            if key in ply_ctx.summary:
                record[key] = ply_ctx.summary[key]
        write_json(ply_ctx.case_dir / "summary.json", {**ply_ctx.summary, **record})
        ctx.files.extend(f"{folder}/{f}" for f in [*ply_ctx.files, "summary.json"])
        records.append(record)
        kept.append(dict(ply_ctx.products))
        for warning in ply_ctx.warnings:
            ctx.warn(f"ply {name}: {warning}")
        if error is not None:
            ctx.summary["plies"] = records
            above = len(layup.plies) - k - 1
            rest = f"; the {above} ply(ies) above it were not draped" if above else ""
            raise CaseFailure(f"ply {k + 1} of {len(layup.plies)} ({name}) failed: {error}{rest}")
        for reason in ply_ctx.partial_reasons:
            ctx.partial(f"ply {name}: {reason}", ply_ctx.summary.get("covered_fraction"))
    points, area = stations(layers)
    maps = stack_at(layers, points, area, own=reference_ply(layers))
    ctx.summary["plies"] = records
    ctx.summary["stack_offset_method"] = method
    ctx.summary.update(maps.summary())
    ctx.summary["stack"] = stack_words(records)
    return {"layup": Stack(tuple(layers), maps, tuple(kept), method)}


def stack_words(records: list[dict[str, Any]]) -> str:
    """What the stack is, in words: how many plies are ok, and which are not and why."""
    n = len(records)
    ok = sum(1 for r in records if r["status"] == CaseStatus.OK.value)
    if ok == n:
        return f"all {n} plies ok"
    worse = "; ".join(
        f"ply {r['ply']} ({r['name']}) {r['status']}"
        + (f": {r['error'] or '; '.join(r['reasons'])}" if r["error"] or r["reasons"] else "")
        for r in records
        if r["status"] != CaseStatus.OK.value
    )
    return f"{ok} of {n} plies ok, so the stack is not: {worse}"


def write_stack_csv(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.csv_columns import write_csv_columns

    stack: Stack = ctx.products["layup"]
    maps = stack.maps
    columns: dict[str, Any] = {
        "x_mm": maps.points_mm[:, 0],
        "y_mm": maps.points_mm[:, 1],
        "z_mm": maps.points_mm[:, 2],
        "area_mm2": maps.area_mm2,
        "total_thickness_mm": maps.total_thickness_mm,
        "fibre_volume_fraction": maps.stack_fibre_volume_fraction,
        "plies_present": maps.plies_present,
        "plies_wrinkling": maps.plies_wrinkling,
    }
    for k, name in enumerate(maps.ply_names):
        columns[f"thickness_mm_{name}"] = maps.thickness_mm[:, k]
    write_csv_columns(columns, ctx.case_dir / "stack.csv")
    return {"stack_csv": "stack.csv"}


def write_stack_thickness_png(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.fig_stack import stack_figure
    from preform.stack.maps import reference_ply

    stack: Stack = ctx.products["layup"]
    # the stations' own cells, drawn as one mesh (preform.export.fig_stack)
    layer = stack.layers[reference_ply(stack.layers)]
    net = (1e3 * np.asarray(layer.result.nodes, dtype=float), layer.region)
    stack_figure(stack.maps, ctx.case_dir / "stack_thickness.png", ctx.scene.name, net)
    return {"stack_thickness_png": "stack_thickness.png"}


def stack_deck_writer(target: str) -> Any:
    """The exporter writing the stack's composite sections for one solver (``abaqus``,
    ``calculix``, ``lsdyna``, ``ansys``; ``preform.export.stack_files``)."""

    def write(ctx: CaseContext) -> dict[str, Any]:
        from preform.export.stack_files import write_stack_files

        sections = ctx.products["stack_sections"]
        written = write_stack_files(sections, ctx.case_dir, [target], title=ctx.scene.name)
        return {f"stack_{target}": written[target]}

    return write


def run_stack_sections(ctx: CaseContext) -> dict[str, Any]:
    """Each ply's drape mapped onto the scene's FE mesh (``export.mesh``), tool side first:
    the ``StackSections`` the solver writers take, and ``stack_elements.csv``."""
    from preform.export.csv_columns import write_csv_columns
    from preform.export.export_steps import export_options, scene_fe_mesh
    from preform.export.fe_mapping import map_to_mesh
    from preform.export.ply_stack import PlySection, StackSections

    options = export_options(ctx)
    mesh = scene_fe_mesh(ctx, "the stack")
    stack: Stack = ctx.products["layup"]
    sections = []
    columns: dict[str, Any] = {}
    total = np.zeros(mesh.n_elements)
    count = np.zeros(mesh.n_elements, dtype=np.int64)
    for layer, products in zip(stack.layers, stack.plies_products, strict=True):
        model = products["thickness"]  # the ply's one thickness (run_layup keeps it)
        draped = products["drape"]
        d_mm = float(draped.result.node_spacing) / MM
        gap = (options.max_gap_mm or d_mm) + layer.offset_mm + layer.nominal_thickness_mm
        mapping = map_to_mesh(
            draped.result,
            mesh,
            model.applied(draped.result, draped.energy),
            reference_direction=options.reference_direction,
            nominal_thickness_mm=layer.nominal_thickness_mm,
            thickness_reference=model.reference,
            thickness_cap_ratio=options.thickness_cap_ratio,
            max_gap_mm=gap,
        )
        sections.append(PlySection(name=layer.name, material=layer.fabric, mapping=mapping))
        total += np.where(mapping.covered, np.nan_to_num(mapping.thickness_mm), 0.0)
        count += mapping.covered
        columns[f"angle_u_deg_{layer.name}"] = mapping.angle_u_deg
        columns[f"thickness_mm_{layer.name}"] = mapping.thickness_mm
    _bare_elements_judged(ctx, mesh, count, stack)  # before any file: a failure writes none
    ids = getattr(mesh, "element_ids", None)
    table: dict[str, Any] = {
        "element": ids if ids is not None else np.arange(1, mesh.n_elements + 1),
        "plies_present": count,
        "total_thickness_mm": total,
        **columns,
    }
    write_csv_columns(table, ctx.case_dir / "stack_elements.csv")
    ctx.files.append("stack_elements.csv")
    ctx.summary["stack_elements"] = int(mesh.n_elements)
    ctx.summary["stack_elements_all_plies"] = int(np.count_nonzero(count == len(sections)))
    ctx.summary["stack_elements_no_ply"] = int(np.count_nonzero(count == 0))
    stack_sections = StackSections(plies=tuple(sections))
    # the counts the decks state (bare elements, each ply's drop-offs), not the element lists
    ctx.summary["stack_sections_summary"] = {
        k: v for k, v in stack_sections.summary().items() if not k.endswith("_ids")
    }
    return {"stack_sections": stack_sections}


def _bare_elements_judged(ctx: CaseContext, mesh: Any, count: Any, stack: Stack) -> None:
    """Elements no ply covers, judged as a single ply's uncovered elements are: none covered
    fails the case (every section would be missing: a mesh in another unit or place), some
    bare make it partial with covered_fraction = elements with a ply / elements. A ply absent
    where another is (a drop-off) is the layup's design, not a gap."""
    from preform.export.export_steps import no_element_covered

    n = int(mesh.n_elements)
    bare = np.nonzero(count == 0)[0]
    if not bare.size:
        return
    if bare.size == n:
        raise CaseFailure(
            "no ply covers any element: "
            + no_element_covered(stack.layers[0].result, mesh, mesh.source_name)
        )
    ids = np.asarray(mesh.element_ids)[bare].tolist()
    first = ", ".join(str(e) for e in ids[:10]) + (" ..." if len(ids) > 10 else "")
    ctx.partial(
        f"the stack covers {n - bare.size} of {n} elements of {mesh.source_name}; {bare.size} "
        f"with no ply (ids {first}) are listed in the decks (the bare set) with no section",
        (n - bare.size) / n,
    )


STEPS = [
    Step(
        "layup",
        ("layup",),
        ("surface",),
        "1",
        run_layup,
        "Every ply of the layup draped on the tool offset by the plies below, each in a "
        "sub-folder with its outputs; the stack's maps.",
        scene_sections=("tool", "layup"),
        sections={"layup": None},
        check=layup_problems,
    ),
    Step(
        "stack_sections",
        ("stack_sections",),
        ("layup",),
        "1",
        run_stack_sections,
        "Each ply mapped onto the FE mesh (export.mesh), tool side first: the solver's "
        "composite sections; stack_elements.csv",
        scene_sections=("layup", "export"),
    ),
]

EXPORTERS = [
    Step.exporter(
        "stack_csv",
        ("layup",),
        write_stack_csv,
        "stack.csv: the stack at its stations (total thickness, Vf, plies present and "
        "wrinkling, each ply's thickness)",
    ),
    Step.exporter(
        "stack_thickness_png",
        ("layup",),
        write_stack_thickness_png,
        "stack_thickness.png: the stack's total thickness and plies present, top view",
    ),
    *(
        Step.exporter(
            f"stack_{target}",
            ("stack_sections",),
            stack_deck_writer(target),
            f"{file}: the stack's composite sections per element for {solver} (a layer per "
            "ply present, its own fibre direction and thickness; drop-offs left out)",
        )
        for target, file, solver in (
            ("abaqus", "stack_abaqus.inp", "Abaqus"),
            ("calculix", "stack_calculix.inp", "CalculiX (ccx applies it)"),
            ("lsdyna", "stack_lsdyna.k", "LS-DYNA"),
            ("ansys", "stack_ansys.mac", "ANSYS"),
        )
    ),
]
