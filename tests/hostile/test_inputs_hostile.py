"""Hostile inputs to the surface added since issue 10 (issue 25, items 4-7 and 9), by class:

- outlines (``ply.outline_mm``, ``part.plan_outline_mm``): self-crossing, no area, repeated
  points: refused at scene validation at the field, saying where the outline crosses itself;
- parts that select nothing: refused at validation where the tool's bounds tell (a cut above
  an analytic tool, an outline beside it), a ``failed`` case with the reason where only the
  drape tells (a cut and an outline that miss each other);
- FE meshes (``.inp``, ``.bdf``): duplicate node or element labels, non-finite coordinates:
  refused when read, at the file's line; a mesh the drape does not reach fails, naming the
  distance between the two bounding boxes;
- the Python API's and the command line's run arguments: every value one refuses the other
  refuses, naming the argument; ``export.prefix`` at scene validation;
- scene names: a bundled name is not captured by a folder of that name.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

import preform
from preform.cli import cli
from preform.export.shell_mesh import read_shell_mesh
from preform.pipeline.scene import SceneError, bundled_scene_dir, resolve_scene_path

SKIN = bundled_scene_dir().parent / "tools" / "hemisphere_skin.inp"

SCENE = """\
name: hostile-inputs
tool:
  surface: hemisphere
  radius_mm: 100
ply:
  node_spacing_mm: 10
  outline_mm: {ply}
start:
  point_mm: [0, 0]
  generator_angle_deg: 90
part:
  plan_outline_mm: {part}
outputs: [drape]
"""
SQUARE = "[[-150, -150], [150, -150], [150, 150], [-150, 150]]"
#: (line, column) of the values of ply.outline_mm and part.plan_outline_mm in SCENE.
PLY_AT, PART_AT = (7, 15), (12, 20)


def _validate(tmp_path: Path, text: str) -> Any:
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return preform.scene(str(path))


BAD_OUTLINES = {
    # (vertices, words, where it crosses itself)
    "bow tie": ("[[-50, -50], [50, 50], [50, -50], [-50, 50]]", "crosses itself", (0, 0)),
    "figure eight": (
        "[[0, 0], [40, 0], [40, 40], [80, 40], [80, 80], [0, 80], [0, 40], [60, 40], [60, 0]]",
        "crosses itself",
        None,
    ),
    "spike back along an edge": ("[[0, 0], [80, 0], [40, 0], [40, 60]]", "crosses itself", None),
    "touching vertex": (
        "[[0, 0], [80, 0], [80, 80], [40, 0], [0, 80]]",
        "crosses itself",
        (40, 0),
    ),
    "collinear": ("[[0, 0], [10, 10], [20, 20]]", "encloses no area", None),
    "one point": ("[[5, 5], [5, 5], [5, 5], [5, 5]]", "encloses no area", None),
}


@pytest.mark.parametrize("field", ["ply", "part"])
@pytest.mark.parametrize("name", sorted(BAD_OUTLINES))
def test_an_ill_defined_outline_is_refused_at_its_field(tmp_path, field: str, name: str) -> None:
    vertices, words, point = BAD_OUTLINES[name]
    ply = vertices if field == "ply" else SQUARE
    part = vertices if field == "part" else "[[-80, -80], [80, -80], [80, 80], [-80, 80]]"
    with pytest.raises(SceneError) as caught:
        _validate(tmp_path, SCENE.format(ply=ply, part=part))
    label = "ply.outline_mm" if field == "ply" else "part.plan_outline_mm"
    line, column = PLY_AT if field == "ply" else PART_AT
    messages = [str(e) for e in caught.value.errors]
    hits = [m for m in messages if f":{line}:{column}: {label}" in m and words in m]
    assert hits, messages
    if point is not None:
        assert f"near (x, y) = ({point[0]}, {point[1]}) mm" in hits[0]


def test_a_simple_outline_still_validates(tmp_path) -> None:
    scene = _validate(tmp_path, SCENE.format(ply=SQUARE, part="[[0, 0], [60, 0], [0, 60]]"))
    assert scene.part is not None and len(scene.part.plan_outline_mm or []) == 3


@pytest.mark.parametrize(
    ("tool", "part", "field"),
    [
        ({"surface": "hemisphere", "radius_mm": 100}, {"z_min_mm": 500}, "z_min_mm"),
        ({"surface": "hemisphere", "radius_mm": 100}, {"z_min_mm": 100.001}, "z_min_mm"),
        (
            {"surface": "paraboloid", "radius_mm": 100, "height_mm": 60},
            {"z_min_mm": 61},
            "z_min_mm",
        ),
        (
            {"surface": "hemisphere", "radius_mm": 100},
            {"plan_outline_mm": [[200, -10], [300, -10], [300, 10]]},
            "plan_outline_mm",
        ),
    ],
)
def test_a_part_off_an_analytic_tool_is_refused_at_validation(
    tool: dict[str, Any], part: dict[str, Any], field: str
) -> None:
    scene = {
        "name": "off",
        "tool": tool,
        "ply": {"node_spacing_mm": 10, "size_mm": [300, 300]},
        "start": {"point_mm": [0, 0], "generator_angle_deg": 90},
        "part": part,
        "outputs": ["drape"],
    }
    with pytest.raises(SceneError, match=rf"part\.{field}: .*selects nothing"):
        preform.scene(scene)


@pytest.mark.parametrize(
    "tool",
    [
        {"surface": "plane", "size_mm": [200, 200]},
        {"surface": "cone", "base_radius_mm": 100, "height_mm": 80, "top_radius_mm": 60},
    ],
)
def test_a_cut_at_the_top_of_a_flat_topped_tool_is_its_top_face(tool: dict[str, Any]) -> None:
    """z ≥ top selects the plane, or the frustum's top disc: not refused, and ok."""
    top = 80 if tool["surface"] == "cone" else 0
    run = preform.drape(
        "plain-weave-150",
        {
            "name": "top",
            "tool": tool,
            "ply": {"node_spacing_mm": 10, "size_mm": [100, 100]},
            "start": {"point_mm": [0, 0], "generator_angle_deg": 90},
            "part": {"z_min_mm": top},
            "outputs": ["drape"],
        },
    )
    assert run.status == "ok", (run.error, run.reasons)
    assert run.summary["part_draped_area_m2"] > 0


