"""Pipeline steps of the downstream exports: the drape mapped onto the user's FE mesh, and the
cutting pattern. Outputs a scene can ask for:

| output | files | needs |
|---|---|---|
| ``mesh_mapping`` | (none: the mapping, for the others) | ``export.mesh`` |
| ``element_table`` | ``elements.csv`` (one row per element, mm, deg) | ``export.mesh`` |
| ``element_vtu`` | ``elements.vtu`` (the user's mesh with the same fields, mm) | ``export.mesh`` |
| ``abaqus_include`` | ``drape_abaqus.inc`` | ``export.mesh`` |
| ``lsdyna_include`` | ``drape_lsdyna.k`` (``export.lsdyna_form``: beta or composite) | ``export.mesh`` |
| ``ansys_macro`` | ``drape_ansys.mac`` (LOCAL + ESYS, two-layer section per element) | ``export.mesh`` |
| ``calculix_include`` | ``drape_calculix.inp`` (explicit *ORIENTATION + *SHELL SECTION per element) | ``export.mesh`` |
| ``cut_pattern`` | ``cut_pattern.dxf``, ``.svg``, ``.csv`` (mm; darts, cuts) | the drape |

Status: elements of the mesh the drape does not cover make the case ``partial`` (the share of
elements covered is the covered fraction) and are listed in every file; elements above the
compaction cap are a warning. A mesh that cannot be read fails the case with the file's error
(located to its line: a duplicate node or element label, a non-finite coordinate); a mesh none
of whose elements the drape covers fails it with how far the mesh lies from the drape.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.export_section import ExportSection
from preform.base.status import CaseFailure
from preform.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene
    from preform.yamlsource import Document, SourceError


def export_options(ctx: CaseContext) -> ExportSection:
    section = getattr(ctx.scene, "export", None)
    return section if section is not None else ExportSection()


def no_element_covered(result: Any, mesh: Any, name: str) -> str:
    """Why a mapping covers none of the mesh's elements, in words: how far apart the FE mesh's
    and the draped net's bounding boxes are [mm] (0 when they overlap: the mesh then lies
    inside the drape's box but off its surface, e.g. in another unit). Every value of such a
    mapping would be missing: a failure, not a partial export."""
    nodes = np.asarray(result.nodes, dtype=float)
    placed = nodes[np.all(np.isfinite(nodes), axis=-1)] * 1e3
    points = np.asarray(mesh.points, dtype=float)
    net_lo, net_hi = placed.min(axis=0), placed.max(axis=0)
    mesh_lo, mesh_hi = points.min(axis=0), points.max(axis=0)
    gap = np.maximum(0.0, np.maximum(mesh_lo - net_hi, net_lo - mesh_hi))
    offset = float(np.linalg.norm(gap))

    def box(lo: Any, hi: Any) -> str:
        return ", ".join(f"{c} {a:.6g} … {b:.6g}" for c, a, b in zip("xyz", lo, hi, strict=True))

    where = (
        f"the boxes are {offset:.6g} mm apart"
        if offset > 0
        else "the boxes overlap, but no element lies on the draped surface"
    )
    return (
        f"the drape covers none of the {mesh.n_elements} elements of {name}: {where} (mesh "
        f"{box(mesh_lo, mesh_hi)} mm; drape {box(net_lo, net_hi)} mm); check the mesh's "
        "position and export.mesh_unit_mm"
    )


def scene_fe_mesh(ctx: CaseContext, what: str = "the drape") -> Any:
    """The scene's FE mesh (``export.mesh``, relative to the scene's folder, in its unit), or
    a ``CaseFailure`` saying what is wrong with it; ``what`` is what would be mapped onto it."""
    from preform.export.shell_mesh import read_shell_mesh

    options = export_options(ctx)
    if options.mesh is None:
        raise CaseFailure(f"export.mesh: the scene names no FE mesh to map {what} onto")
    path = Path(ctx.scene.base_dir) / options.mesh
    try:
        return read_shell_mesh(path, unit_mm=options.mesh_unit_mm)
    except (ValueError, OSError) as error:
        raise CaseFailure(f"export.mesh: {error}") from None


def run_mesh_mapping(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.fe_mapping import map_to_mesh

    options = export_options(ctx)
    mesh = scene_fe_mesh(ctx)
    ply = ctx.products["drape"]
    # the case's one thickness (preform.drape.properties.thickness): its model and its t0
    thickness = ctx.products["thickness"]
    mapping = map_to_mesh(
        ply.result,
        mesh,
        thickness.applied(ply.result, ply.energy),
        reference_direction=options.reference_direction,
        nominal_thickness_mm=thickness.reference_mm,
        thickness_reference=thickness.reference,
        thickness_cap_ratio=options.thickness_cap_ratio,
        max_gap_mm=options.max_gap_mm,
    )
    summary = mapping.summary()
    for key in (
        "elements",
        "elements_covered",
        "elements_uncovered",
        "elements_past_locking",
        "elements_past_failure",
        "elements_above_thickness_cap",
        "max_thickness_ratio",
    ):
        if key in summary:
            ctx.summary[f"mesh_{key}"] = summary[key]
    uncovered = summary["elements_uncovered"]
    if summary["elements"] and not summary["elements_covered"]:
        # the mesh by its file name, as the decks name it: a summary goes to other machines too
        raise CaseFailure(no_element_covered(ply.result, mesh, mesh.source_name))
    if uncovered:
        first = ", ".join(str(e) for e in summary["uncovered_element_ids"][:10])
        more = " ..." if uncovered > 10 else ""
        ctx.partial(
            f"the drape covers {summary['elements_covered']} of {summary['elements']} "
            f"elements of {mesh.source_name}; {uncovered} uncovered (ids {first}{more}) are listed "
            "in the exports and given no value",
            summary["covered_fraction"],
        )
    capped = summary["elements_above_thickness_cap"]
    if capped:
        ctx.warn(
            f"{capped} element(s) of {mesh.source_name} have t/t0 above the compaction cap "
            f"{options.thickness_cap_ratio:g} (up to {summary['max_thickness_ratio']:.3g}); "
            "the thickness is reported as computed, not capped"
        )
    return {"mesh_mapping": mapping}


def write_element_table_step(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.element_table import write_element_table

    write_element_table(ctx.products["mesh_mapping"], ctx.case_dir / "elements.csv")
    return {"element_table": "elements.csv"}


def write_element_vtu_step(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.mapped_vtu import write_mapped_vtu

    write_mapped_vtu(ctx.products["mesh_mapping"], ctx.case_dir / "elements.vtu")
    return {"element_vtu": "elements.vtu"}


def write_abaqus_step(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.abaqus import write_abaqus_include

    write_abaqus_include(
        ctx.products["mesh_mapping"],
        ctx.case_dir / "drape_abaqus.inc",
        prefix=export_options(ctx).prefix,
        title=f"{ctx.fabric.name}, scene {ctx.scene.name}",
    )
    return {"abaqus_include": "drape_abaqus.inc"}


def write_lsdyna_step(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.lsdyna import write_lsdyna_composite, write_lsdyna_include

    options = export_options(ctx)
    title = f"{ctx.fabric.name}, scene {ctx.scene.name}"
    path = ctx.case_dir / "drape_lsdyna.k"
    if options.lsdyna_form == "composite":
        try:
            write_lsdyna_composite(
                ctx.products["mesh_mapping"],
                path,
                part_id=options.part_id,
                materials=options.layer_materials,
                u_fraction=options.u_layer_fraction,
                title=title,
            )
        except ValueError as error:
            raise CaseFailure(f"export.lsdyna_form: {error}") from None
    else:
        write_lsdyna_include(
            ctx.products["mesh_mapping"], path, part_id=options.part_id, title=title
        )
    return {"lsdyna_include": "drape_lsdyna.k"}


def write_ansys_step(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.ansys import write_ansys_macro

    options = export_options(ctx)
    write_ansys_macro(
        ctx.products["mesh_mapping"],
        ctx.case_dir / "drape_ansys.mac",
        prefix=options.prefix,
        materials=options.layer_materials,
        u_fraction=options.u_layer_fraction,
    )
    return {"ansys_macro": "drape_ansys.mac"}


def write_calculix_step(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.calculix import write_calculix_include

    try:
        write_calculix_include(
            ctx.products["mesh_mapping"],
            ctx.case_dir / "drape_calculix.inp",
            prefix=export_options(ctx).prefix,
            title=f"{ctx.fabric.name}, scene {ctx.scene.name}",
        )
    except ValueError as error:
        raise CaseFailure(f"calculix_include: {error}") from None
    return {"calculix_include": "drape_calculix.inp"}


def write_cut_pattern_step(ctx: CaseContext) -> dict[str, Any]:
    from preform.drape.steps import scene_part
    from preform.export.cut_pattern import (
        cut_pattern,
        write_cut_pattern_csv,
        write_cut_pattern_dxf,
        write_cut_pattern_svg,
    )

    ply = ctx.products["drape"]
    options = export_options(ctx)
    pattern = cut_pattern(
        ply.result,
        seam_allowance_mm=options.seam_allowance_mm,
        ply_name=f"{ctx.fabric.name} ({ctx.scene.name})",
        darts_mm=[(d.apex_mm, d.mouth_mm) for d in options.darts],
        cuts_mm=[(c.from_mm, c.to_mm) for c in options.cuts],
        past_locking=None if ply.energy is None else ply.energy.past_locking,
        part=scene_part(ctx.scene, ctx.products["surface"]) if "surface" in ctx.products else None,
    )
    # where a dart or cut lands is known only after the drape: one that misses the
    # pattern is the scene's mistake, said, not silently dropped
    for problem in pattern.problems:
        ctx.warn(f"cutting pattern: {problem}")
    files = ["cut_pattern.dxf", "cut_pattern.svg", "cut_pattern.csv"]
    write_cut_pattern_dxf(pattern, ctx.case_dir / files[0])
    write_cut_pattern_svg(pattern, ctx.case_dir / files[1])
    write_cut_pattern_csv(pattern, ctx.case_dir / files[2])
    ctx.summary["cut_pattern_area_mm2"] = pattern.area_mm2
    ctx.summary["cut_pattern_perimeter_mm"] = pattern.perimeter_mm
    if pattern.darts:
        ctx.summary["cut_pattern_darts_removed_area_mm2"] = sum(
            d.removed_area_mm2 for d in pattern.darts
        )
    if pattern.past_locking is not None:
        ctx.summary["cut_pattern_past_locking_area_mm2"] = float(pattern.past_locking.area)
    if pattern.cuts:
        ctx.summary["cut_pattern_pieces"] = len(pattern.outline.geoms)
    if pattern.allowance_area_mm2 is not None:
        ctx.summary["cut_pattern_allowance_area_mm2"] = pattern.allowance_area_mm2
    return {"cut_pattern": files}


def scene_problems(scene: Scene, doc: Document, registry: Any) -> list[SourceError]:
    """``export.mesh`` missing, unreadable or too large, refused when the scene is validated
    like a tool mesh file (checked, not read) rather than after the drape has run (the
    mesh_mapping step's ``check``)."""
    from preform.export.shell_mesh import MB, mesh_file_problem

    section = scene.export
    if section is None or section.mesh is None:
        return []
    max_bytes = int(scene.limits.max_mesh_mb * MB)
    problem = mesh_file_problem(Path(scene.base_dir) / section.mesh, max_bytes)
    return [] if problem is None else [doc.error(("export", "mesh"), problem)]


STEPS = [
    Step(
        "mesh_mapping",
        ("mesh_mapping",),
        ("drape", "thickness"),
        "1",
        run_mesh_mapping,
        "The drape mapped onto the scene's FE mesh (export.mesh): directions, shear, thickness.",
        scene_sections=("export",),
        sections={"export": None},
        check=scene_problems,
    ),
]

EXPORTERS = [
    Step.exporter(
        "element_table",
        ("mesh_mapping",),
        write_element_table_step,
        "elements.csv: one row per FE element (mm, deg), uncovered ones included",
    ),
    Step.exporter(
        "element_vtu",
        ("mesh_mapping",),
        write_element_vtu_step,
        "elements.vtu: the FE mesh with the mapped fields, for ParaView (mm)",
    ),
    Step.exporter(
        "abaqus_include",
        ("mesh_mapping",),
        write_abaqus_step,
        "drape_abaqus.inc: *DISTRIBUTION/*ORIENTATION per element, thickness, element sets",
    ),
    Step.exporter(
        "lsdyna_include",
        ("mesh_mapping",),
        write_lsdyna_step,
        "drape_lsdyna.k: *ELEMENT_SHELL_BETA (or _COMPOSITE, both families) per covered "
        "element, uncovered set",
    ),
    Step.exporter(
        "ansys_macro",
        ("mesh_mapping",),
        write_ansys_step,
        "drape_ansys.mac: APDL element systems (u fibres), two-layer sections (thickness, "
        "v fibres), components",
    ),
    Step.exporter(
        "calculix_include",
        ("mesh_mapping",),
        write_calculix_step,
        "drape_calculix.inp: explicit *ORIENTATION and *SHELL SECTION per covered element "
        "(what CalculiX applies), element sets",
    ),
    Step.exporter(
        "cut_pattern",
        ("drape",),
        write_cut_pattern_step,
        "cut_pattern.dxf/.svg/.csv: smooth outline, seam allowance, fibre marks, label (mm)",
    ),
]
