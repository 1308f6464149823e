"""The walking kernels on triangle meshes against closed forms: on a plane (however it is
triangulated) a net node completes a rhombus and a geodesic is a straight line; across a
crease a geodesic is the straight line of the unfolded plate; the topology pairs every
interior edge with its twin."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape.result import NodeStatus
from preform.plugins.surfaces.mesh import TriangleMesh


def jittered_plane(seed: int, tilt: float, n: int = 12, size: float = 0.2) -> TriangleMesh:
    """A square plane of side ``size`` [m] tilted by ``tilt`` [rad] about x, triangulated from
    a grid whose interior vertices are jittered in the plane (irregular triangles)."""
    rng = np.random.default_rng(seed)
    s = np.linspace(-size / 2, size / 2, n)
    u, v = np.meshgrid(s, s, indexing="ij")
    h = size / (n - 1)
    inner = (np.abs(u) < size / 2 - 1e-12) & (np.abs(v) < size / 2 - 1e-12)
    u = u + np.where(inner, rng.uniform(-0.3, 0.3, u.shape) * h, 0.0)
    v = v + np.where(inner, rng.uniform(-0.3, 0.3, v.shape) * h, 0.0)
    ey = np.array([0.0, math.cos(tilt), math.sin(tilt)])
    verts = u.ravel()[:, None] * np.array([1.0, 0.0, 0.0]) + v.ravel()[:, None] * ey
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            if rng.random() < 0.5:
                faces += [[a, a + n, a + n + 1], [a, a + n + 1, a + 1]]
            else:
                faces += [[a, a + n, a + 1], [a + n, a + n + 1, a + 1]]
    return TriangleMesh(verts, np.array(faces))


def plane_frame(tilt: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([1.0, 0.0, 0.0]), np.array([0.0, math.cos(tilt), math.sin(tilt)])


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**16),
    tilt=st.floats(-1.2, 1.2),
    angle=st.floats(0.3, 2.8),
    turn=st.floats(0.0, 2 * math.pi),
    spacing=st.floats(0.004, 0.03),
)
def test_on_a_plane_a_node_completes_the_rhombus(
    seed: int, tilt: float, angle: float, turn: float, spacing: float
) -> None:
    mesh = jittered_plane(seed, tilt)
    ex, ey = plane_frame(tilt)
    e1 = math.cos(turn) * ex + math.sin(turn) * ey
    e2 = math.cos(turn + angle) * ex + math.sin(turn + angle) * ey
    c = 0.01 * ex - 0.02 * ey
    a, b = c + spacing * e1, c + spacing * e2
    placed = mesh.place_nodes_from_faces(
        a[None], b[None], c[None], spacing, mesh.locate_faces(a[None]), mesh.locate_faces(b[None])
    )
    assert placed.status[0] == NodeStatus.PLACED
    np.testing.assert_allclose(placed.points[0], a + b - c, atol=1e-12)
    # the plain protocol (parents' triangles located first) gives the same node
    points, status = mesh.place_nodes(a[None], b[None], c[None], spacing)
    assert status[0] == NodeStatus.PLACED
    np.testing.assert_allclose(points[0], placed.points[0], atol=1e-15)
    # the triangle it names holds it, and the normal is the plane's
    weights = mesh.barycentric(placed.points, placed.faces)
    assert np.all(weights >= -1e-9)
    np.testing.assert_allclose(np.abs(placed.normals[0] @ np.cross(ex, ey)), 1.0, atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**16),
    tilt=st.floats(-1.2, 1.2),
    turn=st.floats(0.0, 2 * math.pi),
    spacing=st.floats(0.003, 0.02),
)
def test_on_a_plane_a_geodesic_is_a_straight_line(
    seed: int, tilt: float, turn: float, spacing: float
) -> None:
    mesh = jittered_plane(seed, tilt)
    ex, ey = plane_frame(tilt)
    t = math.cos(turn) * ex + math.sin(turn) * ey
    start = 0.003 * ex + 0.001 * ey
    count = int(0.09 / spacing)
    points, status = mesh.geodesic_nodes(start[None], t[None], spacing, count)
    assert np.all(status == NodeStatus.PLACED)
    expected = start + spacing * np.arange(1, count + 1)[:, None] * t
    np.testing.assert_allclose(points[0], expected, atol=1e-12)
    # past the plane's edge the geodesic leaves the tool
    points, status = mesh.geodesic_nodes(start[None], t[None], spacing, int(0.3 / spacing))
    assert status[0, -1] == NodeStatus.OFF_TOOL


def test_across_a_crease_a_geodesic_is_the_unfolded_straight_line() -> None:
    """A plate z = 0 (x < 0) folded down at x = 0: a geodesic leaving at 35° to the crease's
    normal continues down the wall along the straight line of the unfolded plate; its nodes
    are successive chords d apart (the one straddling the crease too)."""
    n, length = 9, 0.2
    s = np.linspace(0.0, 1.0, n)
    top = [(-length + length * a, -length / 2 + length * b, 0.0) for a in s for b in s]
    wall = [(0.0, -length / 2 + length * b, -length * a) for a in s for b in s]
    faces = []
    for base in (0, n * n):
        for i in range(n - 1):
            for j in range(n - 1):
                k = base + i * n + j
                faces += [[k, k + n, k + n + 1], [k, k + n + 1, k + 1]]
    mesh = TriangleMesh(np.array(top + wall), np.array(faces))
    d, theta = 0.0123, math.radians(35.0)
    start = np.array([-0.05, -0.04, 0.0])
    t = np.array([math.cos(theta), math.sin(theta), 0.0])
    points, status = mesh.geodesic_nodes(start[None], t[None], d, 14)
    assert np.all(status == NodeStatus.PLACED)
    p = points[0]
    # unfold: a wall point (0, y, z) lies at x = −z on the flat plate
    flat = np.where(p[:, :1] > -1e-15, np.column_stack([-p[:, 2], p[:, 1]]), p[:, :2])
    rel = flat - start[:2]
    across = rel[:, 0] * t[1] - rel[:, 1] * t[0]
    np.testing.assert_allclose(across, 0.0, atol=1e-12)
    assert np.any(p[:, 2] < -0.05)  # well down the wall
    chords = np.linalg.norm(np.diff(np.vstack([start, p]), axis=0), axis=1)
    np.testing.assert_allclose(chords, d, rtol=1e-12)


def test_the_topology_pairs_every_interior_edge() -> None:
    mesh = jittered_plane(3, 0.4, n=7)
    topo = mesh.walker.topology
    nb = topo.neighbours
    faces = np.arange(len(nb))
    for k in range(3):
        inner = nb[:, k] >= 0
        # the neighbour names this triangle back across one of its edges
        back = nb[nb[inner, k]]
        assert np.all(np.any(back == faces[inner, None], axis=1))
    # a 6 × 6-square grid has 4 · 6 boundary edges
    assert np.count_nonzero(nb < 0) == 24
    # edge normals point out of their triangle, in its plane
    centroid_side = np.einsum(
        "mki,mki->mk", topo.edge_normals, topo.centroids[:, None, :] - topo.corners
    )
    assert np.all(centroid_side < 0)
    np.testing.assert_allclose(
        np.einsum("mki,mi->mk", topo.edge_normals, topo.normals), 0.0, atol=1e-12
    )
