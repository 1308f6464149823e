"""Mapping a drape onto a user's shell mesh, against closed forms and against the net itself."""

from __future__ import annotations

import meshio
import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from preform.drape.engine.fields import energy_field
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.element_table import element_table, write_element_table
from preform.export.fe_mapping import map_to_mesh
from preform.export.mapped_vtu import write_mapped_vtu
from preform.export.shell_mesh import read_shell_mesh, shell_mesh
from preform.plugins.surfaces.basic import Cylinder, Hemisphere, Plane


def grid_mesh(xs: np.ndarray, ys: np.ndarray, z=lambda x, y: 0.0 * x):
    """A structured quad mesh over plan coordinates [mm], z = z(x, y) [mm]."""
    x, y = np.meshgrid(xs, ys, indexing="ij")
    pts = np.column_stack([x.ravel(), y.ravel(), np.asarray(z(x, y)).ravel()])
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    return shell_mesh(pts, corners)


def net_mesh(result):
    """The net's own valid cells as a quad mesh [mm]."""
    ni, nj = result.shape
    idx = np.arange(ni * nj).reshape(ni, nj)
    ci, cj = np.nonzero(result.valid & result.in_part)
    corners = np.column_stack([idx[ci, cj], idx[ci + 1, cj], idx[ci + 1, cj + 1], idx[ci, cj + 1]])
    return shell_mesh(1e3 * np.nan_to_num(result.nodes.reshape(-1, 3)), corners), ci, cj


@pytest.mark.parametrize("alpha_deg", [90.0, 70.0])
def test_plane_closed_form_and_uncovered_elements_reported(alpha_deg: float) -> None:
    theta = 0.3
    alpha = np.radians(alpha_deg)
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.2, 0.2)),
        orientation_rad=theta,
        generator_angle_rad=alpha,
    )
    # 7 mm elements, not aligned with the 10 mm net, and reaching past the ply's corners
    mesh = grid_mesh(np.arange(-140.0, 141.0, 7.0), np.arange(-140.0, 141.0, 7.0))
    mapping = map_to_mesh(result, mesh, nominal_thickness_mm=0.5)
    cov = mapping.covered
    assert 0.2 < cov.mean() < 0.9  # some of the mesh lies beyond the ply
    np.testing.assert_allclose(
        mapping.fibre_u[cov], [[np.cos(theta), np.sin(theta), 0]] * cov.sum(), atol=1e-9
    )
    np.testing.assert_allclose(
        mapping.fibre_v[cov],
        [[np.cos(theta + alpha), np.sin(theta + alpha), 0]] * cov.sum(),
        atol=1e-9,
    )
    np.testing.assert_allclose(mapping.shear_deg[cov], alpha_deg - 90.0, atol=1e-7)
    np.testing.assert_allclose(
        mapping.thickness_ratio[cov], 1 / np.cos(alpha - np.pi / 2), rtol=1e-9
    )
    np.testing.assert_allclose(
        mapping.thickness_mm[cov], 0.5 / np.cos(alpha - np.pi / 2), rtol=1e-9
    )
    np.testing.assert_allclose(mapping.angle_u_deg[cov], np.degrees(theta), atol=1e-7)
    np.testing.assert_allclose(mapping.angle_v_deg[cov], np.degrees(theta + alpha), atol=1e-7)
    # uncovered: exactly the elements whose centroid lies outside the draped rhombus
    c = mapping.centroid_mm[:, :2] / 10.0
    t_u = np.array([np.cos(theta), np.sin(theta)])
    t_v = np.array([np.cos(theta + alpha), np.sin(theta + alpha)])
    ab = np.linalg.solve(np.column_stack([t_u, t_v]), c.T).T  # net coordinates from the start
    inside = np.all(np.abs(ab) < 10 - 1e-6, axis=1)
    far = np.all(np.abs(ab) < 10 - 0.06, axis=1) | ~np.all(np.abs(ab) < 10 + 0.06, axis=1)
    assert np.array_equal(cov[far], inside[far])
    assert np.all(np.isnan(mapping.shear_deg[~cov])) and not mapping.past_locking[~cov].any()
    assert set(mapping.uncovered_ids.tolist()) == set(mesh.element_ids[~cov].tolist())
    assert mapping.summary()["elements_uncovered"] == int((~cov).sum())


