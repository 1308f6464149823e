"""``preform export NAME... TARGET...``: drape one fabric, or a layup's stack, over a scene's
tool and write downstream files.

The command runs the same steps as ``preform pipeline run`` (the scene's drape, or its
least-energy drape when the scene searches; for a scene with a ``layup`` section, every ply on
the tool offset by the plies below), in this process, then the exporters of the chosen targets,
into ``--out``. Options given here override the scene's ``export`` section.

Which it is comes from the scene: a scene without a layup drapes the one fabric NAME; a layup
scene (``--scene hemisphere-layup``) drapes its stack, its plies' own fabrics when no NAME is
given, else one NAME per ply, tool side first, in their place. The names come before the
targets; a word that is a target is a target.
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
#: For a layup scene: target -> the scene output of the stack (composite sections per element;
#: ``table`` is ``stack_elements.csv``, which the sections step writes).
STACK_TARGETS: dict[str, str] = {
    "abaqus": "stack_abaqus",
    "calculix": "stack_calculix",
    "lsdyna": "stack_lsdyna",
    "ansys": "stack_ansys",
    "table": "stack_sections",
}
#: For a layup scene: target -> the output every ply gives in its own folder (no stack form).
PLY_TARGETS: dict[str, str] = {"vtu": "element_vtu", "cut-pattern": "cut_pattern"}


def split_words(words: tuple[str, ...]) -> tuple[list[str], list[str]]:
    """(fabric names, targets) of the command's words: the leading words that are not targets
    are names, the rest targets. A usage error (exit 2) for no target, a replaced target (naming
    what replaced it) or a word after the first target that is not one."""
    from preform._moved import RETIRED_TARGETS

    known = ", ".join(sorted(TARGETS))
    names: list[str] = []
    targets: list[str] = []
    for k, word in enumerate(words):
        if word in RETIRED_TARGETS:
            raise click.BadParameter(RETIRED_TARGETS[word], param_hint="TARGET")
        if word in TARGETS:
            targets.append(word)
        elif targets:
            raise click.BadParameter(
                f"word {k + 1}, {word!r}, follows the target {targets[-1]!r} and is no target "
                f"(fabric names come first; targets: {known})",
                param_hint="TARGET",
            )
        else:
            names.append(word)
    if not targets:
        raise click.BadParameter(
            f"no target among {' '.join(words)!r}: give one or more of {known}",
            param_hint="TARGET",
        )
    return names, targets


def mesh_label(path: str) -> str:
    """The user's mesh as a report names it: its file name. The report, like the decks, goes
    to other machines and into version control, where the folder it was read from is noise
    (issue 26)."""
    return Path(path).name


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
@click.argument("words", nargs=-1, required=True, metavar="[NAME]... TARGET...")
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
    words: tuple[str, ...],
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
    """Drape fabric NAME as the scene says, or a layup scene's stack, and write TARGETS
    (abaqus, calculix, lsdyna, ansys, table, vtu, cut-pattern).

    abaqus/calculix/lsdyna/ansys/table/vtu map the drape onto your shell mesh (--mesh, or the
    scene's export.mesh); cut-pattern writes the cutting pattern (DXF, SVG, CSV). A layup scene
    (--scene hemisphere-layup) drapes its stack, with its plies' fabrics when no NAME is given,
    else one NAME per ply, tool side first: abaqus/calculix/lsdyna/ansys write its composite
    sections, table stack_elements.csv, vtu and cut-pattern each ply's own in the ply's folder.
    Everything is in mm and degrees. Elements the drape does not cover are listed in every
    file, never given a value. Exit code 0 when written (also when some elements are not
    covered), 1 when the drape or the export failed, 2 for bad input.
    """
    from preform.base.status import CaseFailure
    from preform.command_line import load_library_or_exit
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

    names, targets = split_words(words)
    wanted = list(dict.fromkeys(targets))
    host = default_host()
    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    scene_path = resolve_scene_path(scene_spec)
    if not scene_path.is_file():
        fail([f"error: {missing_scene_message(scene_spec)}"])
    try:
        _scene, data = load_scene(scene_path, host.registry)
    except SceneError as error:
        fail([*error.errors, "nothing was run."])
    data = dict(data)
    is_stack = bool(data.get("layup"))
    if is_stack:
        fabrics = _stack_fabrics(lib, data, names, scene_path)
        if lsdyna_form is not None:
            fail(
                [
                    "error: --lsdyna-form: a stack is written as *ELEMENT_SHELL_COMPOSITE, one "
                    "integration point per ply; the option chooses one ply's form"
                ]
            )
    else:
        if len(names) != 1:
            fail(
                [
                    f"error: scene {scene_path.stem!r} has no layup, so it drapes one fabric: "
                    f"give one NAME, not {len(names)} ({', '.join(names) or 'none'}); a layup "
                    "scene (--scene hemisphere-layup) drapes a stack"
                ]
            )
        fabrics = {names[0]: _fabric_or_fail(lib, names[0], "NAME")}
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
    if is_stack:
        layup = dict(data["layup"])
        # a ply gives only what was asked of it: its drape, and a per-ply target's files
        layup["ply_outputs"] = ["drape", *(PLY_TARGETS[t] for t in wanted if t in PLY_TARGETS)]
        data["layup"] = layup
        data["outputs"] = ["layup", *(STACK_TARGETS[t] for t in wanted if t in STACK_TARGETS)]
    else:
        data["outputs"] = [TARGETS[t] for t in wanted]
    try:
        scene = scene_from_data(data, str(scene_path.parent), host.registry)
        steps = plan(scene, host.registry)
    except (PlanError, ValueError) as error:
        fail([f"error: {scene_path}: {error}"])
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ctx = CaseContext(
        fabric=next(iter(fabrics.values())), scene=scene, registry=host.registry, case_dir=out
    )
    if is_stack:
        ctx.products["layup_fabrics"] = fabrics
    products_written: dict[str, Any] = {}
    error_text = None
    try:
        for step in steps:
            products = dict(step.run(ctx))
            ctx.products.update(products)
            if step.writes_files:
                for product in step.provides:
                    products_written[product] = products[product]
    except CaseFailure as error:
        error_text = str(error)
    written = _stack_files(ctx, wanted) if is_stack else _ply_files(products_written, wanted)
    status = "failed" if error_text else ("partial" if ctx.partial_reasons else "ok")
    report: dict[str, Any] = {
        "status": status,
        "material": "+".join(fabrics) if not is_stack else _stack_label(data),
        "scene": scene.name,
        "out": str(out),
        "written": written,
        "not_written": [t for t in targets if t not in written],
        "units": {"length": "mm", "angle": "deg"},
        "reasons": list(ctx.partial_reasons),
        "warnings": list(ctx.warnings),
    }
    if error_text:
        report["error"] = error_text
    mapping = ctx.products.get("mesh_mapping")
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
        report["mesh"]["mesh"] = mesh_label(summary["mesh"])
    if is_stack:
        report["plies"] = [
            {key: record.get(key) for key in PLY_REPORT_KEYS}
            for record in ctx.summary.get("plies", [])
        ]
        sections = ctx.products.get("stack_sections")
        if sections is not None:
            counts = sections.summary()
            report["mesh"] = {"mesh": mesh_label(sections.mesh.source), **counts}
    for key in (
        "cut_pattern_area_mm2",
        "cut_pattern_allowance_area_mm2",
        "cut_pattern_darts_removed_area_mm2",
        "cut_pattern_pieces",
        "cut_pattern_past_locking_area_mm2",
    ):
        if key in ctx.summary:
            report[key] = ctx.summary[key]
    _print_report(report, out, as_json)
    sys.exit(EXIT_FAILED if error_text else 0)


#: What the report says of each ply of a stack.
PLY_REPORT_KEYS = ("ply", "name", "fabric", "orientation_deg", "offset_mm", "status", "error")


def _fabric_or_fail(lib: Any, name: str, where: str) -> Any:
    """``lib.fabric(name)``, or exit 2 with the library's "no fabric named ... did you mean"
    located at ``where``."""
    try:
        return lib.fabric(name)
    except KeyError as exc:
        fail([f"error: {where}: {exc.args[0]}"])


def _stack_fabrics(
    lib: Any, data: dict[str, Any], names: list[str], scene_path: Path
) -> dict[str, Any]:
    """Fabric name -> fabric of every ply of the layup scene ``data``; with ``names`` (one per
    ply, tool side first) the plies' fabrics are replaced by them (in ``data``). Exit 2, located
    at the NAME or the scene's ply, for a wrong count or a fabric the library lacks."""
    layup = dict(data["layup"])
    plies = [dict(p) for p in layup.get("plies") or []]
    if names and len(names) != len(plies):
        fail(
            [
                f"error: {scene_path}: the layup has {len(plies)} plies: give no NAME (its "
                f"plies' own fabrics) or one per ply, tool side first, not {len(names)} "
                f"({', '.join(names)})"
            ]
        )
    fabrics: dict[str, Any] = {}
    for k, ply in enumerate(plies):
        if names:
            ply["fabric"] = names[k]
            where = f"NAME {k + 1} (ply {k + 1})"
        else:
            where = f"{scene_path}: layup.plies[{k}].fabric"
        name = str(ply.get("fabric"))
        if name not in fabrics:
            fabrics[name] = _fabric_or_fail(lib, name, where)
    layup["plies"] = plies
    data["layup"] = layup
    return fabrics


def _stack_label(data: dict[str, Any]) -> str:
    """A stack's ``material`` as a pipeline run names it: its fabrics joined by '+'."""
    return "+".join(dict.fromkeys(str(p["fabric"]) for p in data["layup"]["plies"]))


def _ply_files(products: dict[str, Any], targets: list[str]) -> dict[str, Any]:
    """Target -> the file (or files) its exporter wrote, for one ply."""
    return {t: products[TARGETS[t]] for t in targets if TARGETS[t] in products}


def _stack_files(ctx: Any, targets: list[str]) -> dict[str, Any]:
    """Target -> the file(s) written for a stack: the deck of a section target, the stack's
    element table, or each ply's files in its folder (``<ply>/<file>``)."""
    from preform.pipeline.runner import folder_name

    out: dict[str, Any] = {}
    stack = ctx.products.get("layup")
    for target in targets:
        if target == "table":
            if "stack_sections" in ctx.products:
                out[target] = "stack_elements.csv"
        elif target in STACK_TARGETS:
            if STACK_TARGETS[target] in ctx.products:
                out[target] = ctx.products[STACK_TARGETS[target]]
        elif stack is not None:
            files: list[str] = []
            for layer, products in zip(stack.layers, stack.plies_products, strict=True):
                made = products.get(PLY_TARGETS[target])
                for name in [made] if isinstance(made, str) else list(made or []):
                    files.append(f"{folder_name(layer.name)}/{name}")
            if files:
                out[target] = files
    return out


def _print_report(report: dict[str, Any], out: Path, as_json: bool) -> None:
    """The report on stdout (JSON, or a line per target and the mesh's coverage), warnings
    and the failure on stderr."""
    if as_json:
        echo_json(report)
    else:
        for target, files in report["written"].items():
            file_names = files if isinstance(files, list) else [files]
            click.echo(f"{target}: " + ", ".join(str(out / f) for f in file_names) + " (mm, deg)")
        m = report.get("mesh")
        if m is not None and "elements_covered" in m:
            click.echo(
                f"mesh: {m['elements_covered']} of {m['elements']} elements covered"
                + (
                    f"; uncovered (listed in the files, no value given): {m['elements_uncovered']}"
                    if m["elements_uncovered"]
                    else ""
                )
            )
        elif m is not None:
            click.echo(
                f"stack on {m['mesh']}: {m['elements_all_plies']} of {m['elements']} elements "
                f"carry every ply; {m['elements_bare']} none (listed in the files, no section)"
            )
    for line in report["warnings"]:
        click.echo(f"warning: {line}", err=True)
    if "error" in report:
        click.echo(f"failed: {report['error']}", err=True)
