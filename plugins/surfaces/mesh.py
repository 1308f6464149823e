"""Tool surfaces given as triangle meshes, and the STL / OBJ readers that produce them.

Lengths are in metres inside; the readers take the file's unit as a factor ``units_to_m``
(millimetres, 1e-3, by default, as CAD exports usually are).

A mesh need not be a height field: vertical walls and undercuts are answered correctly by
``closest_point``, which is exact for the piecewise-flat surface (not an approximation of it).
Outward is defined by the winding: counter-clockwise seen from outside, the STL convention.
"""

from __future__ import annotations

import os
import stat
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from preform.base.arrays import BoolArray, FloatArray, IntArray
from preform.plugins.surfaces.domes import _as_points
from preform.plugins.surfaces.mesh_hygiene import FOLD_ANGLE_DEG, HygieneReport, check_surface

if TYPE_CHECKING:
    from preform.drape.engine.net import FacePlacement, NetLayout
    from preform.plugins.surfaces.mesh_walk import MeshWalker
    from preform.plugins.surfaces.tool_mesh import ToolMesh

Bounds = tuple[tuple[float, float, float], tuple[float, float, float]]

__all__ = [
    "MeshFileError",
    "TriangleMesh",
    "check_mesh_file",
    "obj_triangles",
    "read_obj",
    "read_stl",
    "stl_triangles",
    "tessellate_hemisphere",
    "write_stl",
]

#: Triangles whose doubled area is below this fraction of their longest edge squared are
#: treated as zero-area (collinear corners): their normal is noise.
_DEGENERATE_ASPECT = 1e-12
#: Plan-barycentric slack for vertical ray hits, so a ray through a shared edge hits both sides.
_RAY_SLACK = 1e-12
#: Point-candidate pairs evaluated at once by ``closest_point`` (memory, not accuracy).
_CANDIDATES_PER_CHUNK = 1 << 16


def _dot(u: FloatArray, v: FloatArray) -> FloatArray:
    return np.einsum("...i,...i->...", u, v)