def test_cylinder_closed_form_no_shear_and_fibres_along_axis_and_hoop() -> None:
    radius = 100.0
    result = drape(
        Cylinder(radius / 1e3, 0.6, "x"),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.2, 0.2)),
    )
    phi = np.radians(np.linspace(-40, 40, 21))
    xs = np.linspace(-80, 80, 17)
    x, p = np.meshgrid(xs, phi, indexing="ij")
    pts = np.column_stack([x.ravel(), radius * np.sin(p).ravel(), radius * np.cos(p).ravel()])
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    mesh = shell_mesh(pts, corners)
    mapping = map_to_mesh(result, mesh, energy=None)
    cov = mapping.covered
    assert cov.all()
    np.testing.assert_allclose(np.abs(mapping.fibre_u[:, 0]), 1.0, atol=1e-6)
    c = mapping.centroid_mm
    hoop = np.column_stack([np.zeros(len(c)), c[:, 2], -c[:, 1]])
    hoop /= np.linalg.norm(hoop, axis=1, keepdims=True)
    np.testing.assert_allclose(np.abs(np.sum(mapping.fibre_v * hoop, axis=1)), 1.0, atol=1e-6)
    assert np.max(np.abs(mapping.shear_deg)) < 1e-4
    np.testing.assert_allclose(mapping.thickness_ratio, 1.0, atol=1e-8)
    # directions lie in each element's plane
    assert np.max(np.abs(np.sum(mapping.fibre_u * mapping.normal, axis=1))) < 1e-12


def test_net_mapped_onto_itself_reproduces_the_net() -> None:
    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.3, 0.3)),
        generator_angle_rad=np.radians(75.0),
    )
    mesh, ci, cj = net_mesh(result)
    mapping = map_to_mesh(result, mesh)
    assert mapping.covered.all()
    assert np.array_equal(mapping.cell_i, ci) and np.array_equal(mapping.cell_j, cj)
    # the centroid of a non-planar cell is off the two-triangle surface by O(d²/R); measured
    # 0.0022° at d = 5 mm on R = 100 mm
    np.testing.assert_allclose(mapping.shear_deg, np.degrees(result.shear[ci, cj]), atol=0.005)
    dots = np.sum(mapping.fibre_u * result.fibre_u[ci, cj], axis=1)
    np.testing.assert_allclose(dots, 1.0, atol=1e-6)


def hemisphere_mesh(radius: float = 100.0, half: float = 60.0, h: float = 6.0):
    xs = np.arange(-half, half + 1e-9, h)
    return grid_mesh(xs, xs, lambda x, y: np.sqrt(radius**2 - x**2 - y**2))


def test_hemisphere_mapped_shear_converges_to_the_drape_at_the_centroids() -> None:
    """The truth is a fine drape (d = 1 mm) fitted linearly (least squares in space, over the
    12 cells nearest each centroid), independent of the mapper; the mapped shear of coarser
    drapes approaches it as d shrinks."""
    mesh = hemisphere_mesh()
    alpha = np.radians(80.0)

    def run(d):
        return drape(
            Hemisphere(0.1),
            start_xy_m=(0.0, 0.0),
            node_spacing_m=d,
            ply=PlyOutline.rectangle((0.3, 0.3)),
            generator_angle_rad=alpha,
        )

    fine = run(0.001)
    ok = fine.valid
    centres, shear = 1e3 * fine.centroid[ok], np.degrees(fine.shear[ok])
    # the element centroid on the tool (radially out by the facet's sagitta)
    at = mesh.centroids()
    at = 100.0 * at / np.linalg.norm(at, axis=1, keepdims=True)
    _, near = cKDTree(centres).query(at, k=12)
    truth = np.empty(mesh.n_elements)
    for e, rows in enumerate(near):
        normal = at[e] / 100.0
        t1 = np.cross(normal, [0.0, 0.0, 1.0] if abs(normal[2]) < 0.9 else [1.0, 0.0, 0.0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(normal, t1)
        offset = centres[rows] - at[e]
        design = np.column_stack([np.ones(len(rows)), offset @ t1, offset @ t2])
        truth[e] = np.linalg.lstsq(design, shear[rows], rcond=None)[0][0]
    errors = []
    for d in (0.01, 0.005, 0.0025):
        mapping = map_to_mesh(run(d), mesh)
        assert mapping.covered.all()
        errors.append(float(np.max(np.abs(mapping.shear_deg - truth))))
    # measured 0.080°, 0.014°, 0.0025°: second order (the drape's own error and the
    # interpolation's both shrink as d²)
    assert errors[0] > 3 * errors[1] > 9 * errors[2], errors
    assert errors[2] < 0.005, errors


@settings(max_examples=25, deadline=None)
@given(
    theta=st.floats(-np.pi, np.pi),
    ref_angle=st.floats(-np.pi, np.pi),
)
def test_angles_are_the_fibre_direction_from_the_reference_direction(theta, ref_angle) -> None:
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.02,
        ply=PlyOutline.rectangle((0.2, 0.2)),
        orientation_rad=theta,
    )
    mesh = grid_mesh(np.arange(-50.0, 51.0, 25.0), np.arange(-50.0, 51.0, 25.0))
    ref = (np.cos(ref_angle), np.sin(ref_angle), 0.3)  # projected into the plane
    mapping = map_to_mesh(result, mesh, reference_direction=ref)
    expected = (np.degrees(theta - ref_angle) + 180.0) % 360.0 - 180.0
    diff = (mapping.angle_u_deg - expected + 180.0) % 360.0 - 180.0
    assert np.max(np.abs(diff)) < 1e-6


def test_flags_caps_and_energy_come_from_the_covering_cell() -> None:
    from preform.shear.law import ShearLaw  # noqa: F401  (protocol only)

    class Law:
        locking_angle = np.radians(5.0)
        failure_angle = None

        def energy(self, gamma):
            return 10.0 * np.asarray(gamma) ** 2

    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.3, 0.3)),
    )
    energy = energy_field(result, Law())
    mesh, ci, cj = net_mesh(result)
    mapping = map_to_mesh(result, mesh, energy, thickness_cap_ratio=1.01)
    assert np.array_equal(mapping.past_locking, energy.past_locking[ci, cj])
    assert mapping.past_locking.any() and not mapping.past_locking.all()
    np.testing.assert_allclose(
        mapping.energy_J_per_m2, 10 * np.radians(mapping.shear_deg) ** 2, rtol=0.05, atol=1e-6
    )
    above = mapping.thickness_ratio > 1.01
    assert np.array_equal(mapping.above_thickness_cap, above) and above.any()
    assert mapping.thickness_ratio.max() > 1.01  # reported, not capped
    assert mapping.summary()["elements_above_thickness_cap"] == int(above.sum())


