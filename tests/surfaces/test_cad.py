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
    # of the node spacing (measured: 0.55 and 0.17 mm).
    assert gaps[1] < gaps[0]
    assert gaps[1] < 0.5e-3


def test_bundled_hat_stiffener_step_and_stl_are_one_surface():
    step = build_mesh(MeshTool(surface="mesh", file="hat_stiffener.step"), ".")
    stl = build_mesh(MeshTool(surface="mesh", file="hat_stiffener.stl"), ".")
    assert step.source.unit == "mm" and step.source.unit_from == "declared in the STEP file"
    assert step.n_faces == 6
    for s in (step, stl):
        assert s.hygiene.open_edges == 4 and s.hygiene.pieces == 1
    probe = np.random.default_rng(1).uniform([-0.2, -0.1], [0.2, 0.1], (200, 2))
    a, over_a = step.point_at_plan(probe)
    b, over_b = stl.point_at_plan(probe)
    assert over_a.all() and over_b.all()
    np.testing.assert_allclose(a, b, atol=1e-6)  # float32 STL


def test_faces_select_the_part(cad_dir):
    tool = build_mesh(MeshTool(surface="mesh", file="hat_stiffener.step"), ".")
    crown = tool.face_part([2])
    assert crown.area_m2 == pytest.approx(0.2 * 0.04)
    level = crown.level(np.array([[0.0, 0.0, 0.03], [0.0, 0.05, 0.0], [0.09, 0.0, 0.03]]))
    assert level[0] == pytest.approx(0.02) and level[1] < 0 and level[2] == pytest.approx(0.01)
    with pytest.raises(ValueError, match="no face 9"):
        tool.face_part([9])
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
