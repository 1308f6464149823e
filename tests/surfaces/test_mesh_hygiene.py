"""Mesh hygiene (preform.plugins.surfaces.mesh_hygiene) on hand-built broken meshes, and the
drape of a repaired broken mesh against the drape of the clean one."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape import PlyOutline, drape
from preform.plugins.surfaces.mesh import tessellate_hemisphere
from preform.plugins.surfaces.mesh_hygiene import MeshRefused, repair
from preform.plugins.surfaces.tool_mesh import ToolMesh, ToolSource

SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
HEMI = tessellate_hemisphere(0.1, 8)


def triangles(vertices, faces):
    """The mesh as a set of triangles, each its corner coordinates (rounded) in winding order
    starting at the smallest corner: independent of vertex numbering and triangle order."""
    out = set()
    for tri in np.round(vertices[faces], 9):
        corners = [tuple(c) for c in tri]
        k = corners.index(min(corners))
        out.add(tuple(corners[k:] + corners[:k]))
    return out


def soup(vertices, faces):
    """Every triangle with its own copies of its corners, as STL stores them."""
    corners = vertices[faces].reshape(-1, 3)
    return corners, np.arange(corners.shape[0]).reshape(-1, 3)


def edge_use(faces):
    edges = np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    _, count = np.unique(edges, axis=0, return_counts=True)
    return count


def test_a_clean_mesh_is_left_as_it_is():
    fixed = repair(HEMI.vertices, HEMI.faces)
    assert triangles(fixed.vertices, fixed.faces) == triangles(HEMI.vertices, HEMI.faces)
    assert fixed.report.repairs() == []
    assert fixed.report.pieces == 1


def test_duplicate_vertices_are_welded_and_counted():
    v, f = soup(HEMI.vertices, HEMI.faces)
    fixed = repair(v, f)
    assert fixed.report.duplicate_vertices == v.shape[0] - HEMI.vertices.shape[0]
    assert fixed.report.cracks_welded == 0
    assert fixed.vertices.shape == HEMI.vertices.shape
    assert triangles(fixed.vertices, fixed.faces) == triangles(HEMI.vertices, HEMI.faces)


def test_a_crack_within_the_tolerance_is_closed_and_said():
    # Two squares meeting along x = 1, the right one's copy of the seam 1 µm away.
    right = SQUARE + np.array([1.0, 0.0, 0.0])
    right[[0, 3], 0] += 1e-6
    v = np.vstack([SQUARE, right])
    f = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    assert np.count_nonzero(edge_use(f) == 1) == 8  # the seam is open: unwelded
    fixed = repair(v, f, weld_tolerance_m=1e-5)
    assert fixed.report.cracks_welded == 2
    assert np.count_nonzero(edge_use(fixed.faces) == 1) == 6  # only the outline is open
    assert any("cracks" in r for r in fixed.report.repairs())
    # Below the gap, the crack stays (and is not said to be closed).
    assert repair(v, f, weld_tolerance_m=1e-7).report.cracks_welded == 0


def test_a_t_junction_is_split_so_the_edge_is_shared():
    v = np.vstack([SQUARE, [[0.5, 0.5, 0.0]]])
    # One triangle spans the diagonal 0-2; the other side is two triangles meeting at 4.
    f = np.array([[0, 1, 2], [0, 4, 3], [4, 2, 3]])
    fixed = repair(v, f, weld_tolerance_m=1e-9)
    assert fixed.report.t_junctions_split == 1
    count = edge_use(fixed.faces)
    assert np.count_nonzero(count == 1) == 4 and np.count_nonzero(count == 2) == 4
    area = 0.5 * np.linalg.norm(
        np.cross(*(np.diff(fixed.vertices[fixed.faces], axis=1).transpose(1, 0, 2))), axis=1
    )
    assert area.sum() == pytest.approx(1.0, abs=1e-12)
    normals = np.cross(*(np.diff(fixed.vertices[fixed.faces], axis=1).transpose(1, 0, 2)))
    assert np.all(normals[:, 2] > 0)  # all wound up, as the input was


def test_a_collinear_triangle_is_dropped_and_its_neighbour_split():
    v = np.vstack([SQUARE, [[0.5, 0.0, 0.0]]])
    # (0, 4, 1) has no area; across its long edge 0-1 nothing, across 0-4 and 4-1 the rest.
    f = np.array([[0, 4, 1], [0, 1, 2], [0, 2, 3]])
    fixed = repair(v, f, weld_tolerance_m=1e-9)
    assert fixed.report.degenerate_dropped == 1
    assert fixed.faces.shape[0] == 2  # the dropped needle leaves nothing hanging (4 unused)
    f2 = np.array([[0, 4, 2], [4, 1, 2], [0, 1, 2], [0, 2, 3]])  # a duplicate over 0-1-2
    with pytest.raises(MeshRefused, match="non-manifold"):
        repair(v, f2, weld_tolerance_m=1e-9)


def test_duplicate_triangles_of_either_winding_are_dropped():
    f = np.vstack([HEMI.faces, HEMI.faces[:5], HEMI.faces[5:9, ::-1]])
    fixed = repair(HEMI.vertices, f)
    assert fixed.report.duplicate_triangles_dropped == 9
    assert triangles(fixed.vertices, fixed.faces) == triangles(HEMI.vertices, HEMI.faces)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.booleans(), min_size=HEMI.n_triangles, max_size=HEMI.n_triangles))
def test_any_set_of_flipped_triangles_is_rewound_as_the_clean_mesh(flips):
    f = HEMI.faces.copy()
    flip = np.array(flips)
    f[flip] = f[flip][:, ::-1]
    fixed = repair(HEMI.vertices, f)
    # An open dome is wound so its normals point up, whatever the majority was.
    assert triangles(fixed.vertices, fixed.faces) == triangles(HEMI.vertices, HEMI.faces)


def test_a_closed_solid_is_wound_outward():
    octa = np.array([[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    top = [[k, (k + 1) % 4, 4] for k in range(4)]
    bottom = [[(k + 1) % 4, k, 5] for k in range(4)]
    inside_out = np.array(top + bottom)[:, ::-1]
    fixed = repair(octa, inside_out)
    corners = fixed.vertices[fixed.faces]
    volume = np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum() / 6
    assert volume == pytest.approx(4 / 3)  # the octahedron's volume, positive: outward
    assert fixed.report.pieces_turned == 1


def test_non_manifold_and_one_sided_meshes_are_refused_with_where():
    fin = np.vstack([SQUARE, [[0.5, 0.5, 1.0]]])
    with pytest.raises(MeshRefused, match=r"\(500, 500, 0\) mm .*3 triangles"):
        repair(fin, np.array([[0, 1, 2], [0, 2, 3], [0, 2, 4]]))
    n = 12
    angle = np.linspace(0, 2 * np.pi, n, endpoint=False)
    band = []
    for a in angle:
        for s in (-0.3, 0.3):
            r = 1 + s * np.cos(a / 2)
            band.append([r * np.cos(a), r * np.sin(a), s * np.sin(a / 2)])
    faces = []
    for i in range(n):
        a0, a1 = 2 * i, 2 * i + 1
        b0, b1 = (1, 0) if i == n - 1 else (2 * i + 2, 2 * i + 3)  # the half twist
        faces += [[a0, b0, a1], [a1, b0, b1]]
    with pytest.raises(MeshRefused, match=r"Möbius.*mm"):
        repair(np.array(band), np.array(faces))


def test_slivers_are_counted_located_and_kept():
    v = np.array([[0, 0, 0], [1, 0, 0], [0.5, 0.001, 0], [0.5, 1, 0]], dtype=float)
    fixed = repair(v, np.array([[0, 1, 2], [0, 2, 3], [2, 1, 3]]), weld_tolerance_m=1e-9)
    assert fixed.report.slivers == 1 and fixed.faces.shape[0] == 3
    assert fixed.report.worst_sliver_at_m == pytest.approx((0.5, 0.001 / 3, 0.0))
    assert "sliver" in " ".join(fixed.report.remarks()) and fixed.report.repairs() == []


def _tool(vertices, faces, weld=None):
    fixed = repair(vertices, faces, weld)
    return ToolMesh(fixed, None, {}, ToolSource("test", "STL", "m", "test"))


def _drape(surface):
    return drape(
        surface,
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.24, 0.24)),
        # Inside a triangle: at the pole four triangles tie, and which one answers the start's
        # normal would then depend on 0.1 µm of weld.
        start_xy_m=(0.0031, 0.0017),
        generator_angle_rad=np.radians(80.0),
    )


def test_broken_versions_of_a_mesh_drape_as_the_clean_mesh():
    mesh = tessellate_hemisphere(0.1, 16)
    clean = _drape(_tool(mesh.vertices, mesh.faces))
    v, f = soup(mesh.vertices, mesh.faces)
    rng = np.random.default_rng(7)
    # Cracks: every corner copy moved by up to 0.1 µm (welded at 1 µm); some triangles
    # wound the wrong way; some duplicated.
    cracked = v + rng.uniform(-1e-7, 1e-7, v.shape)
    f = f.copy()
    flip = rng.random(f.shape[0]) < 0.3
    f[flip] = f[flip][:, ::-1]
    f = np.vstack([f, f[:40]])
    broken = _drape(_tool(cracked, f, weld=1e-6))
    assert np.array_equal(broken.status, clean.status)
    placed = clean.status == 0
    assert placed.sum() > 400
    # Welded vertices sit within 0.1 µm of the clean ones; the net moves by as little.
    assert np.max(np.abs(broken.nodes[placed] - clean.nodes[placed])) < 1e-6
    duplicated = _drape(_tool(*soup(mesh.vertices, mesh.faces)))
    assert np.array_equal(duplicated.status, clean.status)
    np.testing.assert_allclose(duplicated.nodes[placed], clean.nodes[placed], atol=1e-12)


def test_long_edges_are_split_without_changing_the_surface():
    # A flat sliver-prone strip: 1 × 0.1 in two triangles, no edge over 0.05 afterwards.
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 0.1, 0], [0, 0.1, 0]], dtype=float)
    fixed = repair(v, np.array([[0, 1, 2], [0, 2, 3]]), max_edge_m=0.05)
    corners = fixed.vertices[fixed.faces]
    edges = np.roll(corners, -1, axis=1) - corners
    assert np.linalg.norm(edges, axis=2).max() <= 0.05
    normals = np.cross(edges[:, 0], -edges[:, 2])
    assert np.all(normals[:, 2] > 0)  # winding kept
    assert 0.5 * normals[:, 2].sum() == pytest.approx(0.1, rel=1e-12)  # area kept
    count = edge_use(fixed.faces)
    assert count.max() == 2  # conforming: no edge hangs
    # The open edges are the strip's outline, cut into pieces no longer than 0.05.
    outline = 2 * (1 + 0.1)
    open_length = sum(
        np.linalg.norm(fixed.vertices[a] - fixed.vertices[b])
        for a, b in np.unique(
            np.sort(np.stack([fixed.faces, np.roll(fixed.faces, -1, 1)], 2).reshape(-1, 2), 1),
            axis=0,
        )[count == 1]
    )
    assert open_length == pytest.approx(outline)
    assert fixed.report.refined_triangles == fixed.faces.shape[0] - 2
    assert fixed.report.open_edges == 4  # counted before the split: the input's outline