def test_table_and_vtu_read_back(tmp_path) -> None:
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
    )
    # one triangle and three quads; the last quad lies beyond the ply
    pts = [
        [0, 0, 0],
        [10, 0, 0],
        [10, 10, 0],
        [0, 10, 0],
        [20, 0, 0],
        [20, 10, 0],
        [200, 0, 0],
        [210, 0, 0],
        [210, 10, 0],
        [200, 10, 0],
    ]
    mesh = shell_mesh(
        np.array(pts, float),
        [[0, 1, 2], [0, 2, 3], [1, 4, 5, 2], [6, 7, 8, 9]],
        element_ids=np.array([11, 12, 13, 99]),
    )
    mapping = map_to_mesh(result, mesh, nominal_thickness_mm=0.3)
    assert mapping.covered.tolist() == [True, True, True, False]
    write_element_table(mapping, tmp_path / "elements.csv")
    table = pd.read_csv(tmp_path / "elements.csv")
    assert table["element_id"].tolist() == [11, 12, 13, 99]
    assert table["covered"].tolist() == [True, True, True, False]
    np.testing.assert_allclose(table["fibre_u_x"][:3], 1.0)
    np.testing.assert_allclose(table["thickness_mm"][:3], 0.3)
    assert (
        table.iloc[3]
        .drop(["element_id", "covered", "centroid_x_mm", "centroid_y_mm", "centroid_z_mm"])
        .isna()
        .all()
    )
    np.testing.assert_allclose(table["centroid_x_mm"], [20 / 3, 10 / 3, 15, 205])
    assert list(element_table(mapping).columns) == list(table.columns)

    write_mapped_vtu(mapping, tmp_path / "elements.vtu")
    back = meshio.read(tmp_path / "elements.vtu")
    np.testing.assert_allclose(back.points, mesh.points)  # mm, as given
    ids = np.concatenate(back.cell_data["element_id"])
    assert sorted(ids.tolist()) == [11, 12, 13, 99]
    covered = np.concatenate(back.cell_data["covered"])
    assert dict(zip(ids.tolist(), covered.tolist(), strict=True)) == {11: 1, 12: 1, 13: 1, 99: 0}


