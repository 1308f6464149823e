"""``preform export NAME TARGET...``: drape one fabric over a scene's tool and write
downstream files.

The command runs the same steps as ``preform pipeline run`` (the scene's drape, or its
least-energy drape when the scene searches), in this process, then the exporters of the chosen
targets, into ``--out``. Options given here override the scene's ``export`` section.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from preform.command_line import EXIT_FAILED, echo_json, fail, json_option, library_options

#: Command-line target -> the scene output (exporter product) it asks for.
TARGETS: dict[str, str] = {
    "abaqus": "abaqus_include",
    "lsdyna": "lsdyna_include",
    "ansys": "ansys_macro",
    "calculix": "calculix_include",
    "table": "element_table",
    "vtu": "element_vtu",
    "cut-pattern": "cut_pattern",
}
#: Targets that need the user's FE mesh.
NEEDS_MESH = frozenset({"abaqus", "calculix", "lsdyna", "ansys", "table", "vtu"})


class TargetChoice(click.Choice):
    """The targets, and a target that was replaced refused with what replaced it (not only
    "invalid choice")."""

    def convert(self, value: Any, param: Any, ctx: Any) -> Any:
        from preform._moved import RETIRED_TARGETS

        if value in RETIRED_TARGETS:
            self.fail(RETIRED_TARGETS[value], param, ctx)
        return super().convert(value, param, ctx)


def _vector(_ctx: Any, _param: Any, value: str | None) -> tuple[float, float, float] | None:
    if value is None:
        return None
    try:
        parts = tuple(float(v) for v in value.split(","))
    except ValueError:
        parts = ()
    if len(parts) != 3 or not any(parts):
        raise click.BadParameter(f"give three numbers X,Y,Z, not all zero (got {value!r})")
    return (parts[0], parts[1], parts[2])


@click.command("export")
@click.argument("name")
@click.argument("targets", nargs=-1, required=True, type=TargetChoice(sorted(TARGETS)))
@click.option(
    "--scene",
    "scene_spec",
    default="hemisphere",
    show_default=True,
    help="Scene file or bundled scene name (its tool, ply, start and export section).",
)
@click.option(
    "--mesh",
    type=click.Path(dir_okay=False),
    metavar="FILE",
    help="Your shell mesh (.inp, .bdf, or any meshio format); default: the scene's export.mesh.",
)
@click.option(
    "--mesh-unit-mm", type=float, default=None, help="Length of one mesh unit in mm (default 1)."
)
@click.option(
    "--reference-direction",
    callback=_vector,
    default=None,
    help="X,Y,Z: direction fibre angles are measured from (default 1,0,0).",
)
@click.option("--thickness-mm", type=float, default=None, help="Nominal ply thickness t0 [mm].")
@click.option(
    "--thickness-cap", type=float, default=None, help="Compaction limit of t/t0 (flagged)."
)
@click.option("--seam-allowance-mm", type=float, default=None, help="Seam allowance [mm].")
@click.option(
    "--lsdyna-form",
    type=click.Choice(["beta", "composite"]),
    default=None,
    help="lsdyna: *ELEMENT_SHELL_BETA (u fibres) or _COMPOSITE (both families; needs t0).",
)
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    metavar="DIR",
    default="preform-export",
    show_default=True,
    help="Directory the files go to.",
)
@library_options
@json_option
def export_command(
    name: str,
    targets: tuple[str, ...],
    scene_spec: str,
    mesh: str | None,
    mesh_unit_mm: float | None,
    reference_direction: tuple[float, float, float] | None,
    thickness_mm: float | None,
    thickness_cap: float | None,
    seam_allowance_mm: float | None,
    lsdyna_form: str | None,
    out_dir: str,
    libraries: tuple[str, ...],
    no_bundled: bool,
    as_json: bool,
) -> None:
    """Drape fabric NAME as the scene says and write TARGETS (abaqus, calculix, lsdyna, ansys,
    table, vtu, cut-pattern).

    abaqus/calculix/lsdyna/ansys/table/vtu map the drape onto your shell mesh (--mesh, or the
    scene's export.mesh); cut-pattern writes the cutting pattern (DXF, SVG, CSV). Everything is in
    mm and degrees. Elements the drape does not cover are listed in every file, never given a
    value. Exit code 0 when written (also when some elements are not covered), 1 when the
    drape or the export failed, 2 for bad input.
    """
    from preform.base.status import CaseFailure
    from preform.command_line import fabric_or_exit, load_library_or_exit
    from preform.pipeline.planner import PlanError, plan
    from preform.pipeline.scene import (
        SceneError,
        load_scene,
        missing_scene_message,
        resolve_scene_path,
        scene_from_data,
    )
    from preform.plugin_manager import default_host
    from preform.step import CaseContext

    host = default_host()
    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    fabric = fabric_or_exit(lib, name)
    scene_path = resolve_scene_path(scene_spec)
    if not scene_path.is_file():
        fail([f"error: {missing_scene_message(scene_spec)}"])
    try:
        _scene, data = load_scene(scene_path, host.registry)
    except SceneError as error:
        fail([*error.errors, "nothing was run."])
    data = dict(data)
    section = dict(data.get("export") or {})
    if mesh is not None:
        from preform.export.shell_mesh import mesh_file_problem

        # refused before the drape runs, as a scene's export.mesh is at validation
        problem = mesh_file_problem(mesh)
        if problem is not None:
            fail([f"error: --mesh: {problem}"])
        section["mesh"] = str(Path(mesh).resolve())
    elif "mesh" in section:
        section["mesh"] = str((scene_path.parent / section["mesh"]).resolve())
    for key, value in (
        ("mesh_unit_mm", mesh_unit_mm),
        ("reference_direction", reference_direction),
        ("nominal_thickness_mm", thickness_mm),
        ("thickness_cap_ratio", thickness_cap),
        ("seam_allowance_mm", seam_allowance_mm),
        ("lsdyna_form", lsdyna_form),
    ):
        if value is not None:
            section[key] = list(value) if isinstance(value, tuple) else value
    if NEEDS_MESH & set(targets) and "mesh" not in section:
        fail(["error: abaqus, calculix, lsdyna, ansys, table and vtu need your mesh: --mesh FILE"])
    data["export"] = section
    data["outputs"] = [TARGETS[t] for t in dict.fromkeys(targets)]
    try:
        scene = scene_from_data(data, str(scene_path.parent), host.registry)
        steps = plan(scene, host.registry)
    except (PlanError, ValueError) as error:
        fail([f"error: {scene_path}: {error}"])
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ctx = CaseContext(fabric=fabric, scene=scene, registry=host.registry, case_dir=out)
    written: dict[str, Any] = {}
    error_text = None
    try:
        for step in steps:
            products = dict(step.run(ctx))
            ctx.products.update(products)
            if step.writes_files:
                for product in step.provides:
                    written[product] = products[product]
    except CaseFailure as error:
        error_text = str(error)
    status = "failed" if error_text else ("partial" if ctx.partial_reasons else "ok")
    mapping = ctx.products.get("mesh_mapping")
    report: dict[str, Any] = {
        "status": status,
        "material": name,
        "scene": scene.name,
        "out": str(out),
        "written": {t: written.get(TARGETS[t]) for t in targets if TARGETS[t] in written},
        "not_written": [t for t in targets if TARGETS[t] not in written],
        "units": {"length": "mm", "angle": "deg"},
        "reasons": list(ctx.partial_reasons),
        "warnings": list(ctx.warnings),
    }
    if error_text:
        report["error"] = error_text
    if mapping is not None:
        summary = mapping.summary()
        report["mesh"] = {
            key: summary[key]
            for key in (
                "mesh",
                "element_labels_from",
                "elements",
                "elements_covered",
                "elements_uncovered",
                "uncovered_element_ids",
                "elements_above_thickness_cap",
                "nominal_thickness_mm",
                "thickness_model",
                "thickness_reference",
            )
        }
    for key in (
        "cut_pattern_area_mm2",
        "cut_pattern_allowance_area_mm2",
        "cut_pattern_darts_removed_area_mm2",
        "cut_pattern_pieces",
        "cut_pattern_past_locking_area_mm2",
    ):
        if key in ctx.summary:
            report[key] = ctx.summary[key]
    if as_json:
        echo_json(report)
        for line in report["warnings"]:
            click.echo(f"warning: {line}", err=True)
        if error_text:
            click.echo(f"failed: {error_text}", err=True)
    else:
        for target, files in report["written"].items():
            file_names = files if isinstance(files, list) else [files]
            click.echo(f"{target}: " + ", ".join(str(out / f) for f in file_names) + " (mm, deg)")
        if mapping is not None:
            m = report["mesh"]
            click.echo(
                f"mesh: {m['elements_covered']} of {m['elements']} elements covered"
                + (
                    f"; uncovered (listed in the files, no value given): {m['elements_uncovered']}"
                    if m["elements_uncovered"]
                    else ""
                )
            )
        for line in report["warnings"]:
            click.echo(f"warning: {line}", err=True)
        if error_text:
            click.echo(f"failed: {error_text}", err=True)
    sys.exit(EXIT_FAILED if error_text else 0)
