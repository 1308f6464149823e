"""STEP and IGES tools (preform.plugins.surfaces.cad) and the tool block reading them: units
from the file, the tessellation tolerance held, STEP and STL of one tool draping alike, face
selection as the part, and located refusals."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from preform.drape import PlyOutline, drape
from preform.plugins.surfaces.cad import CadError, declared_unit, read_cad
from preform.plugins.surfaces.mesh import tessellate_hemisphere
from preform.plugins.surfaces.mesh_hygiene import repair
from preform.plugins.surfaces.tool_mesh import ToolMesh, ToolSource
from preform.plugins.surfaces.tools import MeshTool, build_mesh, resolve_tool_file

gmsh = pytest.importorskip("gmsh")
R_MM = 100.0


def _write(path: Path, build) -> Path:
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        build(gmsh.model.occ)
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


@pytest.fixture(scope="module")
def cad_dir(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("cad")

    def dome(occ):
        # The spherical face of a hemisphere of radius R on z = 0, without its base disc.
        occ.addSphere(0, 0, 0, R_MM, angle1=0)
        occ.synchronize()
        occ.remove([(3, 1)])
        for dim, tag in gmsh.model.getEntities(2):
            if gmsh.model.getType(dim, tag) == "Plane":
                occ.remove([(dim, tag)], recursive=True)

    def box(occ):
        occ.addBox(0, 0, 0, 100, 60, 40)

    _write(folder / "dome.step", dome)
    _write(folder / "box.step", box)
    _write(folder / "box.igs", box)
    text = (folder / "box.step").read_text()
    assert "SI_UNIT(.MILLI.,.METRE.)" in text
    (folder / "box_m.step").write_text(
        text.replace("SI_UNIT(.MILLI.,.METRE.)", "SI_UNIT($,.METRE.)")
    )
    return folder


def test_the_unit_comes_from_the_file(cad_dir):
    mm, m = read_cad(cad_dir / "box.step"), read_cad(cad_dir / "box_m.step")
    assert (mm.unit, m.unit) == ("mm", "m")
    np.testing.assert_allclose(mm.vertices.max(axis=0), [0.1, 0.06, 0.04], atol=1e-9)
    np.testing.assert_allclose(m.vertices.max(axis=0), [100.0, 60.0, 40.0], atol=1e-6)
    iges = read_cad(cad_dir / "box.igs")
    assert declared_unit(cad_dir / "box.igs") == iges.unit == "mm"
    np.testing.assert_allclose(iges.vertices.max(axis=0), [0.1, 0.06, 0.04], atol=1e-9)
    assert mm.n_faces == iges.n_faces == 6


def test_the_facets_stay_within_the_tessellation_tolerance(cad_dir):
    counts = []
    for tol_mm in (0.5, 0.1, 0.02):
        cad = read_cad(cad_dir / "dome.step", tol_mm * 1e-3)
        corners = cad.vertices[cad.faces]
        # Every vertex on the sphere; the facets' deepest points (centroids and edge midpoints
        # among them) within the tolerance inside it.
        assert np.abs(np.linalg.norm(cad.vertices, axis=1) - R_MM * 1e-3).max() < 1e-9
        probes = np.concatenate(
            [corners.mean(axis=1), 0.5 * (corners + np.roll(corners, 1, 1)).reshape(-1, 3)]
        )
        sag = R_MM * 1e-3 - np.linalg.norm(probes, axis=1)
        assert sag.max() <= tol_mm * 1e-3 * 1.01
        counts.append(cad.faces.shape[0])
    assert counts[0] < counts[1] < counts[2]


def _tool_mesh(vertices, faces):
    return ToolMesh(repair(vertices, faces), None, {}, ToolSource("t", "STL", "m", "t"))


def _nodes(surface):
    result = drape(
        surface,
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.24, 0.24)),
        start_xy_m=(0.0031, 0.0017),
        generator_angle_rad=np.radians(80.0),
    )
    return result.nodes, result.status == 0


def test_step_and_stl_of_one_tool_drape_alike_within_the_tessellation(cad_dir):
    # The STL: an independent tessellation of the same dome (sag about 0.008 mm).
    stl = tessellate_hemisphere(R_MM * 1e-3, 64)
    stl_nodes, stl_placed = _nodes(_tool_mesh(stl.vertices, stl.faces))
    gaps = []
    for tol_mm in (0.5, 0.02):
        cad = read_cad(cad_dir / "dome.step", tol_mm * 1e-3)
        nodes, placed = _nodes(_tool_mesh(cad.vertices, cad.faces))
        both = placed & stl_placed
        # The same nodes are placed, but for a few at the rim, where the facets end.
        assert both.sum() >= 0.98 * max(placed.sum(), stl_placed.sum())
        gaps.append(np.linalg.norm(nodes - stl_nodes, axis=2)[both].max())
    # The drapes part by less as the tolerance falls, and at 0.02 mm by well under a tenth
    # of the node spacing (measured: 1.2 and 0.26 mm; 0.38 mm at 0.1 mm).
    assert gaps[1] < gaps[0]
    assert gaps[1] < 0.5e-3


@pytest.fixture(scope="module")
def hat():
    return build_mesh(MeshTool(surface="mesh", file="hat_stiffener.step"), ".")


def test_bundled_hat_stiffener_is_the_tool_its_script_describes(hat):
    assert hat.source.unit == "mm" and hat.source.unit_from == "declared in the STEP file"
    # One closed solid once its faces' shared edges are joined (OpenCASCADE leaves T-junctions
    # where a fillet meets a plane: hygiene splits them).
    assert hat.hygiene.open_edges == 0 and hat.hygiene.pieces == 1
    assert hat.hygiene.t_junctions_split > 0
    # Heights over the flat faces, from the script's dimensions: crown z = 30 mm, plate z = 0,
    # webs rising at 60° from the foot |y| = 20 + 30/tan 60° (away from the rounded corners).
    foot_y = 20 + 30 / np.tan(np.radians(60))
    rng = np.random.default_rng(1)
    crown = np.column_stack([rng.uniform(-95, 95, 50), rng.uniform(-19, 19, 50)])
    plate = np.column_stack([rng.uniform(-190, 190, 50), rng.choice([-1, 1], 50) * 80])
    web = np.column_stack([rng.uniform(-80, 80, 50), rng.uniform(21, foot_y - 1, 50)])
    points, over = hat.point_at_plan(np.vstack([crown, plate, web]) * 1e-3)
    assert over.all()
    expected = np.concatenate(
        [np.full(50, 30.0), np.zeros(50), (foot_y - web[:, 1]) * np.tan(np.radians(60))]
    )
    np.testing.assert_allclose(points[:, 2] * 1e3, expected, atol=1e-6)
    # Splitting long edges left the surface as it was: the same area as tessellated.
    unsplit = build_mesh(MeshTool(surface="mesh", file="hat_stiffener.step", max_edge_mm=1e3), ".")
    assert unsplit.hygiene.refined_triangles == 0 < hat.hygiene.refined_triangles

    def area(mesh):
        c = mesh.vertices[mesh.faces]
        return 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum()

    assert area(hat) == pytest.approx(area(unsplit), rel=1e-12)


def test_the_hat_stiffener_faces_are_numbered_as_its_scene_says(hat):
    tool = hat
    assert tool.n_faces == 15
    corners = tool.vertices[tool.faces]
    for number in range(1, 16):
        z = corners[tool.face_label == number][..., 2]
        on_hat = z.max() > 1e-3 and z.min() > -1e-9
        assert on_hat == (number >= 7), number  # 1-6 the plate, 7-15 the hat
    crown = corners[tool.face_label == 15]
    assert np.allclose(crown[..., 2], 0.03)


def test_faces_select_the_part(hat):
    tool = hat
    crown = tool.face_part([15])
    level = crown.level(np.array([[0.0, 0.015, 0.03], [0.0, 0.06, 0.0], [0.09, 0.0, 0.03]]))
    # φ is the distance to the crown's edge: 5 mm from its long edge, 10 mm from its end.
    assert level[0] == pytest.approx(0.005, abs=1e-9)
    assert level[2] == pytest.approx(0.01, abs=1e-9)
    assert level[1] < 0  # on the plate
    with pytest.raises(ValueError, match="no face 99"):
        tool.face_part([99])
    obj = build_mesh(MeshTool(surface="mesh", file="hat_mould.obj"), ".")
    block = obj.face_part(["block"])
    assert block.area_m2 == pytest.approx(0.1 * 0.06 + 2 * 0.1 * 0.04 + 2 * 0.06 * 0.04)
    with pytest.raises(ValueError, match="named: 'block', 'plate'"):
        obj.face_part(["lid"])


def test_unreadable_cad_is_refused_with_where(tmp_path, cad_dir):
    not_step = tmp_path / "a.step"
    not_step.write_text("solid x\nendsolid x\n")
    with pytest.raises(CadError, match=r"a\.step:1: not a STEP file"):
        read_cad(not_step)
    cut = tmp_path / "cut.step"
    cut.write_text((cad_dir / "box.step").read_text()[:2000])
    with pytest.raises(CadError, match=r"cut\.step:\d+: .*END-ISO-10303-21"):
        read_cad(cut)
    garbled = tmp_path / "garbled.step"
    garbled.write_text("ISO-10303-21;\nHEADER;\nnonsense\nEND-ISO-10303-21;\n")
    with pytest.raises(CadError, match=r"garbled\.step: cannot be read as STEP: .*Line \d"):
        read_cad(garbled)
    not_iges = tmp_path / "b.igs"
    not_iges.write_text("hello\n")
    with pytest.raises(CadError, match=r"b\.igs:1: not an IGES file"):
        read_cad(not_iges)


def test_without_gmsh_the_error_says_how_to_install_it(monkeypatch, cad_dir):
    monkeypatch.setitem(sys.modules, "gmsh", None)
    with pytest.raises(CadError, match=r'pip install "preform\[cad\]"'):
        read_cad(cad_dir / "box.step")


def test_the_tool_block_checks_its_fields_per_format():
    with pytest.raises(ValueError, match="declares its own length unit"):
        MeshTool(surface="mesh", file="x.step", units="mm")
    with pytest.raises(ValueError, match="tessellation_tolerance_mm is for STEP"):
        MeshTool(surface="mesh", file="x.stl", tessellation_tolerance_mm=0.1)
    assert resolve_tool_file("hat_stiffener.step", ".").name == "hat_stiffener.step"
