"""``preform export``: drape one fabric over a scene's tool and write downstream files.

The command runs the same steps as ``preform pipeline run`` (the scene's drape, or its
least-energy drape when the scene searches), in this process, then the exporters of the chosen
targets, into ``--out``. Options given here override the scene's ``export`` section.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import click

#: Command-line target -> the scene output (exporter product) it asks for.
TARGETS: dict[str, str] = {
    "abaqus": "abaqus_include",
    "lsdyna": "lsdyna_include",
    "ansys": "ansys_macro",
    "table": "element_table",
    "vtu": "element_vtu",
    "flat-pattern": "cut_pattern",
}
#: Targets that need the user's FE mesh.
NEEDS_MESH = frozenset({"abaqus", "lsdyna", "ansys", "table", "vtu"})


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
@click.argument("targets", nargs=-1, required=True, type=click.Choice(sorted(TARGETS)))
@click.option("--material", "material", required=True, help="Fabric name in the library.")
@click.option(
    "--scene",
    "scene_spec",
    default="hemisphere",
    show_default=True,
    help="Scene file or bundled scene name (its tool, ply and start).",
)
@click.option("--mesh", type=click.Path(dir_okay=False), help="Your shell mesh (.inp, .bdf, ...).")
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
@click.option("--out", "out_dir", default="preform-export", show_default=True)
@click.option("--library", "libraries", multiple=True, help="Extra library file or directory.")
@click.option("--json", "as_json", is_flag=True, help="Summary as JSON on stdout.")
def export_command(
    targets: tuple[str, ...],
    material: str,
    scene_spec: str,
    mesh: str | None,
    mesh_unit_mm: float | None,
    reference_direction: tuple[float, float, float] | None,
    thickness_mm: float | None,
    thickness_cap: float | None,
    seam_allowance_mm: float | None,
    out_dir: str,
    libraries: tuple[str, ...],
    as_json: bool,
) -> None:
    """Write TARGETS (abaqus, lsdyna, ansys, table, vtu, flat-pattern) for one fabric's drape.

    abaqus/lsdyna/ansys/table/vtu map the drape onto your shell mesh (--mesh, or the scene's
    export.mesh); flat-pattern writes the cutting pattern (DXF, SVG, CSV). Everything is in
    mm and degrees. Exit code 0 when written (also when some elements are not covered: they
    are listed), 1 when the drape or the export failed, 2 for bad input.
    """
    from preform.cli import _host, load_library_or_exit
    from preform.pipeline.planner import PlanError, plan
    from preform.pipeline.scene import SceneError, load_scene, resolve_scene_path, scene_from_data
    from preform.pipeline.status import CaseFailure
    from preform.pipeline.step import CaseContext

    host = _host()
    lib = load_library_or_exit(libraries, bundled=True)
    fabric = lib.fabrics.get(material)
    if fabric is None:
        names = ", ".join(sorted(lib.fabrics))
        click.echo(f"unknown material {material!r}; the library has: {names}", err=True)
        sys.exit(2)
    try:
        scene_path = resolve_scene_path(scene_spec)
        _scene, data = load_scene(scene_path, host.registry)
    except (SceneError, OSError, ValueError) as error:
        click.echo(str(error), err=True)
        sys.exit(2)
    data = dict(data)
    section = dict(data.get("export") or {})
    if mesh is not None:
        section["mesh"] = str(Path(mesh).resolve())
    elif "mesh" in section:
        section["mesh"] = str((scene_path.parent / section["mesh"]).resolve())
    for key, value in (
        ("mesh_unit_mm", mesh_unit_mm),
        ("reference_direction", reference_direction),
        ("nominal_thickness_mm", thickness_mm),
        ("thickness_cap_ratio", thickness_cap),
        ("seam_allowance_mm", seam_allowance_mm),
    ):
        if value is not None:
            section[key] = list(value) if isinstance(value, tuple) else value
    if NEEDS_MESH & set(targets) and "mesh" not in section:
        click.echo("abaqus, lsdyna, ansys, table and vtu need your mesh: --mesh FILE", err=True)
        sys.exit(2)
    data["export"] = section
    data["outputs"] = [TARGETS[t] for t in dict.fromkeys(targets)]
    try:
        scene = scene_from_data(data, str(scene_path.parent), host.registry)
        steps = plan(scene, host.registry)
    except (PlanError, ValueError) as error:
        click.echo(f"{scene_path}: {error}", err=True)
        sys.exit(2)
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
        "material": material,
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
            )
        }
    for key in ("cut_pattern_area_mm2", "cut_pattern_allowance_area_mm2"):
        if key in ctx.summary:
            report[key] = ctx.summary[key]
    if as_json:
        click.echo(json.dumps(report, indent=2, default=str))
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
            click.echo(f"warning: {line}")
        if error_text:
            click.echo(f"failed: {error_text}", err=True)
    sys.exit(1 if error_text else 0)
