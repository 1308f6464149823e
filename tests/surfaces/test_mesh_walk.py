"""The walking kernels on triangle meshes against closed forms: on a plane (however it is
triangulated) a net node completes a rhombus and a geodesic is a straight line; across a
crease a geodesic is the straight line of the unfolded plate; the topology pairs every
interior edge with its twin."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from preform.drape.engine.result import NodeStatus
from preform.plugins.surfaces.mesh import TriangleMesh
from preform.plugins.surfaces.mesh_hygiene import FOLD_ANGLE_DEG

# Each interior vertex moves by up to this fraction of the grid step along u and along v. A cell's
# triangles keep their orientation while it is below 1/6: the triangle (0,0), (1,0), (1,1) with
# its corners moved by up to j has edge vectors off by up to 2j per component, so twice its area
# is at least (1 − 2j)² − 2j(1 + 2j) = 1 − 6j. At 0.3 some triangles turned over (seed 6818: a
# sliver folded back over its neighbours, a 180° fold in the "plane", on which no geodesic is
# a straight line).
JITTER = 0.15


def jittered_grid(
    seed: int,
    tilt: float,
    jitter: float,
    n: int = 12,
    size: float = 0.2,
    fold_angle_deg: float = FOLD_ANGLE_DEG,
) -> TriangleMesh:
    """A square plane of side ``size`` [m] tilted by ``tilt`` [rad] about x, triangulated from
    a grid whose interior vertices are moved in the plane by up to ``jitter`` grid steps along
    each axis (irregular triangles; past 1/6 some may turn over, which TriangleMesh refuses
    as a fold unless ``fold_angle_deg`` is 180)."""
    rng = np.random.default_rng(seed)
    s = np.linspace(-size / 2, size / 2, n)
    u, v = np.meshgrid(s, s, indexing="ij")
    h = size / (n - 1)
    inner = (np.abs(u) < size / 2 - 1e-12) & (np.abs(v) < size / 2 - 1e-12)
    u = u + np.where(inner, rng.uniform(-jitter, jitter, u.shape) * h, 0.0)
    v = v + np.where(inner, rng.uniform(-jitter, jitter, v.shape) * h, 0.0)
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
    return TriangleMesh(verts, np.array(faces), fold_angle_deg=fold_angle_deg)


def jittered_plane(seed: int, tilt: float) -> TriangleMesh:
    """The jittered grid at :data:`JITTER`: a plane, none of its triangles turned over
    (checked)."""
    mesh = jittered_grid(seed, tilt, JITTER)
    _, ey = plane_frame(tilt)
    normal = np.cross([1.0, 0.0, 0.0], ey)
    assert np.all(mesh.walker.topology.normals @ normal > 1.0 - 1e-12)
    return mesh


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
        a[None],
        b[None],
        c[None],
        spacing,
        mesh.locate_faces(a[None]),
        mesh.locate_faces(b[None]),
        mesh.locate_faces(c[None]),
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
# found locally (the old fixture's jitter turned a triangle over on this seed's mesh)
@example(seed=6818, tilt=0.0, turn=1.25, spacing=0.015625)
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
    # with every turn a feature (0°), the rounding-level turns between coplanar triangles
    # (normals equal to ~1e-16) are no crease to unfold about
    sharp = TriangleMesh(mesh.vertices, mesh.faces, feature_angle_deg=0.0)
    points, status = sharp.geodesic_nodes(start[None], t[None], spacing, count)
    assert np.all(status == NodeStatus.PLACED)
    np.testing.assert_allclose(points[0], expected, atol=1e-12)
    # past the plane's edge the geodesic leaves the tool
    points, status = mesh.geodesic_nodes(start[None], t[None], spacing, int(0.3 / spacing))
    assert status[0, -1] == NodeStatus.OFF_TOOL


def test_a_geodesic_over_a_triangle_turned_over_in_a_plane_is_the_folded_line() -> None:
    """The hypothesis failure (seed 6818, tilt 0, turn 1.25, d = 1/64 m) with the old jitter
    (0.3 grid steps): triangle 172 is turned over, a sliver folded back over its neighbours
    151 and 173, so the surface is folded twice through 180° there, not flat. The geodesic
    is then the straight line of the development, in which 172 is mirrored about its edge
    with 151 and 173 beyond it mirrored again (a rotation about their shared vertex); across
    the knife-edge folds node 5 is spaced by the chord from node 4. Computed here by those
    two reflections, independently of the kernel."""
    # The fold is the point: the check that refuses it by default is turned off.
    with pytest.warns(UserWarning, match="turns back by more than 160°"):
        mesh = jittered_grid(6818, 0.0, 0.3, fold_angle_deg=180.0)
    normals = mesh.walker.topology.normals
    assert np.flatnonzero(normals[:, 2] < 0.0).tolist() == [172]
    d, turn = 0.015625, 1.25
    t = np.array([math.cos(turn), math.sin(turn)])
    start = np.array([0.003, 0.001])
    points, status = mesh.geodesic_nodes(np.append(start, 0.0)[None], np.append(t, 0.0)[None], d, 5)
    assert np.all(status == NodeStatus.PLACED)
    np.testing.assert_array_equal(points[0, :, 2], 0.0)
    straight = start + d * np.arange(1, 5)[:, None] * t
    np.testing.assert_allclose(points[0, :4, :2], straight, atol=1e-12)

    def mirror(i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Reflection x ↦ Mx + b about the line through the shared vertices of i and j."""
        a, b = (mesh.vertices[k, :2] for k in sorted(set(mesh.faces[i]) & set(mesh.faces[j])))
        u = (b - a) / np.linalg.norm(b - a)
        m = 2.0 * np.outer(u, u) - np.eye(2)
        return m, a - m @ a

    m1, b1 = mirror(151, 172)
    m2, b2 = mirror(172, 173)
    # actual position of a development point beyond the sliver: undo the mirror about
    # 151|172, then the one about 172|173
    q, c = m2 @ m1, m2 @ b1 + b2
    # node 5 = q·(node 4 + s·t) + c at chord d from node 4: s² + 2s(u·w) + |w|² − d² = 0
    n4 = straight[-1]
    u, w = q @ t, q @ n4 + c - n4
    s = -(u @ w) + math.sqrt((u @ w) ** 2 - w @ w + d * d)
    node5 = q @ (n4 + s * t) + c
    np.testing.assert_allclose(points[0, 4, :2], node5, atol=1e-12)
    assert np.linalg.norm(node5 - (start + 5 * d * t)) > 1e-5  # (off the unfolded line)


