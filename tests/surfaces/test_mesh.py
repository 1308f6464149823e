"""Triangle meshes and their readers, checked against independent truths: dense barycentric
sampling of triangles, the analytic sphere a tessellation approximates (within its chordal
error), hand-computed wall distances, and exact file round trips."""

from __future__ import annotations

import warnings
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape.engine.surface import Surface
from preform.plugins.surfaces.mesh import (
    TriangleMesh,
    read_obj,
    read_stl,
    tessellate_hemisphere,
    write_stl,
)

R = 0.1
TOOLS = files("preform.materials") / "tools"


def chordal_bound(mesh: TriangleMesh, radius: float) -> float:
    """Largest gap between a sphere-inscribed mesh and its sphere: on a triangle every point is
    at least as far from the centre as the triangle's plane, and no farther than R."""
    corners = mesh.vertices[mesh.faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    return float(np.max(radius - np.abs(np.sum(normal * corners[:, 0], axis=1))))


def upper_points(n: int, low: float, high: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=(n, 3))
    direction[:, 2] = np.abs(direction[:, 2])
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    return direction * rng.uniform(low, high, (n, 1))


# --- the point-triangle kernel against dense sampling ------------------------------------------

vertex = st.tuples(*[st.floats(-1.0, 1.0, allow_nan=False)] * 3)


@settings(max_examples=80, deadline=None)
@given(a=vertex, b=vertex, c=vertex, p=vertex)
def test_closest_point_on_a_triangle_beats_dense_sampling(a, b, c, p) -> None:
    corners = np.array([a, b, c], dtype=float)
    doubled_area = np.linalg.norm(np.cross(corners[1] - corners[0], corners[2] - corners[0]))
    longest = np.max(np.linalg.norm(corners - np.roll(corners, 1, axis=0), axis=1))
    if doubled_area <= 1e-3 * longest**2:
        return  # near-degenerate triangles are dropped; covered by their own test
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = TriangleMesh(corners, [[0, 1, 2]], merge_tolerance_rel=0.0)
    closest, distance = mesh.closest_point(np.array([p]))
    n = 300
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    keep = u + v <= 1
    samples = (
        corners[0]
        + np.outer(u[keep], corners[1] - corners[0])
        + np.outer(v[keep], corners[2] - corners[0])
    )
    sampled = np.min(np.linalg.norm(samples - np.array(p), axis=1))
    assert distance[0] <= sampled + 1e-12
    assert distance[0] >= sampled - 2 * longest / n  # and not absurdly close: it lies on the face
    weights = mesh.barycentric(closest, np.array([0]))
    assert np.all(weights >= -1e-9)


def test_candidate_search_finds_a_large_triangle_with_a_distant_centroid() -> None:
    # A fine hemisphere plus one huge triangle whose edge passes 1 cm from the query point while
    # its centroid is metres away: a k-nearest-centroid search alone would miss it.
    sphere = tessellate_hemisphere(R, 16)
    big = np.array([[0.2, -5.0, 0.05], [0.2, 5.0, 0.05], [10.0, 0.0, 0.05]])
    vertices = np.concatenate((sphere.vertices, big))
    faces = np.concatenate((sphere.faces, [[len(sphere.vertices) + k for k in range(3)]]))
    mesh = TriangleMesh(vertices, faces)
    closest, distance = mesh.closest_point(np.array([[0.19, 0.0, 0.05]]))
    np.testing.assert_allclose(closest, [[0.2, 0.0, 0.05]], atol=1e-15)
    assert distance[0] == pytest.approx(0.01, abs=1e-15)


# --- tessellated hemisphere against the analytic sphere ----------------------------------------


def test_tessellated_hemisphere_agrees_with_the_sphere_within_the_chordal_error() -> None:
    errors, bounds, edges = [], [], []
    points = upper_points(3000, 0.7 * R, 1.3 * R, seed=2)
    sphere_distance = np.abs(np.linalg.norm(points, axis=1) - R)
    for divisions in (8, 16, 32):
        mesh = tessellate_hemisphere(R, divisions)
        assert mesh.n_triangles == 4 * divisions**2
        np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), R, rtol=1e-15)
        _, distance = mesh.closest_point(points)
        error = float(np.max(np.abs(distance - sphere_distance)))
        bound = chordal_bound(mesh, R)
        corners = mesh.vertices[mesh.faces]
        longest = float(np.max(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2)))
        # |d_mesh − d_sphere| ≤ Hausdorff gap ≤ bound; the bound is the sagitta of a triangle's
        # circumcircle, r_c²/(2R) ≲ h²/(6R) for near-equilateral faces (an edge alone: h²/(8R)).
        assert error <= bound + 1e-15
        assert error >= 0.5 * bound  # the bound is attained, not vacuous
        assert bound <= longest**2 / (6 * R) * 1.05
        errors.append(error)
        bounds.append(bound)
        edges.append(longest)
    # Second order: halving the edge length quarters the error.
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.5) & (ratios < 4.5)), ratios