def test_a_cut_and_an_outline_that_miss_each_other_fail_with_the_reason() -> None:
    """Each selects part of the dome; together (the rim below 90 mm, the cut above) nothing.
    Only the drape can tell: the case fails, not ``ok`` with 0 J and a coverage of 1."""
    run = preform.drape(
        "plain-weave-150",
        {
            "name": "miss",
            "tool": {"surface": "hemisphere", "radius_mm": 100},
            "ply": {"node_spacing_mm": 10, "size_mm": [300, 300]},
            "start": {"point_mm": [0, 0], "generator_angle_deg": 90},
            "part": {"z_min_mm": 90, "plan_outline_mm": [[50, 50], [90, 50], [90, 90], [50, 90]]},
            "outputs": ["drape"],
        },
    )
    assert run.status == "failed"
    assert "selects nothing of the drape" in (run.error or "")
    assert "z ≥ 90 mm" in (run.error or "")


# -- FE meshes ------------------------------------------------------------------------------

INP = """\
*NODE
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
{extra_node}*ELEMENT, TYPE=S4R
10, 1, 2, 3, 4
{extra_element}"""

BDF = """\
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,1.,1.,0.
GRID,4,,0.,1.,0.
{extra_node}CQUAD4,10,1,1,2,3,4
{extra_element}"""


