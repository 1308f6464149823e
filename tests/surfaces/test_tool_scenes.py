"""Tools read from files, through the pipeline: what the case says about the tool (format,
unit and whence, repairs), parts made of faces, and refusals located in words."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from click.testing import CliRunner

from preform.cli import cli
from preform.plugins.surfaces.mesh import TriangleMesh, tessellate_hemisphere, write_stl


def _run(tmp_path: Path, scene: dict, name: str = "scene") -> tuple[int, str, dict | None]:
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(scene))
    out = tmp_path / f"out-{name}"
    args = ["pipeline", "run", "--scene", str(path), "--materials", "E-BX-318"]
    result = CliRunner().invoke(cli, [*args, "--engine", "serial", "--out", str(out)])
    summaries = sorted(out.glob("*/*/summary.json"))
    return (
        result.exit_code,
        result.output,
        json.loads(summaries[0].read_text()) if summaries else None,
    )


def _scene(tool: dict, part: dict | None = None, spacing_mm: float = 10.0) -> dict:
    scene = {
        "name": "tool-test",
        "tool": {"surface": "mesh", **tool},
        "ply": {"node_spacing_mm": spacing_mm, "size_mm": [160, 160]},
        "start": {"point_mm": [3.1, 1.7], "generator_angle_deg": 80},
        "outputs": ["cells_csv"],
    }
    if part is not None:
        scene["part"] = part
    return scene


def _broken_dome_stl(path: Path) -> None:
    """A dome STL with a fifth of its triangles wound the wrong way."""
    dome = tessellate_hemisphere(0.1, 12)
    faces = dome.faces.copy()
    faces[::5] = faces[::5, ::-1]
    # Written triangle by triangle: a TriangleMesh would re-wind them (with a warning).
    lines = ["solid broken"]
    for corners in dome.vertices[faces] / 1e-3:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += ["vertex " + " ".join(repr(float(c)) for c in corner) for corner in corners]
        lines += ["endloop", "endfacet"]
    path.write_text("\n".join([*lines, "endsolid broken"]) + "\n", encoding="ascii")


def test_the_case_says_what_the_tool_is_and_what_was_repaired(tmp_path):
    _broken_dome_stl(tmp_path / "dome.stl")
    code, output, summary = _run(tmp_path, _scene({"file": "dome.stl"}))
    assert code == 0, output
    assert summary is not None
    assert summary["tool_format"] == "STL" and summary["tool_unit"] == "mm"
    assert summary["tool_unit_from"] == "default (scene gives no tool.units)"
    n_wrong = len(range(0, 4 * 12 * 12, 5))
    assert summary["mesh_flipped_triangles"] == n_wrong
    said = [w for w in summary["warnings"] if w.startswith("tool mesh:")]
    assert said == [
        f"tool mesh: re-wound {n_wrong} triangles whose normals disagreed with their neighbours'"
    ]
    assert "re-wound" in output  # on the console too


def test_a_part_of_named_faces(tmp_path):
    scene = _scene({"file": "hat_mould.obj"}, part={"faces": ["block"]}, spacing_mm=10.0)
    code, output, summary = _run(tmp_path, scene)
    assert code == 0, output
    assert summary is not None and summary["part"] == "faces block of hat_mould.obj"
    block_area = 0.1 * 0.06 + 2 * 0.1 * 0.04 + 2 * 0.06 * 0.04
    # What the net drapes of the part plus what it leaves bare is the part's area.
    assert summary["part_draped_area_m2"] + summary["uncovered_part_area_m2"] == pytest.approx(
        block_area
    )


@pytest.mark.parametrize(
    ("tool", "part", "said"),
    [
        (
            {"file": "hat_mould.obj"},
            {"faces": ["lid"]},
            "part.faces[0]: no face of the tool is named 'lid'",
        ),
        (
            {"file": "hat_mould.obj"},
            {"faces": [7]},
            "part.faces[0]: the tool has no face 7 (faces 1..2)",
        ),
    ],
)
def test_faces_the_tool_does_not_have_are_refused_in_words(tmp_path, tool, part, said):
    code, _, summary = _run(tmp_path, _scene(tool, part))
    assert code != 0
    assert summary is not None and said in summary["error"]


def test_faces_of_an_analytic_tool_are_refused(tmp_path):
    scene = _scene({}, part={"faces": [1]})
    scene["tool"] = {"surface": "hemisphere", "radius_mm": 100}
    code, _, summary = _run(tmp_path, scene)
    assert code != 0 and summary is not None
    assert "part.faces selects faces of a tool read from a file" in summary["error"]


def test_a_non_manifold_tool_is_refused_with_where(tmp_path):
    v = np.array([[0, 0, 0], [100, 0, 0], [100, 100, 0], [0, 100, 0], [50, 50, 80]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3], [0, 2, 4]])
    corners = v[faces]
    lines = ["solid fin"]
    for tri in corners:
        lines += ["facet normal 0 0 1", "outer loop"]
        lines += [f"vertex {x:g} {y:g} {z:g}" for x, y, z in tri]
        lines += ["endloop", "endfacet"]
    (tmp_path / "fin.stl").write_text("\n".join([*lines, "endsolid fin"]) + "\n")
    scene = _scene({"file": "fin.stl"})
    scene["start"]["point_mm"] = [60, 30]
    code, _, summary = _run(tmp_path, scene)
    assert code != 0 and summary is not None
    assert (
        "non-manifold edge(s): the edge at (50, 50, 0) mm is shared by 3 triangles"
        in (summary["error"])
    )


def test_units_on_a_step_tool_are_refused_at_validation(tmp_path):
    scene = _scene({"file": "hat_stiffener.step", "units": "mm"})
    code, output, _ = _run(tmp_path, scene)
    assert code != 0
    assert "tool" in output and "declares its own length unit" in output


def test_the_bundled_stiffener_drapes_and_says_its_unit(tmp_path):
    pytest.importorskip("gmsh")
    scene = _scene(
        {"file": "hat_stiffener.step"}, part={"faces": list(range(7, 16))}, spacing_mm=20.0
    )
    scene["ply"]["size_mm"] = [360, 160]
    code, output, summary = _run(tmp_path, scene)
    assert code == 0, output
    assert summary is not None
    assert summary["tool_format"] == "STEP" and summary["tool_unit"] == "mm"
    assert summary["tool_unit_from"] == "declared in the STEP file"
    assert summary["tool_tessellation_tolerance_mm"] == pytest.approx(0.05)
    assert summary["part"].startswith("faces 7, 8, 9")
    assert summary["status"] in ("ok", "partial")
    if summary["status"] == "partial":
        assert summary["reasons"]  # said in words


def test_the_scenes_feature_angle_reaches_the_mesh(tmp_path):
    """`tool.feature_angle_deg` switches the surface-length rule on for that tool: a plate
    folded 90° along y, crossed by fibres at 60° to the crease, keeps the flat net's angle α
    in every cell lying on one flank only with the rule on (the chord over the crease shears
    the cells beyond it by degrees)."""
    # x < 0 flat, x > 0 going straight down: a grid 25 mm apart, the crease at x = 0
    y = np.linspace(-0.3, 0.3, 25)
    near = [(-a, b, 0.0) for a in np.linspace(0.3, 0.0, 13) for b in y]
    far = [(0.0, b, -a) for a in np.linspace(0.025, 0.3, 12) for b in y]
    cols = len(y)
    faces = [
        f
        for i in range(24)
        for j in range(cols - 1)
        for f in (
            [i * cols + j, (i + 1) * cols + j, (i + 1) * cols + j + 1],
            [i * cols + j, (i + 1) * cols + j + 1, i * cols + j + 1],
        )
    ]
    plate = TriangleMesh(np.array(near + far), np.array(faces))
    write_stl(tmp_path / "fold.stl", plate, binary=True, units_to_m=1.0)
    flank_shear = {}
    for angle in (None, 20.0):
        tool = {"file": "fold.stl", "units": "m"}
        if angle is not None:
            tool["feature_angle_deg"] = angle
        scene = _scene(tool, spacing_mm=10.0)
        scene["start"] = {"point_mm": [-25.0, 0.0], "orientation_deg": 30.0}
        scene["start"]["generator_angle_deg"] = 80.0
        scene["ply"]["size_mm"] = [120, 120]
        code, output, _ = _run(tmp_path, scene, name=f"fold-{angle}")
        assert code == 0, output
        cells = pd.read_csv(next((tmp_path / f"out-fold-{angle}").glob("*/*/cells.csv")))
        # cells whose centre lies more than a spacing from the crease sit on one flank
        flank = (cells["x_mm"] < -10.0) | (cells["z_mm"] < -10.0)
        assert flank.sum() > 40
        flank_shear[angle] = np.abs(cells.loc[flank, "shear_deg"].to_numpy() + 10.0).max()
    # α = 80°: a net that keeps its flat angle has γ = −10° in every flank cell
    assert flank_shear[20.0] < 1e-6
    assert flank_shear[None] > 1.0
