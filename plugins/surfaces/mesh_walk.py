"""Exact net placement and geodesics on a triangle mesh, vectorised over a front.

The numpy face of the compiled kernels in ``preform.plugins.surfaces.mesh_kernels`` (imported
here only when a drape asks, so that ``import preform`` never loads numba): arrays in, arrays
out, scratch buffers kept per mesh. See the kernels' module docstring for the geometry.
Lengths in metres.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from preform.base.arrays import FloatArray, IntArray, StatusArray
from preform.drape.engine.net import FacePlacement, NetLayout
from preform.plugins.surfaces.mesh_topology import MeshTopology

if TYPE_CHECKING:
    from preform.plugins.surfaces.mesh import TriangleMesh


class MeshWalker:
    """Walking queries on one mesh's topology, with the scratch buffers they share."""

    def __init__(self, topology: MeshTopology, feature_angle_deg: float) -> None:
        self.topology = topology
        self.feature_angle_deg = feature_angle_deg
        # Node spacing is the surface length, not the chord, where the surface turns by more
        # than ``feature_angle_deg`` [°] between a node's triangle and its parent's
        # (TriangleMesh, docs/physics.md).
        self.feature_cos = math.cos(math.radians(self.feature_angle_deg))
        m = topology.n_triangles
        # Scratch shared by every call: the kernels hold the GIL (no nogil) and leave it as
        # they found it, so threads sharing one mesh never see it mid-query.
        self._visited = np.zeros(m, dtype=np.bool_)
        self._queue = np.empty(m, dtype=np.int64)

    def place_nodes(
        self,
        a: FloatArray,
        b: FloatArray,
        opposite: FloatArray,
        spacing: float,
        face_a: IntArray,
        face_b: IntArray,
        face_opposite: IntArray,
    ) -> FacePlacement:
        """Nodes at chord ``spacing`` [m] from ``a`` and ``b`` (m, 3) [m] on the mesh, on the
        far side from ``opposite``, walking from the parents' triangles ``face_a``/``face_b``
        (``face_opposite``: the opposite node's)."""
        from preform.plugins.surfaces.mesh_kernels import place_nodes_kernel

        topo = self.topology
        m = len(a)
        points = np.empty((m, 3))
        status = np.empty(m, dtype=np.int8)
        faces = np.empty(m, dtype=np.int64)
        normals = np.empty((m, 3))
        residual = np.empty(m)
        place_nodes_kernel(
            topo.corners,
            topo.normals,
            topo.neighbours,
            topo.edge_normals,
            topo.centroids,
            topo.radii,
            topo.corner_reach,
            np.ascontiguousarray(a, dtype=np.float64),
            np.ascontiguousarray(b, dtype=np.float64),
            np.ascontiguousarray(opposite, dtype=np.float64),
            float(spacing),
            self.feature_cos,
            np.ascontiguousarray(face_a, dtype=np.int64),
            np.ascontiguousarray(face_b, dtype=np.int64),
            np.ascontiguousarray(face_opposite, dtype=np.int64),
            self._visited,
            self._queue,
            points,
            status,
            faces,
            normals,
            residual,
        )
        return FacePlacement(points, status, faces, normals, residual)

    def fill_fronts(
        self,
        pos: FloatArray,
        status: StatusArray,
        residual: FloatArray,
        face: IntArray,
        layout: NetLayout,
        spacing: float,
        lo: FloatArray,
        hi: FloatArray,
    ) -> int:
        """Every front of a net, in place (``preform.drape.engine.net.WalkingFill``); the number of
        fronts placed."""
        from preform.plugins.surfaces.mesh_kernels import fill_fronts_kernel

        topo = self.topology
        nj, start_flat, q_sa, q_sb, q_na, q_nb, last_front = layout
        fronts = fill_fronts_kernel(
            topo.corners, topo.normals, topo.neighbours, topo.edge_normals, topo.centroids,
            topo.radii, topo.corner_reach, self.feature_cos, self._visited, self._queue,
            pos, status, residual, face, nj, start_flat, q_sa, q_sb, q_na, q_nb, last_front,
            float(spacing), lo, hi,
        )  # fmt: skip
        return int(fronts)

    def spacings(
        self, a: FloatArray, b: FloatArray, face_a: IntArray, face_b: IntArray, spacing: float
    ) -> FloatArray:
        """The spacing (m,) [m] from ``a`` on triangles ``face_a`` to ``b`` on ``face_b``
        (m, 3) [m] under the placement's rule (chord, or length along the surface over a
        feature crease)."""
        from preform.plugins.surfaces.mesh_kernels import spacing_kernel

        topo = self.topology
        length = np.empty(len(a))
        spacing_kernel(
            topo.corners,
            topo.normals,
            topo.centroids,
            np.ascontiguousarray(a, dtype=np.float64),
            np.ascontiguousarray(b, dtype=np.float64),
            np.ascontiguousarray(face_a, dtype=np.int64),
            np.ascontiguousarray(face_b, dtype=np.int64),
            self.feature_cos,
            float(spacing),
            length,
        )
        return length

    def geodesic_nodes(
        self,
        start: FloatArray,
        start_face: IntArray,
        direction: FloatArray,
        spacing: float,
        count: int,
    ) -> tuple[FloatArray, StatusArray, IntArray]:
        """``count`` nodes (g, count, 3) [m] along the straightest geodesics from ``start``
        (g, 3) on triangles ``start_face`` in tangent ``direction`` (g, 3), chords ``spacing``
        [m]; NodeStatus codes and triangles (g, count)."""
        from preform.plugins.surfaces.mesh_kernels import geodesic_kernel

        topo = self.topology
        g = len(start)
        points = np.empty((g, count, 3))
        status = np.empty((g, count), dtype=np.int8)
        faces = np.empty((g, count), dtype=np.int64)
        geodesic_kernel(
            topo.corners,
            topo.normals,
            topo.neighbours,
            topo.edge_normals,
            topo.centroids,
            np.ascontiguousarray(start, dtype=np.float64),
            np.ascontiguousarray(start_face, dtype=np.int64),
            np.ascontiguousarray(direction, dtype=np.float64),
            float(spacing),
            self.feature_cos,
            int(count),
            points,
            status,
            faces,
        )
        return points, status, faces


def faces_ahead(mesh: TriangleMesh, start: FloatArray, direction: FloatArray) -> IntArray:
    """The triangle each path leaving ``start`` (g, 3) [m] along ``direction`` (g, 3) enters
    first: where the start is a vertex or on an edge, several triangles hold it and only the
    one ahead gives the path its plane. Found as the triangle of a point a hair ahead."""
    hair = 1e-9 * mesh.size
    unit = direction / np.linalg.norm(direction, axis=1, keepdims=True)
    return mesh.closest_faces(start + hair * unit)[2]