@pytest.mark.parametrize(
    ("suffix", "extra_node", "extra_element", "line", "words"),
    [
        (".inp", "3, 5, 5, 5\n", "", 6, "node 3 is defined twice (first on line 4)"),
        (".inp", "", "10, 4, 3, 2, 1\n", 8, "element 10 is defined twice (first on line 7)"),
        (".inp", "5, nan, 0, 0\n", "", 6, "node 5 has a coordinate that is not a finite"),
        (".inp", "5, 0, inf, 0\n", "", 6, "node 5 has a coordinate that is not a finite"),
        (".bdf", "GRID,2,,9.,9.,9.\n", "", 5, "node 2 is defined twice (first on line 2)"),
        (".bdf", "", "CQUAD4,10,1,4,3,2,1\n", 6, "element 10 is defined twice (first on line 5)"),
        (".bdf", "GRID,5,,nan,0.,0.\n", "", 5, "node 5 has a coordinate that is not a finite"),
    ],
)
def test_an_fe_mesh_with_duplicate_ids_or_non_finite_coordinates_is_refused_at_its_line(
    tmp_path, suffix: str, extra_node: str, extra_element: str, line: int, words: str
) -> None:
    template = INP if suffix == ".inp" else BDF
    path = tmp_path / f"m{suffix}"
    path.write_text(template.format(extra_node=extra_node, extra_element=extra_element))
    with pytest.raises(ValueError) as caught:
        read_shell_mesh(path)
    assert f"m{suffix}:{line}:" in str(caught.value)
    assert words in str(caught.value)


def test_a_clean_fe_mesh_still_reads(tmp_path) -> None:
    path = tmp_path / "m.inp"
    path.write_text(INP.format(extra_node="", extra_element="11, 1, 2, 3\n"))
    mesh = read_shell_mesh(path)
    assert mesh.element_ids.tolist() == [10, 11] and mesh.node_ids.tolist() == [1, 2, 3, 4]


CAP = """\
name: cap
tool: {{surface: hemisphere, radius_mm: 100}}
ply: {{node_spacing_mm: 10, size_mm: [100, 100]}}
start: {{point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90}}
export: {{mesh: {mesh}}}
outputs: [drape, abaqus_include]
"""


def _export(tmp_path: Path, mesh: Path, *extra: str) -> Any:
    scene = tmp_path / "cap.yaml"
    scene.write_text(CAP.format(mesh=mesh))
    return CliRunner().invoke(
        cli,
        [
            "export",
            "plain-weave-150",
            "abaqus",
            "--scene",
            str(scene),
            "--out",
            str(tmp_path / "out"),
            "--json",
            *extra,
        ],
    )


def test_an_fe_mesh_with_a_nan_fails_the_export_at_its_line_not_in_scipy(tmp_path) -> None:
    mesh = tmp_path / "m.inp"
    mesh.write_text(INP.format(extra_node="5, nan, 0, 0\n", extra_element=""))
    result = _export(tmp_path, mesh)
    assert result.exit_code == 1, result.output
    report = json.loads(result.stdout)
    assert report["status"] == "failed"
    assert re.search(r"m\.inp:6: node 5 has a coordinate that is not a finite", report["error"])
    assert not (tmp_path / "out" / "drape_abaqus.inc").exists()


def test_an_fe_mesh_far_from_the_drape_fails_naming_the_offset(tmp_path) -> None:
    """The bundled skin moved 10 m along x: nothing of it is covered."""
    lines = []
    section = ""
    for raw in SKIN.read_text().splitlines():
        if raw.startswith("*"):
            section = raw.split(",")[0].upper()
        elif section == "*NODE" and raw.strip():
            label, x, y, z = (f.strip() for f in raw.split(","))
            raw = f"{label}, {float(x) + 10_000.0}, {y}, {z}"
        lines.append(raw)
    far = tmp_path / "far.inp"
    far.write_text("\n".join(lines) + "\n")
    result = _export(tmp_path, far)
    assert result.exit_code == 1, result.output
    report = json.loads(result.stdout)
    assert report["status"] == "failed"
    found = re.search(
        r"covers none of the (\d+) elements.*the boxes are ([\d.]+) mm apart", report["error"]
    )
    assert found, report["error"]
    # the skin reaches x = 100 mm, the drape of a 100 mm ply a little past x = 50 mm
    assert 9_800 < float(found.group(2)) < 10_000
    assert "abaqus" in report["not_written"]


