"""The connectivity of a triangle mesh, built once per mesh for walking queries.

The exact net placement and geodesics (``preform.plugins.surfaces.mesh_kernels``) walk from
triangle to triangle instead of searching space afresh for every node, so they need, per
triangle: its neighbour across each edge, its plane, and each edge's in-plane outward normal.
Edge k of triangle t runs from corner k to corner k + 1 (mod 3). Lengths in metres.

An edge shared by more than two triangles (non-manifold; the mesh-hygiene code reports those)
links the first two triangles found; a boundary edge has neighbour −1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from preform.base.arrays import FloatArray, IntArray


@dataclass(frozen=True)
class MeshTopology:
    """Per-triangle adjacency and frames of a mesh with ``m`` triangles."""

    #: Corner positions (m, 3, 3) [m].
    corners: FloatArray
    #: Unit outward face normals (m, 3).
    normals: FloatArray
    #: Triangle across edge k (m, 3); −1 on the mesh boundary.
    neighbours: IntArray
    #: Unit in-plane normal of edge k pointing out of the triangle (m, 3, 3).
    edge_normals: FloatArray
    #: Edge lengths (m, 3) [m].
    edge_lengths: FloatArray
    #: Centroids (m, 3) [m] and the radius of the smallest centroid-centred ball holding each
    #: triangle (m,) [m]: a cheap, conservative test of whether a triangle meets a ball.
    centroids: FloatArray
    radii: FloatArray
    #: How far past its corners (m,) a triangle's inside test, which lets a point lie a
    #: tolerance τ outside each edge, reaches, per unit of τ: 1 / sin(θ/2) at its sharpest
    #: corner θ (the offset triangle's corner moves that far); infinite for a zero angle.
    corner_reach: FloatArray

    @property
    def n_triangles(self) -> int:
        return int(self.neighbours.shape[0])


def build_topology(vertices: FloatArray, faces: IntArray, normals: FloatArray) -> MeshTopology:
    """Topology of the mesh (``vertices`` (n, 3) [m], ``faces`` (m, 3), unit ``normals``
    (m, 3)); sorting the edge keys pairs each edge with its twin in O(m log m)."""
    m = faces.shape[0]
    corners = vertices[faces]
    start = faces
    end = np.roll(faces, -1, axis=1)
    low = np.minimum(start, end).ravel()
    high = np.maximum(start, end).ravel()
    key = low * np.int64(vertices.shape[0]) + high
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    neighbours = np.full(3 * m, -1, dtype=np.int64)
    # Runs of equal keys are one geometric edge: link the first two half-edges of each run.
    twin = np.flatnonzero(sorted_key[1:] == sorted_key[:-1])
    first_of_run = np.r_[True, sorted_key[1:] != sorted_key[:-1]]
    pair = twin[first_of_run[twin]]
    h0, h1 = order[pair], order[pair + 1]
    neighbours[h0] = h1 // 3
    neighbours[h1] = h0 // 3
    edge = np.roll(corners, -1, axis=1) - corners
    lengths = np.linalg.norm(edge, axis=2)
    # For a counter-clockwise triangle seen from its normal, edge × normal points outward.
    out = np.cross(edge, normals[:, None, :])
    out /= np.linalg.norm(out, axis=2, keepdims=True)
    centroids = corners.mean(axis=1)
    radii = np.linalg.norm(corners - centroids[:, None, :], axis=2).max(axis=1)
    # The angle at corner k between its edges to k + 1 and to k − 1: sin²(θ/2) = (1 − cos θ)/2.
    to_next = edge / lengths[..., None]
    to_last = -np.roll(to_next, 1, axis=1)
    half_sin = np.sqrt(np.maximum(0.5 * (1.0 - np.einsum("tki,tki->tk", to_next, to_last)), 0.0))
    with np.errstate(divide="ignore"):
        corner_reach = 1.0 / half_sin.min(axis=1)
    return MeshTopology(
        corners=np.ascontiguousarray(corners),
        normals=np.ascontiguousarray(normals),
        neighbours=neighbours.reshape(m, 3),
        edge_normals=np.ascontiguousarray(out),
        edge_lengths=lengths,
        centroids=centroids,
        radii=radii,
        corner_reach=corner_reach,
    )