def _cross(u: FloatArray, v: FloatArray) -> FloatArray:
    """Cross products of (..., 3) arrays: np.cross's axis shuffling costs more than the
    arithmetic on the small arrays a marching generator sends."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    return np.stack((u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0), axis=-1)


def _closest_on_segments(p: FloatArray, start: FloatArray, end: FloatArray) -> FloatArray:
    edge = end - start
    length_sq = _dot(edge, edge)
    safe = np.where(length_sq > 0.0, length_sq, 1.0)
    t = np.clip(_dot(p - start, edge) / safe, 0.0, 1.0)
    return start + t[..., None] * edge


def _closest_on_triangles(p: FloatArray, a: FloatArray, b: FloatArray, c: FloatArray) -> FloatArray:
    """Closest points on triangles (a, b, c) to points p; all arrays (..., 3), broadcast.

    The foot of the perpendicular on the triangle's plane is the answer when it falls inside
    (all barycentric weights ≥ 0); otherwise the nearest point is on the boundary, i.e. the
    nearest of the three edge projections. Exact, branch-free, vectorised.
    """
    normal = _cross(b - a, c - a)
    normal_sq = _dot(normal, normal)
    foot = p - (_dot(p - a, normal) / normal_sq)[..., None] * normal
    weight_a = _dot(_cross(b - foot, c - foot), normal) / normal_sq
    weight_b = _dot(_cross(c - foot, a - foot), normal) / normal_sq
    inside = (weight_a >= 0.0) & (weight_b >= 0.0) & (weight_a + weight_b <= 1.0)
    edges = np.stack(
        (
            _closest_on_segments(p, a, b),
            _closest_on_segments(p, b, c),
            _closest_on_segments(p, c, a),
        )
    )
    edge_dist_sq = _dot(edges - p[None], edges - p[None])
    nearest_edge = np.take_along_axis(edges, np.argmin(edge_dist_sq, axis=0)[None, ..., None], 0)[0]
    return np.where(inside[..., None], foot, nearest_edge)


#: The turn [°] of the surface normal, from a net node's parent's triangle to the node's, above
#: which the node spacing is the length along the surface over the crease instead of the chord
#: (a sharp CAD edge, not the facets of a smooth surface). Off (180°, the chord everywhere) by
#: default until the bundled hat stiffener drapes completely with it; 20° is the value for
#: tools with isolated sharp creases (docs/physics.md, "Sharp creases").
DEFAULT_FEATURE_ANGLE_DEG = 180.0


class TriangleMesh:
    """A tool surface made of triangles; vertices (n, 3) [m], faces (m, 3) vertex indices.

    On construction, vertices closer than ``merge_tolerance_rel`` × (bounding-box diagonal) are
    merged (STL stores every corner separately) and zero-area triangles are dropped with a
    warning; ``dropped_triangles`` counts them. ``size`` is the bounding-box diagonal [m].

    Then the surface is checked as a scene's tool is (``mesh_hygiene.check_surface``, one
    implementation): an edge shared by three or more triangles (a fin), a one-sided surface
    and a fold (two neighbours' normals turning by more than ``fold_angle_deg`` [°], default
    ``FOLD_ANGLE_DEG`` = 160°: a triangle turned over) raise ``MeshRefused`` saying where.
    Triangles wound against their piece are re-wound, with a warning, to the winding of the
    larger area (``rewound_triangles`` counts them); the caller's winding otherwise says which
    side is out (nothing is turned over whole, unlike a file tool). Edges a raised
    ``fold_angle_deg`` lets through are said as a warning and in ``cautions``. Cracks and
    T-junctions are not mended here: :func:`read_stl`, :func:`read_obj` and scenes repair
    them (``mesh_hygiene.repair``).

    Normals are the face normal of the closest triangle by default (exactly consistent with the
    faceted surface ``closest_point`` answers for). With ``smooth_normals=True`` they are the
    barycentric interpolation of area-weighted vertex normals, continuous across edges.

    ``closest_point`` gathers candidate triangles by their centroids' k nearest neighbours and
    certifies each answer: every triangle not examined has its centroid at least d_k away (the
    k-th candidate's centroid distance) and lies within ``r_max`` (largest centroid-to-corner
    distance) of it, so no unexamined triangle is nearer than d_k − r_max. Points whose best
    distance exceeds that bound are re-queried with twice as many candidates.

    ``feature_angle_deg`` [°]: where the surface turns by more than this between a net node's
    triangle and its parent's, the node is spaced by the length along the surface over the
    crease, elsewhere by the chord (:data:`DEFAULT_FEATURE_ANGLE_DEG`, docs/physics.md).

    ``point_at_plan`` casts vertical rays downward. For a ray along −z the Möller–Trumbore test
    reduces to the barycentric coordinates of the plan position in the triangle's plan
    projection, and the hit height to the barycentric blend of the corner heights; vertical
    triangles are never hit by a vertical ray (their neighbours are). Triangles are binned on a
    uniform plan grid so each ray tests only the triangles whose plan bounding box covers it.
    """

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        *,
        merge_tolerance_rel: float = 1e-6,
        smooth_normals: bool = False,
        initial_candidates: int = 16,
        feature_angle_deg: float = DEFAULT_FEATURE_ANGLE_DEG,
        fold_angle_deg: float = FOLD_ANGLE_DEG,
    ) -> None:
        vertex_array = np.asarray(vertices, dtype=np.float64)
        face_array = np.asarray(faces)
        if vertex_array.ndim != 2 or vertex_array.shape[1] != 3 or vertex_array.shape[0] < 3:
            raise ValueError(f"vertices must be an (n ≥ 3, 3) array [m], got {vertex_array.shape}")
        if not np.all(np.isfinite(vertex_array)):
            raise ValueError("vertices contain non-finite coordinates")
        if face_array.ndim != 2 or face_array.shape[1] != 3 or face_array.shape[0] == 0:
            raise ValueError(f"faces must be an (m ≥ 1, 3) integer array, got {face_array.shape}")
        if not np.issubdtype(face_array.dtype, np.integer):
            raise ValueError(
                f"faces must hold integer vertex indices, got dtype {face_array.dtype}"
            )
        face_array = face_array.astype(np.int64)
        if face_array.min() < 0 or face_array.max() >= vertex_array.shape[0]:
            raise ValueError(
                f"faces index vertices outside 0..{vertex_array.shape[0] - 1} "
                f"(min {face_array.min()}, max {face_array.max()})"
            )
        if not merge_tolerance_rel >= 0.0:
            raise ValueError(f"merge_tolerance_rel must be ≥ 0, got {merge_tolerance_rel!r}")
        if initial_candidates < 1:
            raise ValueError(f"initial_candidates must be ≥ 1, got {initial_candidates!r}")
        if not 0.0 <= feature_angle_deg <= 180.0:
            raise ValueError(
                f"feature_angle_deg must be an angle in [0, 180] degrees, got {feature_angle_deg!r}"
            )
        self.feature_angle_deg = float(feature_angle_deg)

        used = vertex_array[np.unique(face_array)]
        diagonal = float(np.linalg.norm(used.max(axis=0) - used.min(axis=0)))
        if diagonal == 0.0:
            raise ValueError("the mesh has no extent: all its vertices coincide")
        vertex_array, face_array = _merge_vertices(
            vertex_array, face_array, merge_tolerance_rel * diagonal
        )
        kept = _non_degenerate(vertex_array, face_array)
        face_array = face_array[kept]
        self.dropped_triangles = int(kept.size - np.count_nonzero(kept))
        if self.dropped_triangles:
            warnings.warn(
                f"TriangleMesh: dropped {self.dropped_triangles} degenerate (zero-area) triangles",
                stacklevel=2,
            )
        if face_array.shape[0] == 0:
            raise ValueError("the mesh has no triangle of non-zero area")
        vertex_array, face_array = _drop_unused_vertices(vertex_array, face_array)
        #: Triangles re-wound to agree with their piece, and what a raised fold angle let
        #: through, in words (class docstring).
        self.rewound_triangles = 0
        self.cautions: list[str] = []
        if not self._surface_checked:
            face_array = self._check_surface(
                vertex_array, face_array, np.flatnonzero(kept), fold_angle_deg
            )

        self.vertices: FloatArray = vertex_array
        self.faces: IntArray = face_array
        self.smooth_normals = smooth_normals
        self._initial_candidates = initial_candidates
        low, high = vertex_array.min(axis=0), vertex_array.max(axis=0)
        self.bounds: Bounds = (
            (float(low[0]), float(low[1]), float(low[2])),
            (float(high[0]), float(high[1]), float(high[2])),
        )
        self.size = float(np.linalg.norm(high - low))

        corners = vertex_array[face_array]
        self._corners = corners
        doubled_area_normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        self.face_normals: FloatArray = doubled_area_normal / np.linalg.norm(
            doubled_area_normal, axis=1, keepdims=True
        )
        # Summing un-normalised face normals weights each face by its area.
        vertex_normals = np.zeros_like(vertex_array)
        for corner in range(3):
            np.add.at(vertex_normals, face_array[:, corner], doubled_area_normal)
        self.vertex_normals: FloatArray = vertex_normals / np.linalg.norm(
            vertex_normals, axis=1, keepdims=True
        )
        centroids = corners.mean(axis=1)
        from scipy.spatial import cKDTree  # scipy only once a mesh is built

        self._centroid_tree = cKDTree(centroids)
        self._bounding_radius = float(np.max(np.linalg.norm(corners - centroids[:, None], axis=2)))
        self._build_plan_grid()

    def moved(self, vertices: FloatArray) -> TriangleMesh:
        """This mesh with its vertices (n, 3) [m] moved (the same faces, normals and knobs):
        a tool offset along its vertex normals (``preform.drape.engine.offset``)."""
        return TriangleMesh(
            vertices,
            self.faces,
            merge_tolerance_rel=0.0,
            smooth_normals=self.smooth_normals,
            initial_candidates=self._initial_candidates,
            feature_angle_deg=self.feature_angle_deg,
        )

    #: Whether the arrays come already checked (a ``ToolMesh``'s come from ``repair``, which
    #: ran the same checks), so construction does not pay for them twice.
    _surface_checked = False

    def _check_surface(
        self, vertices: FloatArray, faces: IntArray, origin: IntArray, fold_angle_deg: float
    ) -> IntArray:
        """The class docstring's checks; returns the consistently wound faces."""
        report = HygieneReport(
            triangles_read=int(faces.shape[0]),
            vertices_read=int(vertices.shape[0]),
            weld_tolerance_m=0.0,
        )
        faces = check_surface(
            vertices,
            faces,
            report,
            origin=origin,
            fold_angle_deg=fold_angle_deg,
            turn_pieces=False,
        )
        self.rewound_triangles = report.flipped_triangles
        self.cautions = report.cautions()
        if self.rewound_triangles:
            warnings.warn(
                f"TriangleMesh: re-wound {self.rewound_triangles} triangles whose normals "
                "disagreed with their neighbours' (each piece keeps the winding of its larger "
                "area)",
                stacklevel=3,
            )
        for caution in self.cautions:
            warnings.warn(f"TriangleMesh: {caution}", stacklevel=3)
        return faces

    @property
    def n_triangles(self) -> int:
        """Number of (non-degenerate) triangles."""
        return int(self.faces.shape[0])

    # --- closest point -----------------------------------------------------------------------

    def closest_faces(self, points: FloatArray) -> tuple[FloatArray, FloatArray, IntArray]:
        """Closest surface points (n, 3) [m], distances (n,) [m] and the index of the triangle
        each closest point lies on (n,)."""
        p = _as_points(points, 3)
        n_points, n_faces = p.shape[0], self.n_triangles
        # Non-finite queries answer NaN (face 0), as the analytic surfaces do, instead of
        # making the k-d tree raise: a marching caller can then see the NaN and stop.
        closest = np.full_like(p, np.nan)
        distance = np.full(n_points, np.nan)
        face = np.zeros(n_points, dtype=np.int64)
        pending = np.flatnonzero(np.all(np.isfinite(p), axis=1))
        k = min(self._initial_candidates, n_faces)
        while pending.size:
            # Chunks bound the (points × candidates) temporaries to a few tens of MB.
            n_chunks = -(-pending.size * k // _CANDIDATES_PER_CHUNK)
            uncertified = []
            for chunk in np.array_split(pending, n_chunks):
                feet, dist, face_index, certified = self._nearest_candidate(p[chunk], k)
                done = chunk[certified]
                closest[done], distance[done], face[done] = (
                    feet[certified],
                    dist[certified],
                    face_index[certified],
                )
                uncertified.append(chunk[~certified])
            pending = np.concatenate(uncertified)
            k = min(2 * k, n_faces)
        return closest, distance, face

    def _nearest_candidate(
        self, points: FloatArray, k: int
    ) -> tuple[FloatArray, FloatArray, IntArray, BoolArray]:
        """Best of the k triangles with the nearest centroids, and whether it is certified."""
        centroid_dist, candidates = self._centroid_tree.query(points, k=k)
        centroid_dist = np.asarray(centroid_dist).reshape(points.shape[0], k)
        candidates = np.asarray(candidates).reshape(points.shape[0], k)
        tri = self._corners[candidates]
        query = points[:, None, :]
        feet = _closest_on_triangles(query, tri[..., 0, :], tri[..., 1, :], tri[..., 2, :])
        dist = np.linalg.norm(feet - query, axis=2)
        best = np.argmin(dist, axis=1)
        rows = np.arange(points.shape[0])
        best_dist = dist[rows, best]
        bound = centroid_dist[:, -1] - self._bounding_radius
        certified = (k == self.n_triangles) | (best_dist <= bound)
        return feet[rows, best], best_dist, candidates[rows, best], certified

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest surface points (n, 3) [m] to ``points`` (n, 3) [m] and distances (n,) [m]."""
        closest, distance, face = self.closest_faces(points)
        # Callers usually ask next for the normals at exactly these points (project, then
        # orient): remember which triangle each lies on so normal() need not search again.
        self._last_feet = (closest, face)
        return closest, distance

    def barycentric(self, points: FloatArray, face: IntArray) -> FloatArray:
        """Barycentric coordinates (n, 3) of points (n, 3) [m] projected onto triangles
        ``face`` (n,)."""
        tri = self._corners[face]
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        normal = np.cross(b - a, c - a)
        normal_sq = _dot(normal, normal)
        weight_a = _dot(np.cross(b - points, c - points), normal) / normal_sq
        weight_b = _dot(np.cross(c - points, a - points), normal) / normal_sq
        return np.column_stack((weight_a, weight_b, 1.0 - weight_a - weight_b))

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at surface points (n, 3) [m]: the closest triangle's face
        normal, or the interpolated vertex normal with ``smooth_normals``."""
        last = getattr(self, "_last_feet", None)
        if (
            last is not None
            and last[0].shape == np.shape(points)
            and np.array_equal(last[0], points, equal_nan=True)
        ):
            closest, face = last
        else:
            closest, _, face = self.closest_faces(points)
        if not self.smooth_normals:
            normals = self.face_normals[face]
        else:
            weights = np.clip(self.barycentric(closest, face), 0.0, 1.0)
            blended = np.einsum("ni,nij->nj", weights, self.vertex_normals[self.faces[face]])
            normals = blended / np.linalg.norm(blended, axis=1, keepdims=True)
        return np.where(np.isfinite(closest[:, :1]), normals, np.nan)

    # --- walking queries (exact net placement and geodesics) --------------------------------

    @property
    def walker(self) -> MeshWalker:
        """Walking queries over this mesh's topology (built on first use, then kept)."""
        walker = getattr(self, "_walker", None)
        if walker is None:
            from preform.plugins.surfaces.mesh_topology import build_topology
            from preform.plugins.surfaces.mesh_walk import MeshWalker

            walker = MeshWalker(
                build_topology(self.vertices, self.faces, self.face_normals),
                self.feature_angle_deg,
            )
            self._walker = walker
        return walker

    def locate_faces(self, points: FloatArray) -> IntArray:
        """The triangle (n,) each point (n, 3) [m] lies on (or is closest to)."""
        return self.closest_faces(points)[2]

    def place_nodes_from_faces(
        self,
        a: FloatArray,
        b: FloatArray,
        opposite: FloatArray,
        spacing: float,
        face_a: IntArray,
        face_b: IntArray,
        face_opposite: IntArray,
    ) -> FacePlacement:
        """Net nodes at chord ``spacing`` [m] from ``a`` and ``b`` (m, 3) [m], on the far side
        from ``opposite``, found exactly on the triangles met walking from the parents'
        triangles ``face_a``/``face_b`` (``preform.plugins.surfaces.mesh_kernels``); the
        opposite node's triangle ``face_opposite`` places it across a crease."""
        return self.walker.place_nodes(a, b, opposite, spacing, face_a, face_b, face_opposite)

    def fill_fronts(
        self,
        pos: FloatArray,
        status: NDArray[np.int8],
        residual: FloatArray,
        face: IntArray,
        layout: NetLayout,
        spacing: float,
        lo: FloatArray,
        hi: FloatArray,
    ) -> int:
        """Every front of a net at node spacing ``spacing`` [m], in one compiled loop, in place
        on the flat node arrays (``preform.drape.engine.net.WalkingFill``): each node placed as
        :meth:`place_nodes_from_faces` places it, then checked as every tool's nodes are."""
        return self.walker.fill_fronts(pos, status, residual, face, layout, spacing, lo, hi)

    def spacings(
        self, a: FloatArray, b: FloatArray, face_a: IntArray, face_b: IntArray, spacing: float
    ) -> FloatArray:
        """Node-to-parent spacings (m,) [m] from ``a`` (m, 3) on triangles ``face_a`` to ``b``
        on ``face_b`` under this mesh's rule: the chord, or the length along the surface where
        a feature crease lies between (``feature_angle_deg``) within ``spacing`` [m] of ``a``."""
        return self.walker.spacings(a, b, face_a, face_b, spacing)

    def place_nodes(
        self, a: FloatArray, b: FloatArray, opposite: FloatArray, spacing: float
    ) -> tuple[FloatArray, NDArray[np.int8]]:
        """As :meth:`place_nodes_from_faces`, locating the parents' triangles first."""
        placed = self.place_nodes_from_faces(
            a,
            b,
            opposite,
            spacing,
            self.locate_faces(a),
            self.locate_faces(b),
            self.locate_faces(opposite),
        )
        return placed.points, placed.status

    def geodesic_nodes(
        self, start: FloatArray, direction: FloatArray, spacing: float, count: int
    ) -> tuple[FloatArray, NDArray[np.int8]]:
        """``count`` nodes (m, count, 3) [m] along the straightest geodesics of the faceted
        surface from ``start`` (m, 3) in tangent ``direction`` (m, 3), successive chords
        ``spacing`` [m]; NodeStatus codes (m, count), OFF_TOOL past the mesh's boundary. Exact
        for the piecewise-flat surface: no sub-steps."""
        from preform.plugins.surfaces.mesh_walk import faces_ahead

        start = np.asarray(start, dtype=float)
        direction = np.asarray(direction, dtype=float)
        faces = faces_ahead(self, start, direction)
        points, status, _ = self.walker.geodesic_nodes(start, faces, direction, spacing, count)
        return points, status

    # --- vertical rays ----------------------------------------------------------------------

    def _build_plan_grid(self) -> None:
        corners = self._corners
        plan_normal = self.face_normals[:, 2]
        rayable = np.flatnonzero(np.abs(plan_normal) > 1e-12)
        low = corners[rayable, :, :2].min(axis=1)
        high = corners[rayable, :, :2].max(axis=1)
        origin = np.array(self.bounds[0][:2])
        extent = np.maximum(np.array(self.bounds[1][:2]) - origin, 1e-12 * self.size)
        # Cells about the size of a typical triangle keep a few triangles per cell.
        typical = float(np.median(np.max(high - low, axis=1))) if rayable.size else 1.0
        shape = np.clip(np.ceil(extent / max(typical, 1e-9 * self.size)), 1, 2048).astype(np.int64)
        cell_size = extent / shape
        first = np.clip(((low - origin) / cell_size).astype(np.int64), 0, shape - 1)
        last = np.clip(((high - origin) / cell_size).astype(np.int64), 0, shape - 1)
        span = last - first + 1
        per_face = span[:, 0] * span[:, 1]
        owner = np.repeat(np.arange(rayable.size), per_face)
        offset = np.arange(owner.size) - np.repeat(np.cumsum(per_face) - per_face, per_face)
        cell_x = first[owner, 0] + offset % span[owner, 0]
        cell_y = first[owner, 1] + offset // span[owner, 0]
        cell = cell_x * shape[1] + cell_y
        order = np.argsort(cell, kind="stable")
        self._grid_faces = rayable[owner[order]]
        self._grid_start = np.concatenate(
            ([0], np.cumsum(np.bincount(cell, minlength=int(shape.prod()))))
        )
        self._grid_origin, self._grid_cell, self._grid_shape = origin, cell_size, shape

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """The topmost surface point (n, 3) [m] above each plan position ``xy`` (n, 2) [m], and
        whether a vertical ray there hits the tool at all. Off the tool z is the tool's lowest
        height (``bounds[0][2]``)."""
        plan = _as_points(xy, 2)
        n_points = plan.shape[0]
        cell_xy = np.floor((plan - self._grid_origin) / self._grid_cell).astype(np.int64)
        # A position on the far edge of the grid belongs to the last cell.
        at_far_edge = plan == self._grid_origin + self._grid_cell * self._grid_shape
        cell_xy = np.where(at_far_edge, self._grid_shape - 1, cell_xy)
        in_grid = np.all((cell_xy >= 0) & (cell_xy < self._grid_shape), axis=1)
        cell = np.where(in_grid, cell_xy[:, 0] * self._grid_shape[1] + cell_xy[:, 1], 0)
        count = np.where(in_grid, self._grid_start[cell + 1] - self._grid_start[cell], 0)
        ray = np.repeat(np.arange(n_points), count)
        offset = np.arange(ray.size) - np.repeat(np.cumsum(count) - count, count)
        face = self._grid_faces[self._grid_start[cell[ray]] + offset]

        tri = self._corners[face]
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        p = plan[ray]

        def cross_z(u: FloatArray, v: FloatArray) -> FloatArray:
            return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]

        ab, ac, ap = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2], p - a[:, :2]
        plan_area = cross_z(ab, ac)
        weight_b = cross_z(ap, ac) / plan_area
        weight_c = cross_z(ab, ap) / plan_area
        weight_a = 1.0 - weight_b - weight_c
        hit = (weight_a >= -_RAY_SLACK) & (weight_b >= -_RAY_SLACK) & (weight_c >= -_RAY_SLACK)
        height = weight_a * a[:, 2] + weight_b * b[:, 2] + weight_c * c[:, 2]
        top = np.full(n_points, -np.inf)
        np.maximum.at(top, ray[hit], height[hit])
        over_tool = np.isfinite(top)
        z = np.where(over_tool, top, self.bounds[0][2])
        return np.column_stack((plan, z)), over_tool