def test_readers_keep_abaqus_and_nastran_labels(tmp_path) -> None:
    inp = tmp_path / "part.inp"
    inp.write_text(
        "*HEADING\n** a comment\n*NODE\n101, 0., 0., 0.\n102, 1., 0., 0.\n103, 1., 1., 0.\n"
        "104, 0., 1., 0.\n*ELEMENT, TYPE=S4R, ELSET=SKIN\n7, 101, 102, 103, 104\n"
        "*ELEMENT, TYPE=S3\n9, 101, 103, 104\n*ELEMENT, TYPE=C3D4\n50, 101, 102, 103, 104\n"
    )
    mesh = read_shell_mesh(inp, unit_mm=1000.0)  # the file is in metres
    assert mesh.element_ids.tolist() == [7, 9]
    assert mesh.node_ids.tolist() == [101, 102, 103, 104]
    np.testing.assert_allclose(mesh.centroids(), [[500, 500, 0], [1000 / 3, 2000 / 3, 0]])
    np.testing.assert_allclose(mesh.normals(), [[0, 0, 1], [0, 0, 1]])

    bdf = tmp_path / "part.bdf"
    bdf.write_text(
        "$ free field and small field\n"
        "GRID,1,,0.,0.,0.\n"
        "GRID           2        10.0     0.0     0.0\n"
        "GRID,3,,10.,10.,0.\nGRID,4,,0.,1.+1,0.\n"
        "CQUAD4,21,5,1,2,3,4\nCTRIA3  22      6       1       3       4\n"
    )
    mesh = read_shell_mesh(bdf)
    assert mesh.element_ids.tolist() == [21, 22] and mesh.property_ids.tolist() == [5, 6]
    np.testing.assert_allclose(mesh.points[3], [0, 10, 0])
    with pytest.raises(ValueError, match="no shell elements"):
        (tmp_path / "empty.inp").write_text("*NODE\n1, 0, 0, 0\n")
        read_shell_mesh(tmp_path / "empty.inp")


def test_our_own_tool_mesh_reads_through_meshio_and_maps() -> None:
    """The bundled hemisphere STL (mm): triangles labelled by position, every element the
    drape reaches is covered, and each mapped direction lies in its triangle's plane."""
    from preform.pipeline.scene import bundled_scene_dir

    mesh = read_shell_mesh(bundled_scene_dir().parent / "tools" / "hemisphere_r100.stl")
    assert mesh.labels_from == "position" and mesh.is_triangle.all()
    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.12, 0.12)),
    )
    mapping = map_to_mesh(result, mesh)
    cov = mapping.covered
    assert 0 < cov.sum() < mesh.n_elements
    # every element whose centroid is within 40 mm of the axis lies under the 120 mm ply
    near_axis = np.hypot(*mapping.centroid_mm[:, :2].T) < 40.0
    assert near_axis.any() and cov[near_axis].all()
    dots = np.abs(np.sum(mapping.fibre_u[cov] * mapping.normal[cov], axis=1))
    assert dots.max() < 1e-9
    np.testing.assert_allclose(np.linalg.norm(mapping.fibre_v[cov], axis=1), 1.0)


def test_far_and_degenerate_elements_are_not_covered() -> None:
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
    )
    pts = np.array(
        [
            [0, 0, 0],
            [10, 0, 0],
            [10, 10, 0],
            [0, 10, 0],
            [0, 0, 30],
            [10, 0, 30],
            [10, 10, 30],
            [20, 0, 0],
        ],
        float,
    )
    # on the ply; 30 mm above it (gap > d = 10 mm); a zero-area sliver on the ply
    mesh = shell_mesh(pts, [[0, 1, 2, 3], [4, 5, 6], [0, 1, 7]])
    mapping = map_to_mesh(result, mesh)
    assert mapping.covered.tolist() == [True, False, False]
    np.testing.assert_allclose(mapping.gap_mm[1], 30.0)
    assert map_to_mesh(result, mesh, max_gap_mm=31.0).covered.tolist() == [True, True, False]


def test_element_table_parquet_keeps_dtypes(tmp_path) -> None:
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
    )
    pts = np.array(
        [[0, 0, 0], [10, 0, 0], [10, 10, 0], [300, 0, 0], [310, 0, 0], [310, 10, 0]], float
    )
    mapping = map_to_mesh(result, shell_mesh(pts, [[0, 1, 2], [3, 4, 5]]))
    write_element_table(mapping, tmp_path / "elements.parquet")
    table = pd.read_parquet(tmp_path / "elements.parquet")
    assert table["covered"].tolist() == [True, False]
    assert str(table["past_locking"].dtype) == "boolean" and table[
        "past_locking"
    ].isna().tolist() == [False, True]
    np.testing.assert_allclose(table["shear_deg"][0], 0.0, atol=1e-9)
