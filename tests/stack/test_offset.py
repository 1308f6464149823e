"""Offset tools (preform.drape.engine.offset): exact for analytic tools, vertex normals for meshes,
folds reported where a concave radius is smaller than the offset."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape.engine.offset import EXACT, VERTEX_NORMALS, OffsetError, offset_tool
from preform.plugins.surfaces.basic import Cylinder, Hemisphere, Plane, Sphere
from preform.plugins.surfaces.domes import Cone
from preform.plugins.surfaces.mesh import TriangleMesh, tessellate_hemisphere


@settings(max_examples=30, deadline=None)
@given(
    radius=st.floats(0.01, 2.0),
    thickness=st.floats(1e-5, 5e-3),
    plies=st.integers(1, 12),
)
def test_a_sphere_offset_by_k_plies_is_the_sphere_of_radius_r_plus_k_t(
    radius: float, thickness: float, plies: int
) -> None:
    made = offset_tool(Hemisphere(radius, run_off_m=0.25 * radius), plies * thickness)
    assert made.method == EXACT
    # independent truth: every point's closest point lies at R + k·t from the centre
    rng = np.random.default_rng(0)
    directions = rng.normal(size=(200, 3))
    directions[:, 2] = np.abs(directions[:, 2])
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    foot, _ = made.surface.closest_point(3.0 * radius * directions)
    assert np.abs(np.linalg.norm(foot, axis=1) - (radius + plies * thickness)).max() < 1e-9
    # the run-off keeps its angle below the rim, so the offset tool reaches as far round
    floor = made.surface.bounds[0][2]
    assert floor / made.surface.radius == pytest.approx(-0.25, abs=1e-12)


def test_plane_sphere_and_cylinder_offsets_move_every_point_by_the_distance() -> None:
    h = 1.5e-3
    plane = offset_tool(Plane((0.4, 0.3)), h).surface
    assert plane.bounds[0][2] == pytest.approx(h, abs=1e-15)
    foot, _ = plane.closest_point(np.array([[0.05, -0.02, 1.0]]))
    assert foot[0, 2] == pytest.approx(h, abs=1e-15)
    sphere = offset_tool(Sphere(0.1, centre_m=(0.0, 0.0, 0.2)), h).surface
    foot, _ = sphere.closest_point(np.array([[0.3, 0.0, 0.2]]))
    assert foot[0, 0] == pytest.approx(0.1 + h, abs=1e-15)
    cylinder = offset_tool(Cylinder(0.05, 0.4, "y"), h).surface
    foot, _ = cylinder.closest_point(np.array([[0.0, 0.1, 1.0]]))
    assert foot[0, 2] == pytest.approx(0.05 + h, abs=1e-15)


def test_a_tool_without_an_offset_is_refused_in_words() -> None:
    with pytest.raises(OffsetError, match="give the tool as a mesh"):
        offset_tool(Cone(0.1, 0.05), 1e-3)
    with pytest.raises(OffsetError, match="one distance"):
        offset_tool(Plane((0.1, 0.1)), np.full(4, 1e-3))
    with pytest.raises(OffsetError, match="non-negative"):
        offset_tool(Plane((0.1, 0.1)), -1e-3)


def test_a_mesh_sphere_offset_lies_on_r_plus_h_within_the_tessellation_tolerance() -> None:
    radius, h = 0.1, 2.4e-3
    mesh = tessellate_hemisphere(radius, 24)
    made = offset_tool(mesh, h)
    assert made.method == VERTEX_NORMALS
    edges = mesh.vertices[mesh.faces] - np.roll(mesh.vertices[mesh.faces], 1, axis=1)
    longest = float(np.linalg.norm(edges, axis=2).max())
    # the tessellation tolerance: the sag of the longest chord below its sphere
    sag = radius - np.sqrt(radius**2 - (0.5 * longest) ** 2)
    moved = made.surface.vertices
    assert np.abs(np.linalg.norm(moved, axis=1) - (radius + h)).max() <= sag
    centroids = moved[made.surface.faces].mean(axis=1)
    gap = radius + h - np.linalg.norm(centroids, axis=1)
    assert gap.min() >= -1e-12 and gap.max() <= sag * (radius + h) / radius * 1.5
    # and the mesh offset is further from the exact one than rounding (it is a mesh)
    assert np.abs(np.linalg.norm(moved, axis=1) - (radius + h)).max() > 1e-12


def _concave_channel(radius: float, length: float = 0.05, n: int = 24) -> TriangleMesh:
    """The inside of a half-pipe of ``radius`` [m] along x, seen from above (its normals point
    at the axis): concave with that radius."""
    theta = np.linspace(np.pi, 2.0 * np.pi, n + 1)  # the lower half, y from −r to r
    x = np.linspace(0.0, length, 6)
    tt, xx = np.meshgrid(theta, x, indexing="ij")
    points = np.column_stack(
        [xx.ravel(), radius * np.cos(tt).ravel(), radius + radius * np.sin(tt).ravel()]
    )
    index = np.arange(points.shape[0]).reshape(tt.shape)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    mesh = TriangleMesh(points, faces)
    # the winding makes the normals point up out of the channel, at the axis
    if mesh.face_normals[:, 2].mean() < 0:
        mesh = TriangleMesh(points, faces[:, ::-1])
    return mesh


def test_a_concave_radius_smaller_than_the_stack_is_reported_with_where() -> None:
    channel = _concave_channel(5e-3)
    made = offset_tool(channel, 3e-3)  # below the radius: a smaller channel, no fold
    assert made.distance_max_m == pytest.approx(3e-3)
    with pytest.raises(OffsetError) as info:
        offset_tool(channel, 8e-3)  # beyond it: the offset crosses itself
    message = str(info.value)
    assert "folds over itself" in message and "concave" in message
    assert "8 mm" in message and "triangle(s)" in message


def test_a_per_vertex_offset_follows_the_thickness_at_each_vertex() -> None:
    vertices = np.array([[x, y, 0.0] for y in (0.0, 0.1) for x in (0.0, 0.1, 0.2)])
    faces = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
    mesh = TriangleMesh(vertices, faces)
    distance = np.array([1e-3, 2e-3, 0.0, 1e-3, 2e-3, 0.0])
    moved = offset_tool(mesh, distance).surface
    assert np.allclose(moved.vertices[:, 2], distance, atol=1e-15)
    assert np.allclose(moved.vertices[:, :2], vertices[:, :2], atol=1e-15)