def grid_plane(h: float, tilt: float, n: int = 9) -> TriangleMesh:
    """A plane tilted by ``tilt`` [rad] about x on an n × n vertex grid of step ``h`` [m], cells
    cut along alternating diagonals so that both kinds of vertex fan occur."""
    ex, ey = plane_frame(tilt)
    k = np.arange(n) - n // 2
    u, v = np.meshgrid(k * h, k * h, indexing="ij")
    verts = u.ravel()[:, None] * ex + v.ravel()[:, None] * ey
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            if (i + j) % 2:
                faces += [[a, a + n, a + n + 1], [a, a + n + 1, a + 1]]
            else:
                faces += [[a, a + n, a + 1], [a + n, a + n + 1, a + 1]]
    return TriangleMesh(verts, np.array(faces))


@pytest.mark.parametrize(
    ("h", "tilt"),
    [(2.0**-5, 0.0), (0.0237, 0.7)],  # exact in binary; rounded everywhere
)
@pytest.mark.parametrize(
    ("start_h", "aim_h", "spacing_h"),
    [
        ((0.1, 0.0), (1.0, 0.0), 0.37),  # along the edges of a grid line, through its vertices
        ((0.0, 0.0), (1.0, 0.0), 1.0),  # from a vertex along edges, every node on a vertex
        ((0.1, 0.1), (1.0, 1.0), 0.41),  # along cut diagonals, through vertices between
        ((0.0, 0.0), (1.0, 1.0), 2**0.5),  # from a vertex, every node on a vertex
        ((0.0, 0.0), (0.0, -1.0), 0.5),  # down a grid line, nodes on vertices and mid-edges
        ((0.2, 0.1), (2.0, 1.0), 0.29),  # across cells, through the vertex (2h, h)
        ((-0.3, 0.4), (-1.0, 3.0), 0.53),  # through the vertex (−h, 3h), across cells
        ((0.1, 1e-14), (1.0, 0.0), 0.37),  # a hair beside a grid line: through edges' ends
        ((0.1, -1e-14), (1.0, 0.0), 0.37),
    ],
)
def test_a_geodesic_through_vertices_and_along_edges_of_a_plane_is_straight(
    h: float,
    tilt: float,
    start_h: tuple[float, float],
    aim_h: tuple[float, float],
    spacing_h: float,
) -> None:
    """Where the line meets a vertex or runs along an edge, several triangles hold each point
    and the walk must pass through them without bending or losing length (the plane's truth:
    node k at start + k·d·t)."""
    mesh = grid_plane(h, tilt)
    ex, ey = plane_frame(tilt)
    start = start_h[0] * h * ex + start_h[1] * h * ey
    aim = aim_h[0] * h * ex + aim_h[1] * h * ey
    t = (aim - start) / np.linalg.norm(aim - start)
    d = spacing_h * h
    count = int(3.5 * h / d)  # up to the grid's edge at 4h, not past it
    points, status = mesh.geodesic_nodes(start[None], t[None], d, count)
    assert np.all(status == NodeStatus.PLACED)
    expected = start + d * np.arange(1, count + 1)[:, None] * t
    np.testing.assert_allclose(points[0], expected, atol=1e-12)


def test_across_a_crease_a_geodesic_is_the_unfolded_straight_line() -> None:
    """A plate z = 0 (x < 0) folded down at x = 0: a geodesic leaving at 35° to the crease's
    normal continues down the wall along the straight line of the unfolded plate; its nodes
    are d apart along it, the one straddling the crease too (the crease is a feature: the tow
    bends over it, so the spacing there is the length along the surface, not the chord); with
    the feature angle at 180° every spacing is the chord."""
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
    mesh = TriangleMesh(np.array(top + wall), np.array(faces), feature_angle_deg=20.0)
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
    along = np.linalg.norm(np.diff(np.vstack([start[:2], flat]), axis=0), axis=1)
    np.testing.assert_allclose(along, d, rtol=1e-12)
    chord_mesh = TriangleMesh(mesh.vertices, mesh.faces, feature_angle_deg=180.0)
    points, _ = chord_mesh.geodesic_nodes(start[None], t[None], d, 14)
    chords = np.linalg.norm(np.diff(np.vstack([start, points[0]]), axis=0), axis=1)
    np.testing.assert_allclose(chords, d, rtol=1e-12)
    # the chord cuts the corner, so the chord-spaced net runs further down the unfolded line
    q = points[0]
    q_flat = np.where(q[:, :1] > -1e-15, np.column_stack([-q[:, 2], q[:, 1]]), q[:, :2])
    assert np.linalg.norm(q_flat[-1] - start[:2]) > 14 * d + 1e-4


def test_the_topology_pairs_every_interior_edge() -> None:
    mesh = jittered_grid(3, 0.4, JITTER, n=7)
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