def test_smooth_normals_are_closer_to_the_sphere_than_face_normals() -> None:
    faceted = tessellate_hemisphere(R, 12)
    smooth = TriangleMesh(faceted.vertices, faceted.faces, smooth_normals=True)
    points = upper_points(2000, 0.999 * R, R, seed=4)
    points = points[points[:, 2] > 0.05 * R]
    exact = points / np.linalg.norm(points, axis=1, keepdims=True)
    face_error = np.max(np.linalg.norm(faceted.normal(points) - exact, axis=1))
    smooth_error = np.max(np.linalg.norm(smooth.normal(points) - exact, axis=1))
    assert smooth_error < 0.5 * face_error
    np.testing.assert_allclose(np.linalg.norm(smooth.normal(points), axis=1), 1.0, atol=1e-14)
    # Face normals point outward (the winding is counter-clockwise seen from outside).
    assert np.all(
        np.sum(faceted.face_normals * faceted.vertices[faceted.faces].mean(axis=1), axis=1) > 0
    )


def test_point_at_plan_on_a_closed_sphere_takes_the_top_hit() -> None:
    upper = tessellate_hemisphere(R, 16)
    lower_vertices = upper.vertices * np.array([1.0, 1.0, -1.0])
    # Mirroring flips the winding; reverse it so the lower half faces outward too.
    vertices = np.concatenate((upper.vertices, lower_vertices))
    faces = np.concatenate((upper.faces, upper.faces[:, ::-1] + len(upper.vertices)))
    sphere = TriangleMesh(vertices, faces)
    plan = np.random.default_rng(6).uniform(-1.2 * R, 1.2 * R, (5000, 2))
    points, over_tool = sphere.point_at_plan(plan)
    r = np.hypot(plan[:, 0], plan[:, 1])
    bound = chordal_bound(upper, R)
    assert np.all(over_tool[r < R - bound])  # inside the polygonal silhouette
    assert not np.any(over_tool[r > R])
    top = np.sqrt(R**2 - r[over_tool] ** 2)
    # Vertical distance to the sphere can exceed the radial gap on steep faces; stay away from
    # the silhouette where the slope blows up.
    interior = r[over_tool] < 0.9 * R
    assert np.all(points[over_tool, 2] > 0)
    assert np.all(np.abs(points[over_tool, 2][interior] - top[interior]) <= 2.3 * bound)
    assert np.all(points[~over_tool, 2] == sphere.bounds[0][2])
    _, distance = sphere.closest_point(points[over_tool])
    assert np.max(distance) <= 1e-15


# --- a mesh that is not a height field ---------------------------------------------------------


def hat() -> TriangleMesh:
    return read_obj(Path(str(TOOLS / "hat_mould.obj")), units_to_m=1e-3)


def test_bundled_hat_mould() -> None:
    mesh = hat()
    assert mesh.n_triangles == 26
    assert mesh.bounds == ((-0.15, -0.1, 0.0), (0.15, 0.1, 0.04))
    assert isinstance(mesh, Surface)


@settings(max_examples=60, deadline=None)
@given(
    gap=st.floats(1e-6, 0.009),
    y=st.floats(-0.029, 0.029),
    z=st.floats(0.01, 0.03),
)
def test_closest_points_on_vertical_walls(gap: float, y: float, z: float) -> None:
    mesh = hat()
    # Beside the east wall (x = 50 mm) and nearer to it than to the plate or the top.
    point = np.array([[0.05 + gap, y, z]])
    closest, distance = mesh.closest_point(point)
    np.testing.assert_allclose(closest, [[0.05, y, z]], atol=1e-15)
    assert distance[0] == pytest.approx(gap, abs=1e-15)
    np.testing.assert_allclose(mesh.normal(point), [[1.0, 0.0, 0.0]], atol=1e-15)
    # Inside the block (the tool's solid) the walls and the top answer from behind; the plate's
    # inner edges lie under the walls, so they are never nearer than the nearest wall.
    inner = np.array([[0.05 - gap, y, z]])
    nearest = min(gap, 0.03 - abs(y), 0.04 - z, 0.1 - gap)
    assert mesh.closest_point(inner)[1][0] == pytest.approx(nearest, abs=1e-15)