def test_a_bad_export_prefix_is_refused_at_scene_validation(tmp_path) -> None:
    scene = tmp_path / "cap.yaml"
    text = CAP.format(mesh=SKIN).replace("export: {", "export: {prefix: 9bad, ")
    scene.write_text(text)
    with pytest.raises(SceneError, match=r"cap\.yaml:5:\d+: export\.prefix: prefix must be"):
        preform.scene(str(scene))
    run = f"pipeline run --materials plain-weave-150 --out {tmp_path / 'run'} --scene"
    result = CliRunner().invoke(cli, [*run.split(), str(scene)])
    assert result.exit_code == 2, result.output
    assert "export.prefix" in result.output and "nothing was run" in result.output


# -- run arguments, API and command line alike ----------------------------------------------

API_ARGUMENTS = [
    ("workers", 0, ValueError),
    ("workers", -3, ValueError),
    ("workers", 2.5, TypeError),
    ("workers", True, TypeError),
    ("case_timeout_s", -1, ValueError),
    ("case_timeout_s", 0, ValueError),
    ("case_timeout_s", math.nan, ValueError),
    ("case_timeout_s", math.inf, ValueError),
    ("case_timeout_s", "60", TypeError),
    ("engine", "threads", ValueError),
    ("fidelity", "ultra", ValueError),
    ("materials", 3, TypeError),
    ("force", "yes", TypeError),
]


@pytest.mark.parametrize(("name", "value", "kind"), API_ARGUMENTS)
def test_run_refuses_what_the_command_line_refuses_naming_the_argument(
    tmp_path, name: str, value: Any, kind: type
) -> None:
    with pytest.raises(kind, match=rf"^{name} "):
        preform.run(out_dir=tmp_path / "out", **{name: value})
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--case-timeout", "nan"),
        ("--case-timeout", "inf"),
        ("--case-timeout", "0"),
        ("--workers", "0"),
    ],
)
def test_the_command_line_refuses_the_same_values(tmp_path, option: str, value: str) -> None:
    result = CliRunner().invoke(
        cli, ["pipeline", "run", option, value, "--out", str(tmp_path / "out")]
    )
    assert result.exit_code == 2, result.output
    assert option in result.output
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("call", "argument"),
    [
        (lambda: preform.drape(42), "fabric"),
        (lambda: preform.drape(None), "fabric"),
        (lambda: preform.least_energy(3.5), "fabric"),
        (lambda: preform.drape("plain-weave-150", 42), "scene"),
        (lambda: preform.drape("plain-weave-150", library="lib.yaml"), "library"),
        (lambda: preform.run(scenes="hemisphere"), "scenes"),
    ],
)
def test_api_arguments_of_the_wrong_kind_raise_a_type_error_naming_them(
    call: Any, argument: str
) -> None:
    with pytest.raises(TypeError, match=rf"^{argument} must be"):
        call()


# -- scene names ----------------------------------------------------------------------------


def test_a_bundled_scene_name_is_not_captured_by_a_folder_of_that_name(
    tmp_path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "unit-cell").mkdir()  # e.g. the results of an earlier run
    (tmp_path / "hemisphere").write_text("not a scene")
    assert resolve_scene_path("unit-cell") == bundled_scene_dir() / "unit-cell.yaml"
    assert resolve_scene_path("hemisphere") == bundled_scene_dir() / "hemisphere.yaml"
    # a path the user wrote is the user's file
    assert resolve_scene_path("./unit-cell") == Path("./unit-cell")
    assert resolve_scene_path("mine.yaml") == Path("mine.yaml")
    result = CliRunner().invoke(cli, ["scenes", "show", "unit-cell"])
    assert result.exit_code == 0, result.output
    assert "name: unit-cell" in result.output