def _merge_vertices(
    vertices: FloatArray, faces: IntArray, tolerance: float
) -> tuple[FloatArray, IntArray]:
    """Merge vertices within ``tolerance`` [m] (transitively) and re-index the faces."""
    if tolerance <= 0.0:
        return vertices, faces
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(vertices).query_pairs(tolerance, output_type="ndarray")
    if pairs.size == 0:
        return vertices, faces
    n = vertices.shape[0]
    links = coo_matrix((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(links, directed=False)
    _, representative = np.unique(label, return_index=True)
    return vertices[representative], label[faces].astype(np.int64)


def _non_degenerate(vertices: FloatArray, faces: IntArray) -> BoolArray:
    """Which triangles have area (not a repeated corner, not collinear corners)."""
    corners = vertices[faces]
    edges = np.roll(corners, -1, axis=1) - corners
    longest_sq = np.max(np.sum(edges * edges, axis=2), axis=1)
    doubled_area = np.linalg.norm(np.cross(edges[:, 0], -edges[:, 2]), axis=1)
    repeated = (
        (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    )
    return np.asarray(~(repeated | (doubled_area <= _DEGENERATE_ASPECT * longest_sq)))


def _drop_unused_vertices(vertices: FloatArray, faces: IntArray) -> tuple[FloatArray, IntArray]:
    used, new_index = np.unique(faces, return_inverse=True)
    return vertices[used], new_index.reshape(faces.shape).astype(np.int64)


# --- generated meshes ------------------------------------------------------------------------


def tessellate_hemisphere(radius_m: float, divisions: int) -> TriangleMesh:
    """A hemisphere of radius ``radius_m`` [m] centred at the origin, z ≥ 0, as 4·divisions²
    triangles: each of the four upper faces of an octahedron is split into a triangular lattice
    of ``divisions`` steps per edge and pushed radially onto the sphere. The rim lies exactly on
    z = 0 and every vertex exactly on the sphere; edges are about πR / (2·divisions) long.
    """
    if not radius_m > 0.0:
        raise ValueError(f"radius_m must be a positive length in metres, got {radius_m!r}")
    if divisions < 1:
        raise ValueError(f"divisions must be ≥ 1, got {divisions!r}")
    n = int(divisions)
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    i, j = i[keep], j[keep]
    lattice_index = np.full((n + 1, n + 1), -1, dtype=np.int64)
    lattice_index[i, j] = np.arange(i.size)
    lower_i, lower_j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    up = lower_i + lower_j <= n - 1
    down = lower_i + lower_j <= n - 2
    li, lj = lower_i[up], lower_j[up]
    di, dj = lower_i[down], lower_j[down]
    lattice_faces = np.concatenate(
        (
            np.column_stack(
                (lattice_index[li, lj], lattice_index[li + 1, lj], lattice_index[li, lj + 1])
            ),
            np.column_stack(
                (
                    lattice_index[di + 1, dj],
                    lattice_index[di + 1, dj + 1],
                    lattice_index[di, dj + 1],
                )
            ),
        )
    )
    pole = np.array([0.0, 0.0, 1.0])
    vertices, faces = [], []
    for quarter in range(4):
        angle = 0.5 * np.pi * quarter
        start = np.array([np.cos(angle), np.sin(angle), 0.0])
        end = np.array([-np.sin(angle), np.cos(angle), 0.0])
        # (end − start) × (pole − start) points away from the origin: outward winding.
        points = start + np.outer(i / n, end - start) + np.outer(j / n, pole - start)
        faces.append(lattice_faces + quarter * i.size)
        vertices.append(points)
    unit = np.concatenate(vertices)
    unit /= np.linalg.norm(unit, axis=1, keepdims=True)
    return TriangleMesh(radius_m * unit, np.concatenate(faces))


# --- STL -------------------------------------------------------------------------------------

_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


class MeshFileError(ValueError):
    """A tool mesh file that cannot be read safely: missing, not a regular file, too large."""


#: Bytes per MB in ``limits.max_mesh_mb`` (decimal megabytes, as file managers show them).
MB = 1_000_000


def check_mesh_file(path: str | Path, max_bytes: int | None = None) -> int:
    """Refuse a mesh path before anything reads it; returns its size [bytes].

    Only a regular file is read: a device (``/dev/zero`` never ends), a FIFO (reading blocks
    until a writer appears, possibly forever) or a directory is refused, as is a file larger
    than ``max_bytes`` (a scene's ``limits.max_mesh_mb``), judged by ``stat`` so that a 2 GB
    file costs nothing to refuse. ``stat`` follows symbolic links, so a link to a device is
    refused like the device. An empty file is refused too: besides being no mesh, a size of 0
    is what ``/proc`` pseudo-files report whatever they hold.
    """
    file = Path(path)
    try:
        info = os.stat(file)
    except FileNotFoundError:
        raise MeshFileError(f"{file}: no such file") from None
    except OSError as error:
        raise MeshFileError(f"{file}: cannot be read: {error.strerror or error}") from None
    mode = info.st_mode
    if not stat.S_ISREG(mode):
        kind = (
            "a directory"
            if stat.S_ISDIR(mode)
            else "a FIFO (named pipe)"
            if stat.S_ISFIFO(mode)
            else "a character device"
            if stat.S_ISCHR(mode)
            else "a block device"
            if stat.S_ISBLK(mode)
            else "a socket"
            if stat.S_ISSOCK(mode)
            else "not a regular file"
        )
        raise MeshFileError(
            f"{file}: is {kind}, not a regular file; a tool mesh must be an STL or OBJ file"
        )
    if info.st_size == 0:
        # Also what every /proc pseudo-file reports, some of which never end or block.
        raise MeshFileError(f"{file}: is empty (0 bytes); a tool mesh must be an STL or OBJ file")
    if max_bytes is not None and info.st_size > max_bytes:
        raise MeshFileError(
            f"{file}: {info.st_size / MB:.1f} MB, larger than the limit of {max_bytes / MB:g} MB "
            "(limits.max_mesh_mb); decimate the mesh or raise limits.max_mesh_mb in the scene"
        )
    return int(info.st_size)


def _read_limited(file: Path, max_bytes: int | None) -> bytes:
    """The bytes of a checked mesh file, never more than ``max_bytes`` (+1 to detect growth)."""
    check_mesh_file(file, max_bytes)
    with open(file, "rb") as handle:
        data = handle.read() if max_bytes is None else handle.read(max_bytes + 1)
    if max_bytes is not None and len(data) > max_bytes:
        raise MeshFileError(
            f"{file}: grew past the limit of {max_bytes / MB:g} MB (limits.max_mesh_mb) while "
            "being read"
        )
    return data


def read_stl(
    path: str | Path,
    units_to_m: float = 1e-3,
    *,
    max_bytes: int | None = None,
    weld_tolerance_m: float | None = None,
    max_edge_m: float | None = None,
    fold_angle_deg: float = FOLD_ANGLE_DEG,
    feature_angle_deg: float = DEFAULT_FEATURE_ANGLE_DEG,
    smooth_normals: bool = False,
) -> ToolMesh:
    """Read an ASCII or binary STL file whose coordinates are in units of ``units_to_m`` metres
    (1e-3: millimetres) and repair it as a scene's tool is. Binary vs ASCII is decided by
    content, not by the leading "solid" (binary headers often start with it too): a file that
    starts with "solid" and contains no NUL byte is ASCII; otherwise it is binary if its size is
    84 + 50·N for the N triangles its header declares. Malformed files raise ``ValueError``
    naming the file (and line, for ASCII).

    Only regular files are read, and none larger than ``max_bytes`` (:func:`check_mesh_file`);
    ``MeshFileError`` (a ``ValueError``) says which limit refused it.

    The triangles go through ``mesh_hygiene.repair`` with a scene's defaults and knobs, in SI:
    ``weld_tolerance_m`` [m] (default 1e-6 × the bounding-box diagonal), ``max_edge_m`` [m]
    (default none), ``fold_angle_deg`` [°] (default 160); ``feature_angle_deg`` [°] (the
    drape's crease rule) and ``smooth_normals`` are :class:`TriangleMesh`'s. What cannot be
    repaired (a fin, a one-sided surface, a fold) raises ``MeshRefused`` naming the file, with
    the place in ``where_m`` [m]. The result is a ``ToolMesh`` whose ``hygiene`` report counts
    what was repaired; the repairs, and folds a raised ``fold_angle_deg`` let through, are also
    said as a warning."""
    return _read_tool(
        path,
        "STL",
        units_to_m,
        max_bytes,
        weld_tolerance_m,
        max_edge_m,
        fold_angle_deg,
        feature_angle_deg,
        smooth_normals,
    )


def _read_tool(
    path: str | Path,
    kind: str,
    units_to_m: float,
    max_bytes: int | None,
    weld_tolerance_m: float | None,
    max_edge_m: float | None,
    fold_angle_deg: float,
    feature_angle_deg: float,
    smooth_normals: bool,
) -> ToolMesh:
    """A file read by :func:`read_stl` or :func:`read_obj`: the scene's reader (one
    implementation), and its repairs and cautions said as a warning."""
    # tool_mesh builds on this module: imported when a file is read, not when this module is.
    from preform.plugins.surfaces.tool_mesh import ToolSource, read_tool_file

    scale = _scale(units_to_m)
    unit = _UNIT_NAMES.get(scale, f"{scale:g} m")
    source = ToolSource(str(path), kind, unit, f"units_to_m = {scale:g}")
    mesh = read_tool_file(
        Path(path),
        source,
        scale,
        max_bytes=max_bytes,
        weld_tolerance_m=weld_tolerance_m,
        max_edge_m=max_edge_m,
        fold_angle_deg=fold_angle_deg,
        feature_angle_deg=feature_angle_deg,
        smooth_normals=smooth_normals,
    )
    said = [*mesh.hygiene.repairs(), *mesh.hygiene.cautions()]
    if said:
        warnings.warn(f"{path}: " + "; ".join(said), stacklevel=3)
    return mesh


#: Names of the length units a reader's ``units_to_m`` commonly is, for the tool's source.
_UNIT_NAMES = {1e-3: "mm", 1.0: "m", 0.0254: "in"}


def stl_triangles(
    path: str | Path, units_to_m: float = 1e-3, *, max_bytes: int | None = None
) -> tuple[FloatArray, IntArray]:
    """The triangles of an STL file as read (:func:`read_stl`), before any merging: vertices
    (3m, 3) [m], every triangle's corners its own, and faces (m, 3)."""
    file = Path(path)
    data = _read_limited(file, max_bytes)
    if data.lstrip()[:5].lower() == b"solid" and b"\x00" not in data:
        corners = _parse_ascii_stl(file, data)
    else:
        if len(data) < 84:
            raise ValueError(
                f"{file}: not an STL file: {len(data)} bytes, shorter than a binary header"
            )
        count = int.from_bytes(data[80:84], "little")
        if len(data) != 84 + 50 * count:
            raise ValueError(
                f"{file}: not a valid binary STL: the header declares {count} triangles, which "
                f"needs {84 + 50 * count} bytes, but the file has {len(data)} (and it is not "
                "ASCII STL either: that starts with 'solid' and has no NUL bytes)"
            )
        if count == 0:
            raise ValueError(f"{file}: binary STL with no triangles")
        records = np.frombuffer(data, dtype=_STL_RECORD, count=count, offset=84)
        corners = records["corners"].astype(np.float64)
        bad = np.flatnonzero(~np.all(np.isfinite(corners), axis=(1, 2)))
        if bad.size:
            raise ValueError(f"{file}: triangle {bad[0]} has a non-finite coordinate")
    vertices = corners.reshape(-1, 3) * _scale(units_to_m)
    return vertices, np.arange(vertices.shape[0]).reshape(-1, 3)


def _scale(units_to_m: float) -> float:
    scale = float(units_to_m)
    if not np.isfinite(scale) or scale <= 0.0:
        raise ValueError(f"units_to_m must be a positive factor, got {units_to_m!r}")
    return scale


def _parse_floats(file: Path, line_no: int, tokens: list[str], what: str) -> list[float]:
    try:
        values = [float(t) for t in tokens]
    except ValueError:
        raise ValueError(
            f"{file}:{line_no}: {what}: not a number in {' '.join(tokens)!r}"
        ) from None
    if not all(np.isfinite(values)):
        raise ValueError(f"{file}:{line_no}: {what}: non-finite value in {' '.join(tokens)!r}")
    return values


def _parse_ascii_stl(file: Path, data: bytes) -> FloatArray:
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as error:
        raise ValueError(
            f"{file}: ASCII STL contains a non-ASCII byte at offset {error.start}"
        ) from None
    corners: list[list[float]] = []
    state = "outside"  # outside → solid → facet → loop → (vertices) → facet → solid → outside
    loop_vertices = 0
    line_no = 0
    for line_no, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if not tokens:
            continue
        keyword = tokens[0].lower()
        expected = {
            "solid": "outside",
            "facet": "solid",
            "outer": "facet",
            "vertex": "loop",
            "endloop": "loop",
            "endfacet": "facet",
            "endsolid": "solid",
        }.get(keyword)
        if expected is None:
            raise ValueError(f"{file}:{line_no}: unknown ASCII STL keyword {tokens[0]!r}")
        if state != expected:
            raise ValueError(f"{file}:{line_no}: {tokens[0]!r} out of place (inside {state})")
        if keyword == "solid":
            state = "solid"
        elif keyword == "facet":
            if len(tokens) != 5 or tokens[1].lower() != "normal":
                raise ValueError(
                    f"{file}:{line_no}: expected 'facet normal nx ny nz', got {line.strip()!r}"
                )
            _parse_floats(file, line_no, tokens[2:], "facet normal")
            state = "facet"
        elif keyword == "outer":
            if len(tokens) != 2 or tokens[1].lower() != "loop":
                raise ValueError(f"{file}:{line_no}: expected 'outer loop', got {line.strip()!r}")
            state, loop_vertices = "loop", 0
        elif keyword == "vertex":
            if len(tokens) != 4:
                raise ValueError(f"{file}:{line_no}: expected 'vertex x y z', got {line.strip()!r}")
            corners.append(_parse_floats(file, line_no, tokens[1:], "vertex"))
            loop_vertices += 1
        elif keyword == "endloop":
            if loop_vertices != 3:
                raise ValueError(
                    f"{file}:{line_no}: facet has {loop_vertices} vertices, STL needs 3"
                )
            state = "facet"
        elif keyword == "endfacet":
            state = "solid"
        else:
            state = "outside"
    if state != "outside":
        raise ValueError(f"{file}:{line_no}: file ends inside a {state} (missing 'end{state}')")
    if not corners:
        raise ValueError(f"{file}: ASCII STL with no triangles")
    return np.array(corners).reshape(-1, 3, 3)


def write_stl(
    path: str | Path,
    mesh: TriangleMesh,
    units_to_m: float = 1e-3,
    *,
    binary: bool = True,
    name: str = "preform",
) -> None:
    """Write ``mesh`` as an STL file in units of ``units_to_m`` metres (1e-3: millimetres).
    Binary STL stores float32 (about 7 significant digits); ASCII is written with full float64
    precision so it round-trips exactly."""
    corners = mesh.vertices[mesh.faces] / _scale(units_to_m)
    normals = mesh.face_normals
    file = Path(path)
    if binary:
        records = np.zeros(corners.shape[0], dtype=_STL_RECORD)
        records["normal"] = normals
        records["corners"] = corners
        # The header must not start with "solid", or naive readers take the file for ASCII.
        header = f"binary STL written by preform: {name}".encode("ascii")[:80].ljust(80, b" ")
        file.write_bytes(header + np.uint32(corners.shape[0]).tobytes() + records.tobytes())
        return
    lines = [f"solid {name}"]
    for normal, triangle in zip(normals, corners, strict=True):
        lines.append("  facet normal " + " ".join(repr(float(v)) for v in normal))
        lines.append("    outer loop")
        lines.extend(
            "      vertex " + " ".join(repr(float(v)) for v in corner) for corner in triangle
        )
        lines.append("    endloop")
        lines.append("  endfacet")
    lines.append(f"endsolid {name}")
    file.write_text("\n".join(lines) + "\n", encoding="ascii")


# --- OBJ -------------------------------------------------------------------------------------

#: OBJ statements that carry nothing a tool surface needs.
_OBJ_IGNORED = {"vt", "vn", "vp", "g", "o", "s", "usemtl", "mtllib", "l", "p", "mg", "lod"}


def read_obj(
    path: str | Path,
    units_to_m: float = 1e-3,
    *,
    max_bytes: int | None = None,
    weld_tolerance_m: float | None = None,
    max_edge_m: float | None = None,
    fold_angle_deg: float = FOLD_ANGLE_DEG,
    feature_angle_deg: float = DEFAULT_FEATURE_ANGLE_DEG,
    smooth_normals: bool = False,
) -> ToolMesh:
    """Read the polygon faces of a Wavefront OBJ file whose coordinates are in units of
    ``units_to_m`` metres (1e-3: millimetres).

    Reads ``v x y z [w]`` (w ignored) and ``f`` lines with ``v``, ``v/vt``, ``v//vn`` or
    ``v/vt/vn`` corners; indices are 1-based, negative ones count back from the last vertex read
    so far. Polygons are fan-triangulated from their first corner (fine for the convex polygons
    CAD writes). Texture, normal, grouping and material statements are ignored. Malformed lines
    raise ``ValueError`` with file:line and what is wrong. Only regular files no larger than
    ``max_bytes`` are read (:func:`check_mesh_file`).

    Repaired as :func:`read_stl` says (same knobs); each ``g``/``o`` group is a face of the
    returned ``ToolMesh``, as in a scene."""
    return _read_tool(
        path,
        "OBJ",
        units_to_m,
        max_bytes,
        weld_tolerance_m,
        max_edge_m,
        fold_angle_deg,
        feature_angle_deg,
        smooth_normals,
    )


def obj_triangles(
    path: str | Path, units_to_m: float = 1e-3, *, max_bytes: int | None = None
) -> tuple[FloatArray, IntArray, list[str]]:
    """The triangles of an OBJ file as read (:func:`read_obj`), before any merging: vertices
    (n, 3) [m], faces (m, 3), and each triangle's group: the name of the last ``g`` or ``o``
    statement before it ("" before any)."""
    file = Path(path)
    vertices: list[list[float]] = []
    triangles: list[tuple[int, int, int]] = []
    triangle_lines: list[int] = []
    triangle_groups: list[str] = []
    group = ""
    text = _read_limited(file, max_bytes).decode("utf-8", errors="replace")
    for line_no, raw in enumerate(text.splitlines(), start=1):
        tokens = raw.split("#", 1)[0].split()
        if not tokens:
            continue
        keyword = tokens[0]
        if keyword == "v":
            if len(tokens) not in (4, 5):
                raise ValueError(f"{file}:{line_no}: expected 'v x y z [w]', got {raw.strip()!r}")
            vertices.append(_parse_floats(file, line_no, tokens[1:4], "vertex"))
        elif keyword == "f":
            if len(tokens) < 4:
                raise ValueError(
                    f"{file}:{line_no}: a face needs at least 3 corners, got {raw.strip()!r}"
                )
            corners = [_obj_vertex_index(file, line_no, t, len(vertices)) for t in tokens[1:]]
            for k in range(1, len(corners) - 1):
                triangles.append((corners[0], corners[k], corners[k + 1]))
                triangle_lines.append(line_no)
                triangle_groups.append(group)
        elif keyword in ("g", "o"):
            group = " ".join(tokens[1:])
        elif keyword in _OBJ_IGNORED or keyword.isalpha():
            continue
        else:
            raise ValueError(f"{file}:{line_no}: not an OBJ statement: {raw.strip()!r}")
    if not triangles:
        raise ValueError(f"{file}: OBJ file with no faces")
    faces = np.array(triangles, dtype=np.int64)
    beyond = np.flatnonzero(np.any(faces >= len(vertices), axis=1))
    if beyond.size:
        raise ValueError(
            f"{file}:{triangle_lines[beyond[0]]}: face refers to a vertex beyond the "
            f"{len(vertices)} the file defines"
        )
    return np.array(vertices) * _scale(units_to_m), faces, triangle_groups


def _obj_vertex_index(file: Path, line_no: int, token: str, n_read: int) -> int:
    field = token.split("/", 1)[0]
    try:
        index = int(field)
    except ValueError:
        raise ValueError(
            f"{file}:{line_no}: face corner {token!r} has no integer vertex index"
        ) from None
    if index == 0:
        raise ValueError(f"{file}:{line_no}: face corner {token!r}: OBJ indices start at 1, not 0")
    if index < 0:
        if -index > n_read:
            raise ValueError(
                f"{file}:{line_no}: face corner {token!r} counts back past the first vertex "
                f"(only {n_read} read so far)"
            )
        return n_read + index
    return index - 1