def test_point_at_plan_on_the_hat_and_a_shelf() -> None:
    mesh = hat()
    plan = np.array(
        [[0.0, 0.0], [0.049, 0.029], [0.06, 0.0], [0.149, -0.099], [0.16, 0.0], [0.0, -0.2]]
    )
    points, over_tool = mesh.point_at_plan(plan)
    np.testing.assert_array_equal(over_tool, [True, True, True, True, False, False])
    np.testing.assert_allclose(points[:, 2], [0.04, 0.04, 0.0, 0.0, 0.0, 0.0], atol=1e-15)
    # Two overlapping horizontal squares: the ray must return the upper one.
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    shelf = square * np.array([0.5, 0.5, 1.0]) + np.array([0.25, 0.25, 0.2])
    vertices = np.concatenate((square, shelf))
    faces = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]
    points, over_tool = TriangleMesh(vertices, faces).point_at_plan(
        np.array([[0.5, 0.5], [0.1, 0.1], [0.7, 0.3]])
    )
    assert over_tool.all()
    np.testing.assert_allclose(points[:, 2], [0.2, 0.0, 0.2], atol=1e-15)


# --- construction: merging and degenerate triangles -------------------------------------------


def test_degenerate_triangles_are_dropped_with_a_count() -> None:
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [3, 0, 0]], dtype=float)
    faces = [[0, 1, 2], [0, 1, 3], [0, 0, 2], [1, 3, 4]]  # collinear, repeated, collinear
    with pytest.warns(UserWarning, match="dropped 3 degenerate"):
        mesh = TriangleMesh(vertices, faces)
    assert mesh.dropped_triangles == 3
    assert mesh.n_triangles == 1
    closest, distance = mesh.closest_point(np.array([[0.2, 0.2, 0.5]]))
    np.testing.assert_allclose(closest, [[0.2, 0.2, 0.0]], atol=1e-15)
    assert distance[0] == pytest.approx(0.5)
    with pytest.raises(ValueError, match="no triangle of non-zero area"), pytest.warns(UserWarning):
        TriangleMesh(vertices, [[0, 1, 3]])


def test_duplicate_vertices_merge_within_a_size_relative_tolerance() -> None:
    # Two triangles sharing an edge, each with its own copies of the shared corners.
    size = 0.5
    base = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]) * size
    nudged = base.copy()
    nudged[3:5] += 1e-8 * size
    merged = TriangleMesh(nudged, [[0, 1, 2], [3, 4, 5]])
    assert len(merged.vertices) == 4
    apart = base.copy()
    apart[3] += 1e-3 * size  # only this copy moves out of tolerance; 5 and 2 still merge
    assert len(TriangleMesh(apart, [[0, 1, 2], [3, 4, 5]]).vertices) == 5


@pytest.mark.parametrize(
    ("vertices", "faces", "message"),
    [
        (np.zeros((3, 2)), [[0, 1, 2]], "vertices"),
        ([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]], [[0, 1, 2]], "non-finite"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]], "outside"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0.0, 1.0, 2.0]], "integer"),
        ([[1, 1, 1], [1, 1, 1], [1, 1, 1]], [[0, 1, 2]], "no extent"),
    ],
)
def test_invalid_meshes_are_rejected(vertices, faces, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        TriangleMesh(vertices, faces)


# --- STL --------------------------------------------------------------------------------------


def corners_of(mesh: TriangleMesh) -> np.ndarray:
    return mesh.vertices[mesh.faces]


def test_stl_round_trips_ascii_exactly_and_binary_to_float32(tmp_path: Path) -> None:
    mesh = tessellate_hemisphere(R, 6)
    write_stl(tmp_path / "a.stl", mesh, binary=False)
    write_stl(tmp_path / "b.stl", mesh, binary=True)
    ascii_mesh = read_stl(tmp_path / "a.stl")
    binary_mesh = read_stl(tmp_path / "b.stl")
    assert (tmp_path / "a.stl").read_bytes().startswith(b"solid")
    assert (tmp_path / "b.stl").stat().st_size == 84 + 50 * mesh.n_triangles
    np.testing.assert_allclose(corners_of(ascii_mesh), corners_of(mesh), rtol=1e-15, atol=1e-18)
    np.testing.assert_allclose(corners_of(binary_mesh), corners_of(mesh), rtol=1e-7, atol=1e-9)
    assert len(binary_mesh.vertices) == len(mesh.vertices)  # corners were merged again
    # The unit factor: the same file read as metres is 1000 times larger.
    np.testing.assert_allclose(
        read_stl(tmp_path / "b.stl", units_to_m=1.0).size, 1000 * binary_mesh.size
    )


def test_binary_stl_whose_header_starts_with_solid(tmp_path: Path) -> None:
    mesh = tessellate_hemisphere(R, 2)
    write_stl(tmp_path / "trap.stl", mesh)
    data = bytearray((tmp_path / "trap.stl").read_bytes())
    data[:80] = b"solid exported by some CAD system".ljust(80, b" ")
    (tmp_path / "trap.stl").write_bytes(bytes(data))
    np.testing.assert_allclose(
        corners_of(read_stl(tmp_path / "trap.stl")), corners_of(mesh), rtol=1e-7
    )


@pytest.mark.parametrize(
    ("text", "where", "what"),
    [
        ("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n", ":4:", "vertex x y z"),
        ("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 a\n", ":4:", "not a number"),
        (
            "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n",
            ":6:",
            "2 vertices",
        ),
        ("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", ":4:", "ends inside"),
        ("solid x\nfacet normal 0 0 1\nbanana\n", ":3:", "unknown"),
        ("solid x\nendsolid x\n", "", "no triangles"),
    ],
)
def test_malformed_ascii_stl_names_file_and_line(
    tmp_path: Path, text: str, where: str, what: str
) -> None:
    path = tmp_path / "bad.stl"
    path.write_text(text)
    with pytest.raises(ValueError, match=f"bad.stl{where}.*{what}"):
        read_stl(path)


def test_truncated_binary_stl_is_rejected(tmp_path: Path) -> None:
    write_stl(tmp_path / "t.stl", tessellate_hemisphere(R, 2))
    path = tmp_path / "t.stl"
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(ValueError, match=r"t\.stl: not a valid binary STL"):
        read_stl(path)


def test_bundled_hemisphere_stl_is_the_generated_one() -> None:
    mesh = read_stl(Path(str(TOOLS / "hemisphere_r100.stl")), units_to_m=1e-3)
    reference = tessellate_hemisphere(R, 36)
    assert mesh.n_triangles == reference.n_triangles == 5184
    assert len(mesh.vertices) == len(reference.vertices)
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), R, rtol=2e-7)
    np.testing.assert_allclose(corners_of(mesh), corners_of(reference), atol=1e-8)
    assert (TOOLS / "hemisphere_r100.stl").read_bytes()[:5] != b"solid"


# --- OBJ --------------------------------------------------------------------------------------


def test_obj_quads_negative_indices_and_index_forms(tmp_path: Path) -> None:
    positive = "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 0 0 10\nf 1 2 3 4\nf 1 5 2\n"
    mixed = (
        "# a unit square and a wall, in mm\nmtllib x.mtl\no part\n"
        "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nvt 0 0\nvn 0 0 1\n"
        "f -4/1/1 -3/1/1 -2/1/1 -1/1/1\n"
        "v 0 0 10\n"
        "f 1//1 -1//1 2//1\n"
    )
    (tmp_path / "p.obj").write_text(positive)
    (tmp_path / "m.obj").write_text(mixed)
    a, b = read_obj(tmp_path / "p.obj"), read_obj(tmp_path / "m.obj")
    assert a.n_triangles == b.n_triangles == 3  # the quad fans into two
    np.testing.assert_array_equal(corners_of(a), corners_of(b))
    closest, _ = b.closest_point(np.array([[0.004, 0.004, 0.003]]))
    np.testing.assert_allclose(closest, [[0.004, 0.004, 0.0]], atol=1e-15)
    assert b.bounds == ((0.0, 0.0, 0.0), (0.01, 0.01, 0.01))


@pytest.mark.parametrize(
    ("text", "where", "what"),
    [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", ":4:", "no integer vertex index"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4:", "start at 1"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", ":4:", "at least 3"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 7\n", ":5:", "beyond"),
        ("v 0 0 0\nv 1 0 0\nf 1 2 -3\n", ":3:", "counts back"),
        ("v 0 0\n", ":1:", r"v x y z"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n3 1 2\n", ":4:", "not an OBJ statement"),
        ("v 0 0 0\n", "", "no faces"),
    ],
)
def test_malformed_obj_names_file_and_line(
    tmp_path: Path, text: str, where: str, what: str
) -> None:
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(ValueError, match=f"bad.obj{where}.*{what}"):
        read_obj(path)
