"""Mesh hygiene: repair what CAD exports contain before a tool mesh is draped, and say what.

A tool mesh read from a file is a list of triangles (vertices [m], faces). CAD exports carry
defects a pin-jointed net must not meet unannounced; :func:`repair` finds and mends them in
this order, each step working on the previous one's result:

1. **Weld.** Vertices closer than the weld tolerance [m] become one (transitively: a chain of
   close vertices merges whole; with a tolerance far below the edge lengths that is what is
   meant). Exact copies (STL stores every corner of every triangle) are counted as
   *duplicate vertices*; vertices that were apart but within the tolerance close a *crack*
   (an unwelded edge) and are counted separately. The merged vertex sits at its copies' mean.
2. **Degenerate triangles** (two corners welded into one, or a corner within the weld
   tolerance of the opposite edge: no area to drape on) are dropped.
3. **Duplicate triangles** (the same three vertices, either winding) are dropped but one.
4. **T-junctions.** A vertex lying on another triangle's open edge (within the weld tolerance)
   means the two sides were tessellated apart (or a degenerate triangle was dropped between
   them): the triangle is split there so the edge is shared. Repeated until none is left.
5. **Non-manifold edges** (one edge shared by three or more triangles: fins, internal faces,
   two bodies touching along an edge) have no "other side" to cross: refused, with where.
6. **Orientation.** Triangles are wound consistently, piece by piece, across shared edges,
   keeping the winding of the larger area; a surface that cannot be wound consistently (a
   Möbius band) is refused, with where. Then a closed piece is turned so its normals point
   out of the solid (positive enclosed volume) and an open piece so that its area-weighted
   mean normal points up (+z, the side the fabric lies on), the convention of
   ``preform.plugins.surfaces.mesh``.
7. **Folds.** An edge across which the surface turns back on itself (its two triangles'
   normals, consistently wound, turn by more than :data:`FOLD_ANGLE_DEG`) is a triangle turned
   over: a vertex pushed through the surface, a tessellation or export error. Winding cannot
   see it (the windings agree across the edge; the geometry does not), and a net or a geodesic
   would follow the fold and bend silently, so it is refused, with where: there is no repair
   that keeps the user's surface (where the vertex belongs is not known), and a real edge that
   sharp (a wedge thinner than 180° − :data:`FOLD_ANGLE_DEG`) is beyond what a pin-jointed net
   is known to follow. A caller who knows the edge is real raises ``fold_angle_deg`` past it
   (a scene: ``tool.fold_angle_deg``); the edges that lets through are counted and said
   (:meth:`HygieneReport.cautions`).
8. **Long edges** (only when a largest edge length is given): triangles are split (an edge
   at its midpoint, or a triangle into four) until no edge is longer. New vertices lie on the
   old facets, so the surface is exactly what it was; only its triangles are smaller. A CAD
   tessellation covers a large flat face with a few long triangles, and closest-point
   queries, which bound their search by the largest triangle, slow down by the number of
   triangles there.
9. **Slivers** (smallest angle below :data:`SLIVER_ANGLE_DEG`) are counted and located, not
   changed: they are real surface, and removing them would open holes.

The :class:`HygieneReport` counts each of these, and says in words what was repaired
(:meth:`HygieneReport.repairs`, for the case's console and summary) and what was left as it
is (:meth:`HygieneReport.remarks`: slivers, for the summary).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import FloatArray, IntArray

#: Weld tolerance when a scene gives none, as a fraction of the mesh's bounding-box diagonal
#: [-]: the value ``TriangleMesh`` has always merged vertices with (float32 STL coordinates
#: carry about 1e-7 relative error, so copies of one corner are well within it).
DEFAULT_WELD_TOLERANCE_REL = 1e-6
#: Triangles whose smallest angle is below this [deg] are reported as slivers [C] (a choice:
#: at 1° the longest edge is about 57 × the triangle's height, where closest-point and
#: circle-intersection arithmetic loses about two digits).
SLIVER_ANGLE_DEG = 1.0
#: The turn [deg] of the surface normal across an edge (between its two triangles' normals,
#: consistently wound: 0° flat, 90° a right-angled crease, 180° folded flat back) above which
#: the edge is a fold and the mesh is refused (module docstring, 7) [C]. A choice between two
#: bounds: above 150°, the sharpest real crease a tool is expected to have (a 30° wedge; sharp
#: CAD edges of 90-150° must pass, and the feature-crease rule, ``feature_angle_deg`` ≤ 180°,
#: acts on them), and below 180° − 15°, what a triangle turned over on a tessellation of a
#: smooth tool still turns against its neighbours when neighbouring facets differ by up to the
#: CAD tessellation angle (15° by default); in a plane a turned-over triangle turns by 180°.
#: Measured: every vertex of a dome with facets up to 18° apart pushed past the opposite edge
#: of a triangle around it turns that triangle by at least 163.6° (tests/surfaces/
#: test_mesh_folds.py); on facets 25° apart some turn by less and pass.
FOLD_ANGLE_DEG = 160.0
#: Rounds of long-edge splitting before giving up (each halves the longest edges).
_MAX_REFINE_ROUNDS = 64
#: Rounds of T-junction splitting before giving up (each round splits every open edge at all
#: the vertices lying on it, so one round normally suffices; the second confirms).
_MAX_SPLIT_ROUNDS = 8
MM = 1e-3


class MeshRefused(ValueError):
    """A tool mesh that cannot be draped even after repair; the message says where and why,
    and ``where_m`` is that place [m] (None when the refusal has no one place)."""

    def __init__(self, message: str, where_m: FloatArray | None = None) -> None:
        super().__init__(message)
        self.where_m = None if where_m is None else np.asarray(where_m, dtype=np.float64)


@dataclass
class HygieneReport:
    """What :func:`repair` found and did; counts are of triangles or vertices as named."""

    triangles_read: int
    vertices_read: int
    weld_tolerance_m: float
    duplicate_vertices: int = 0
    cracks_welded: int = 0
    degenerate_dropped: int = 0
    duplicate_triangles_dropped: int = 0
    t_junctions_split: int = 0
    flipped_triangles: int = 0
    #: Pieces turned over whole (normals pointed into the solid, or down on an open tool).
    pieces_turned: int = 0
    #: Largest edge length asked for [m] (None: triangles kept as large as they came).
    max_edge_m: float | None = None
    #: Triangles added by splitting long edges (step 7).
    refined_triangles: int = 0
    slivers: int = 0
    #: Where the thinnest sliver is [m] and its smallest angle [deg] (None without slivers).
    worst_sliver_at_m: tuple[float, float, float] | None = None
    worst_sliver_angle_deg: float | None = None
    pieces: int = 1
    open_edges: int = 0
    triangles: int = 0
    vertices: int = 0
    #: The fold angle in force [deg] (step 7): ``FOLD_ANGLE_DEG`` unless the caller raised it.
    fold_angle_deg: float = FOLD_ANGLE_DEG
    #: Edges turning by more than ``FOLD_ANGLE_DEG`` that a raised ``fold_angle_deg`` let
    #: through, the sharpest turn [deg] and where it is [m] (None without such edges).
    folds_allowed: int = 0
    sharpest_fold_deg: float | None = None
    sharpest_fold_at_m: tuple[float, float, float] | None = None

    def repairs(self) -> list[str]:
        """What was repaired, in words (empty for a clean mesh)."""
        out = []
        tol = f"{self.weld_tolerance_m / MM:.3g} mm"
        if self.cracks_welded:
            out.append(
                f"welded {self.cracks_welded} vertices that were apart but within the weld "
                f"tolerance {tol} (cracks: unwelded edges)"
            )
        if self.degenerate_dropped:
            out.append(
                f"dropped {self.degenerate_dropped} degenerate triangles (no area within the "
                f"weld tolerance {tol})"
            )
        if self.duplicate_triangles_dropped:
            out.append(f"dropped {self.duplicate_triangles_dropped} duplicate triangles")
        if self.t_junctions_split:
            out.append(
                f"split {self.t_junctions_split} triangles at T-junctions (a vertex on "
                "another triangle's edge) so neighbouring triangles share their edges"
            )
        if self.flipped_triangles:
            out.append(
                f"re-wound {self.flipped_triangles} triangles whose normals disagreed with "
                "their neighbours'"
            )
        if self.pieces_turned:
            out.append(
                f"turned {self.pieces_turned} piece(s) over so the normals point out of the "
                "tool (up for an open surface, outward for a closed one)"
            )
        return out

    def remarks(self) -> list[str]:
        """What is worth knowing about the mesh but was left as it is (slivers, separate pieces),
        in words."""
        out = []
        if self.refined_triangles:
            assert self.max_edge_m is not None
            out.append(
                f"split long triangles into {self.refined_triangles} more so no edge exceeds "
                f"{self.max_edge_m / MM:.3g} mm (the surface is unchanged)"
            )
        if self.slivers:
            assert self.worst_sliver_at_m is not None and self.worst_sliver_angle_deg is not None
            x, y, z = (c / MM for c in self.worst_sliver_at_m)
            out.append(
                f"{self.slivers} sliver triangles (smallest angle below {SLIVER_ANGLE_DEG:g}°; "
                f"thinnest {self.worst_sliver_angle_deg:.2g}° at ({x:.4g}, {y:.4g}, {z:.4g}) "
                "mm) kept as they are; a finer or cleaner tessellation avoids them"
            )
        if self.pieces > 1:
            out.append(
                f"the tool is {self.pieces} separate pieces (no shared edge between them); a "
                "net cannot cross a gap between pieces"
            )
        return out

    def cautions(self) -> list[str]:
        """What the mesh holds that the drape may not follow, let through because the caller
        asked (a raised fold angle), in words (empty otherwise)."""
        if not self.folds_allowed:
            return []
        assert self.sharpest_fold_deg is not None and self.sharpest_fold_at_m is not None
        x, y, z = (c / MM for c in self.sharpest_fold_at_m)
        return [
            f"{self.folds_allowed} edge(s) where the surface turns back by more than "
            f"{FOLD_ANGLE_DEG:g}° (the sharpest {self.sharpest_fold_deg:.4g}° at ({x:.4g}, "
            f"{y:.4g}, {z:.4g}) mm) were let through by a fold angle of "
            f"{self.fold_angle_deg:g}°: a net or geodesic follows such an edge as it is, and "
            "one from a triangle turned over bends it; check the drape there"
        ]

    def summary(self) -> dict[str, float | int | str]:
        """Scalars for a case's summary (``mesh_*``; the largest edge only when one was asked)."""
        out: dict[str, float | int | str] = {
            "mesh_triangles_read": self.triangles_read,
            "mesh_triangles": self.triangles,
            "mesh_vertices": self.vertices,
            "mesh_weld_tolerance_mm": self.weld_tolerance_m / MM,
            "mesh_duplicate_vertices": self.duplicate_vertices,
            "mesh_cracks_welded": self.cracks_welded,
            "mesh_degenerate_dropped": self.degenerate_dropped,
            "mesh_duplicate_triangles_dropped": self.duplicate_triangles_dropped,
            "mesh_t_junctions_split": self.t_junctions_split,
            "mesh_flipped_triangles": self.flipped_triangles,
            "mesh_pieces_turned": self.pieces_turned,
            "mesh_refined_triangles": self.refined_triangles,
            "mesh_slivers": self.slivers,
            "mesh_pieces": self.pieces,
            "mesh_open_edges": self.open_edges,
            "mesh_repairs": "; ".join(self.repairs()) or "none",
            "mesh_remarks": "; ".join(self.remarks()) or "none",
            "mesh_fold_angle_deg": self.fold_angle_deg,
            "mesh_folds_allowed": self.folds_allowed,
        }
        if self.max_edge_m is not None:
            out["mesh_max_edge_mm"] = self.max_edge_m / MM
        return out


@dataclass(frozen=True)
class RepairedMesh:
    """A repaired triangle mesh: vertices (n, 3) [m], faces (m, 3), and for every face the
    index of the triangle of the input it comes from (``origin``; a split triangle's parts
    share theirs)."""

    vertices: FloatArray
    faces: IntArray
    origin: IntArray
    report: HygieneReport


def _where(point_m: FloatArray) -> str:
    x, y, z = (float(c) / MM for c in point_m)
    return f"({x:.6g}, {y:.6g}, {z:.6g}) mm"


def repair(
    vertices: FloatArray,
    faces: IntArray,
    weld_tolerance_m: float | None = None,
    *,
    max_edge_m: float | None = None,
    fold_angle_deg: float = FOLD_ANGLE_DEG,
) -> RepairedMesh:
    """Repair a triangle mesh (module docstring); ``weld_tolerance_m`` [m] defaults to
    :data:`DEFAULT_WELD_TOLERANCE_REL` × the bounding-box diagonal; ``max_edge_m`` [m], if
    given, is the longest edge left (step 8); ``fold_angle_deg`` [deg] is the normal's turn
    across an edge above which it is a fold (step 7; 180 turns the check off).

    Raises :class:`MeshRefused` for what cannot be repaired (non-manifold edges, a surface
    that cannot be wound consistently, a fold, nothing left with area), saying where in mm and
    which triangle of the input (counted from 1)."""
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError("vertices must be (n, 3) [m] and faces (m, 3) vertex indices")
    if faces.shape[0] == 0:
        raise MeshRefused("the mesh has no triangles")
    if not np.all(np.isfinite(vertices)):
        raise MeshRefused("the mesh has non-finite vertex coordinates")
    if faces.min() < 0 or faces.max() >= vertices.shape[0]:
        raise ValueError("faces index vertices outside the vertex array")
    used = vertices[np.unique(faces)]
    diagonal = float(np.linalg.norm(used.max(axis=0) - used.min(axis=0)))
    if diagonal == 0.0:
        raise MeshRefused("the mesh has no extent: all its vertices coincide")
    if weld_tolerance_m is None:
        weld_tolerance_m = DEFAULT_WELD_TOLERANCE_REL * diagonal
    if not weld_tolerance_m >= 0.0:
        raise ValueError(f"weld tolerance must be ≥ 0 m, got {weld_tolerance_m!r}")
    if max_edge_m is not None and not (np.isfinite(max_edge_m) and max_edge_m > 0.0):
        raise ValueError(f"largest edge must be a positive length [m], got {max_edge_m!r}")
    _check_fold_angle(fold_angle_deg)
    report = HygieneReport(
        triangles_read=int(faces.shape[0]),
        vertices_read=int(vertices.shape[0]),
        weld_tolerance_m=float(weld_tolerance_m),
        max_edge_m=None if max_edge_m is None else float(max_edge_m),
    )
    origin = np.arange(faces.shape[0], dtype=np.int64)

    vertices, faces = _weld(vertices, faces, weld_tolerance_m, report)
    keep = ~_degenerate(vertices, faces, weld_tolerance_m)
    report.degenerate_dropped = int(np.count_nonzero(~keep))
    faces, origin = faces[keep], origin[keep]
    if faces.shape[0] == 0:
        raise MeshRefused(
            "the mesh has no triangle of non-zero area (none beyond the weld tolerance "
            f"{weld_tolerance_m / MM:.3g} mm)"
        )
    _, which = _unique_rows(np.sort(faces, axis=1))
    first = np.sort(np.unique(which, return_index=True)[1])
    report.duplicate_triangles_dropped = int(faces.shape[0] - first.size)
    faces, origin = faces[first], origin[first]
    faces, origin = _split_t_junctions(vertices, faces, origin, weld_tolerance_m, report)
    faces = check_surface(vertices, faces, report, origin=origin, fold_angle_deg=fold_angle_deg)
    if max_edge_m is not None:
        before = faces.shape[0]
        vertices, faces, origin = _split_long_edges(vertices, faces, origin, max_edge_m)
        report.refined_triangles = int(faces.shape[0] - before)
    _slivers(vertices, faces, report)
    vertices, faces = _drop_unused(vertices, faces)
    report.triangles, report.vertices = int(faces.shape[0]), int(vertices.shape[0])
    return RepairedMesh(vertices, faces, origin, report)


def _check_fold_angle(fold_angle_deg: float) -> None:
    if not 0.0 < fold_angle_deg <= 180.0:
        raise ValueError(f"fold angle must be in (0, 180] degrees, got {fold_angle_deg!r}")


def check_surface(
    vertices: FloatArray,
    faces: IntArray,
    report: HygieneReport,
    *,
    origin: IntArray | None = None,
    fold_angle_deg: float = FOLD_ANGLE_DEG,
    turn_pieces: bool = True,
) -> IntArray:
    """Steps 5-7 of :func:`repair` on a welded mesh without degenerate triangles: refuse
    non-manifold edges, wind every piece consistently (refusing a one-sided surface), turn
    pieces out or up (only with ``turn_pieces``), refuse folds past ``fold_angle_deg`` [deg].
    Returns the re-wound faces; counts go in ``report`` (``open_edges``, ``pieces``,
    ``flipped_triangles``, ``pieces_turned``, the fold entries). ``origin`` numbers each face
    as the caller's input did (default: its row), for the refusals' "input triangle N".

    A ``TriangleMesh`` built from arrays runs this without ``turn_pieces``: the caller's
    winding says which side is out, and only triangles disagreeing with their piece are
    re-wound; ``repair`` runs it whole."""
    _check_fold_angle(fold_angle_deg)
    faces = np.asarray(faces, dtype=np.int64)
    if origin is None:
        origin = np.arange(faces.shape[0], dtype=np.int64)
    edges, edge_of_face = _edges(faces)
    count = np.bincount(edge_of_face.ravel(), minlength=edges.shape[0])
    crowded = np.flatnonzero(count > 2)
    if crowded.size:
        e = crowded[0]
        sharing = np.flatnonzero(np.any(edge_of_face == e, axis=1))
        midpoint = vertices[edges[e]].mean(axis=0)
        raise MeshRefused(
            f"{crowded.size} non-manifold edge(s): the edge at {_where(midpoint)} is shared by "
            f"{count[e]} triangles (input triangles "
            f"{', '.join(str(int(origin[f]) + 1) for f in sharing[:6])}); a tool surface must "
            "be one sheet there: remove the fin, internal face or second body in CAD",
            midpoint,
        )
    report.open_edges = int(np.count_nonzero(count == 1))
    # the two faces of every manifold edge, found once for winding and folds
    pairs = _edge_pairs(edge_of_face, count)
    faces = _orient(vertices, faces, edge_of_face, count, pairs, origin, report, turn_pieces)
    report.fold_angle_deg = float(fold_angle_deg)
    _refuse_folds(vertices, faces, edges, pairs, origin, fold_angle_deg, report)
    return faces


def _weld(
    vertices: FloatArray, faces: IntArray, tolerance: float, report: HygieneReport
) -> tuple[FloatArray, IntArray]:
    """Merge vertices within ``tolerance`` [m]; count exact copies and crack closures."""
    # Only vertices some face uses: unused ones are neither duplicates nor cracks.
    used, faces = np.unique(faces, return_inverse=True)
    faces = faces.reshape(-1, 3).astype(np.int64)
    vertices = vertices[used]
    exact, exact_label = _unique_rows(vertices)
    report.duplicate_vertices = int(vertices.shape[0] - exact.shape[0])
    label = np.arange(exact.shape[0])
    if tolerance > 0.0:
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components
        from scipy.spatial import cKDTree

        pairs = cKDTree(exact).query_pairs(tolerance, output_type="ndarray")
        if pairs.size:
            n = exact.shape[0]
            links = coo_matrix((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), (n, n))
            _, label = connected_components(links, directed=False)
    n_welded = int(label.max()) + 1
    report.cracks_welded = int(exact.shape[0] - n_welded)
    sums = np.zeros((n_welded, 3))
    np.add.at(sums, label, exact)
    merged = sums / np.bincount(label, minlength=n_welded)[:, None]
    return merged, label[exact_label][faces]


def _unique_rows(rows: NDArray[Any]) -> tuple[NDArray[Any], IntArray]:
    """The distinct rows of a 2-D array (sorted) and each row's index among them: what
    ``np.unique(rows, axis=0, return_inverse=True)`` gives, by a lexicographic sort of the
    columns (many times faster than its sort of whole rows as opaque bytes)."""
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    starts = np.concatenate([[True], np.any(ordered[1:] != ordered[:-1], axis=1)])
    inverse = np.empty(rows.shape[0], dtype=np.int64)
    inverse[order] = np.cumsum(starts) - 1
    return ordered[starts], inverse


def _degenerate(vertices: FloatArray, faces: IntArray, tolerance: float) -> NDArray[np.bool_]:
    """Triangles with a repeated vertex, or whose height over their longest edge is within
    ``tolerance`` [m] (or zero to rounding)."""
    corners = vertices[faces]
    edges = np.roll(corners, -1, axis=1) - corners
    longest_sq = np.max(np.sum(edges * edges, axis=2), axis=1)
    doubled_area = np.linalg.norm(np.cross(edges[:, 0], -edges[:, 2]), axis=1)
    repeated = (
        (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    )
    height = doubled_area / np.sqrt(np.maximum(longest_sq, 1e-300))
    flat = (height <= tolerance) | (doubled_area <= 1e-12 * longest_sq)
    return np.asarray(repeated | flat)


def _edges(faces: IntArray) -> tuple[IntArray, IntArray]:
    """Unique undirected edges (k, 2) and, per face, the index of its edges (i→i+1)."""
    directed = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)
    edges, inverse = _unique_rows(np.sort(directed, axis=1))
    return edges, inverse.reshape(-1, 3)


def _edge_pairs(
    edge_of_face: IntArray, count: IntArray
) -> tuple[IntArray, IntArray, IntArray, IntArray, IntArray]:
    """Every edge shared by exactly two faces (``count`` == 2): the edge, its two faces and
    the slot (0-2) each face holds it in, in the order of the edges."""
    shared = np.flatnonzero(count == 2)
    rows, slots = np.nonzero(np.isin(edge_of_face, shared))
    order = np.argsort(edge_of_face[rows, slots], kind="stable")
    rows, slots = rows[order], slots[order]
    return shared, rows[0::2], rows[1::2], slots[0::2], slots[1::2]


def _split_t_junctions(
    vertices: FloatArray,
    faces: IntArray,
    origin: IntArray,
    tolerance: float,
    report: HygieneReport,
) -> tuple[IntArray, IntArray]:
    """Split triangles at vertices lying inside their open edges (module docstring, 4)."""
    from scipy.spatial import cKDTree

    for _ in range(_MAX_SPLIT_ROUNDS):
        edges, edge_of_face = _edges(faces)
        count = np.bincount(edge_of_face.ravel(), minlength=edges.shape[0])
        open_edges = np.flatnonzero(count == 1)
        if open_edges.size == 0 or tolerance <= 0.0:
            return faces, origin
        # Only vertices on open edges can hang on another open edge.
        candidates = np.unique(edges[open_edges])
        tree = cKDTree(vertices[candidates])
        a, b = vertices[edges[open_edges, 0]], vertices[edges[open_edges, 1]]
        half = 0.5 * np.linalg.norm(b - a, axis=1)
        near = tree.query_ball_point(0.5 * (a + b), half + tolerance)
        hanging: dict[int, list[tuple[float, int]]] = {}
        for k, found in enumerate(near):
            e = open_edges[k]
            ends = edges[e]
            axis = b[k] - a[k]
            length_sq = float(axis @ axis)
            for j in found:
                v = int(candidates[j])
                if v in (ends[0], ends[1]):
                    continue
                t = float((vertices[v] - a[k]) @ axis) / length_sq
                foot = a[k] + t * axis
                if 0.0 < t < 1.0 and np.linalg.norm(vertices[v] - foot) <= tolerance:
                    hanging.setdefault(int(e), []).append((t, v))
        if not hanging:
            return faces, origin
        new_faces, new_origin, split = [], [], np.zeros(faces.shape[0], dtype=bool)
        owner = np.empty(edges.shape[0], dtype=np.int64)
        owner[edge_of_face.ravel()] = np.repeat(np.arange(faces.shape[0]), 3)
        for e, points in hanging.items():
            f = int(owner[e])
            if split[f]:
                continue  # its other open edge's split waits for the next round
            split[f] = True
            i, j = edges[e]
            tri = faces[f]
            # Walk the face's corners so the split edge runs start → end in its winding.
            for r in range(3):
                if {int(tri[r]), int(tri[(r + 1) % 3])} == {int(i), int(j)}:
                    start, end, apex = int(tri[r]), int(tri[(r + 1) % 3]), int(tri[(r + 2) % 3])
                    break
            forward = start == edges[e, 0]
            chain = [v for _, v in sorted(points, reverse=not forward)]
            path = [start, *chain, end]
            for p, q in itertools.pairwise(path):
                new_faces.append((p, q, apex))
                new_origin.append(int(origin[f]))
        report.t_junctions_split += int(np.count_nonzero(split))
        faces = np.concatenate([faces[~split], np.array(new_faces, dtype=np.int64)])
        origin = np.concatenate([origin[~split], np.array(new_origin, dtype=np.int64)])
    return faces, origin


def _orient(
    vertices: FloatArray,
    faces: IntArray,
    edge_of_face: IntArray,
    count: IntArray,
    pairs: tuple[IntArray, IntArray, IntArray, IntArray, IntArray],
    origin: IntArray,
    report: HygieneReport,
    turn_pieces: bool = True,
) -> IntArray:
    """Wind every piece consistently (module docstring, 6), and with ``turn_pieces`` turn
    each out or up; returns the re-wound faces."""
    n_faces = faces.shape[0]
    # The two faces of every manifold edge, and whether each runs the edge low → high.
    _, pair_a, pair_b, slot_a, slot_b = pairs

    def runs_up(f: IntArray, s: IntArray) -> NDArray[np.bool_]:
        return np.asarray(faces[f, s] < faces[f, (s + 1) % 3])

    # Consistent neighbours run their shared edge in opposite directions.
    same_sense = runs_up(pair_a, slot_a) == runs_up(pair_b, slot_b)
    # Two copies of every face, as wound (f) and re-wound (f + n): neighbours that agree link
    # like copies, neighbours that disagree link crosswise. A piece is then two mirror
    # components, unless it is one-sided and both copies of a face fall in one component.
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    cross = same_sense.astype(np.int64) * n_faces
    src = np.concatenate([pair_a, pair_a + n_faces])
    dst = np.concatenate([pair_b + cross, (pair_b + n_faces - cross)])
    graph = coo_matrix((np.ones(src.size), (src, dst)), shape=(2 * n_faces, 2 * n_faces))
    _, label = connected_components(graph, directed=False)
    as_wound, rewound = label[:n_faces], label[n_faces:]
    one_sided = np.flatnonzero(as_wound == rewound)
    if one_sided.size:
        g = int(one_sided[0])
        where = vertices[faces[g]].mean(axis=0)
        raise MeshRefused(
            f"the surface cannot be wound consistently (it is one-sided, like a Möbius band) "
            f"around {_where(where)} (input triangle {int(origin[g]) + 1}); a tool must have "
            "an inside and an outside",
            where,
        )
    flip_of = (as_wound > rewound).astype(np.int64)
    _, piece = np.unique(np.minimum(as_wound, rewound), return_inverse=True)
    piece = piece.ravel().astype(np.int64)
    n_pieces = int(piece.max()) + 1
    report.pieces = n_pieces
    corners = vertices[faces]
    doubled = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = 0.5 * np.linalg.norm(doubled, axis=1)
    flip = flip_of.astype(bool)
    # Each piece keeps the winding of the larger area.
    flipped_area = np.bincount(piece, weights=area * flip, minlength=n_pieces)
    piece_area = np.bincount(piece, weights=area, minlength=n_pieces)
    flip ^= (flipped_area > 0.5 * piece_area)[piece]
    report.flipped_triangles = int(np.count_nonzero(flip))
    sign = np.where(flip, -1.0, 1.0)
    # Then turn whole pieces: closed ones outward (signed volume > 0), open ones up.
    closed_piece = np.ones(n_pieces, dtype=bool)
    open_faces = np.any(count[edge_of_face] == 1, axis=1)
    closed_piece[piece[open_faces]] = False
    volume = np.bincount(
        piece,
        weights=sign * np.einsum("ij,ij->i", corners[:, 0], doubled) / 6.0,
        minlength=n_pieces,
    )
    lift = np.bincount(piece, weights=sign * doubled[:, 2], minlength=n_pieces)
    turn = np.where(closed_piece, volume < 0.0, lift < 0.0) & turn_pieces
    report.pieces_turned = int(np.count_nonzero(turn))
    final = flip ^ turn[piece]
    out = faces.copy()
    out[final] = out[final][:, ::-1]
    return out


def _refuse_folds(
    vertices: FloatArray,
    faces: IntArray,
    edges: IntArray,
    pairs: tuple[IntArray, IntArray, IntArray, IntArray, IntArray],
    origin: IntArray,
    fold_angle_deg: float,
    report: HygieneReport,
) -> None:
    """Refuse edges across which the consistently wound surface turns by more than
    ``fold_angle_deg`` [deg] (module docstring, 7), naming the sharpest; with a fold angle
    raised past ``FOLD_ANGLE_DEG``, count in ``report`` the edges it let through.
    ``pairs`` (:func:`_edge_pairs`) may predate the re-winding of ``faces``: re-winding a face
    keeps its edges."""
    shared, pair_a, pair_b, _, _ = pairs
    corners = vertices[faces]
    doubled = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal = doubled / np.linalg.norm(doubled, axis=1, keepdims=True)
    a, b = normal[pair_a], normal[pair_b]
    # atan2 of sine and cosine keeps the turn exact near 180°, where arccos of the cosine
    # loses half its digits.
    turn = np.degrees(
        np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))
    )
    let_through = np.flatnonzero((turn > FOLD_ANGLE_DEG) & (turn <= fold_angle_deg))
    if let_through.size:
        k = int(let_through[np.argmax(turn[let_through])])
        report.folds_allowed = int(let_through.size)
        report.sharpest_fold_deg = float(turn[k])
        midpoint = vertices[edges[shared[k]]].mean(axis=0)
        report.sharpest_fold_at_m = (float(midpoint[0]), float(midpoint[1]), float(midpoint[2]))
    folded = np.flatnonzero(turn > fold_angle_deg)
    if not folded.size:
        return
    k = int(folded[np.argmax(turn[folded])])
    midpoint = vertices[edges[shared[k]]].mean(axis=0)
    first, second = sorted((int(origin[pair_a[k]]) + 1, int(origin[pair_b[k]]) + 1))
    # A triangle turned over in a smooth surface is folded against all its neighbours: the
    # triangle on most fold edges is the one to look at.
    on_folds = np.bincount(np.concatenate([pair_a[folded], pair_b[folded]]))
    worst = int(np.argmax(on_folds))
    raise MeshRefused(
        f"{folded.size} fold edge(s): the surface turns back on itself (the normals of the two "
        f"triangles on an edge turn by more than {fold_angle_deg:g}°); the sharpest, "
        f"{turn[k]:.4g}°, is the edge at {_where(midpoint)} between input triangles {first} "
        f"and {second}, and input triangle {int(origin[worst]) + 1} is folded across "
        f"{int(on_folds[worst])} of its edges. A triangle turned over (a vertex pushed through "
        "the surface, a tessellation or export error) makes a net follow the fold: move the "
        "vertex back or re-tessellate the tool; a real edge this sharp (a wedge thinner than "
        f"{180.0 - fold_angle_deg:g}°) is beyond what a net is known to follow: round it or give "
        "it a thickness in CAD, or, to drape it as it is, set the fold angle (a scene's "
        "tool.fold_angle_deg, or fold_angle_deg in Python) to at least "
        f"{turn[k]:.4g}° (180: no fold check)",
        midpoint,
    )


def _split_long_edges(
    vertices: FloatArray, faces: IntArray, origin: IntArray, max_edge: float
) -> tuple[FloatArray, IntArray, IntArray]:
    """Split triangles until no edge is longer than ``max_edge`` [m] (module docstring, 8).

    Each round marks the long edges, then also the third edge of every triangle with two
    marked (until none has two), puts a vertex at each marked edge's midpoint, and splits a
    triangle with one marked edge in two (through the opposite corner) and one with three in
    four. Neighbours split the shared edge at the same midpoint, so the mesh stays conforming;
    windings are kept."""
    for _ in range(_MAX_REFINE_ROUNDS):
        edges, edge_of_face = _edges(faces)
        length = np.linalg.norm(vertices[edges[:, 1]] - vertices[edges[:, 0]], axis=1)
        marked = length > max_edge
        if not marked.any():
            break
        while True:
            two = np.count_nonzero(marked[edge_of_face], axis=1) == 2
            if not two.any():
                break
            marked[edge_of_face[two]] = True
        midpoint = np.full(edges.shape[0], -1, dtype=np.int64)
        midpoint[marked] = vertices.shape[0] + np.arange(np.count_nonzero(marked))
        vertices = np.vstack(
            [vertices, 0.5 * (vertices[edges[marked, 0]] + vertices[edges[marked, 1]])]
        )
        mid = midpoint[edge_of_face]  # (F, 3): midpoint of edge k = corner k → k + 1, or -1
        n_marked = np.count_nonzero(mid >= 0, axis=1)
        keep = n_marked == 0
        pieces, owners = [faces[keep]], [origin[keep]]
        one = np.flatnonzero(n_marked == 1)
        k = np.argmax(mid[one] >= 0, axis=1)
        a = faces[one, k]
        b = faces[one, (k + 1) % 3]
        c = faces[one, (k + 2) % 3]
        m = mid[one, k]
        pieces += [np.stack([a, m, c], axis=1), np.stack([m, b, c], axis=1)]
        owners += [origin[one], origin[one]]
        all3 = np.flatnonzero(n_marked == 3)
        a, b, c = faces[all3, 0], faces[all3, 1], faces[all3, 2]
        ab, bc, ca = mid[all3, 0], mid[all3, 1], mid[all3, 2]
        pieces += [
            np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))
        ]
        owners += [origin[all3]] * 4
        faces = np.concatenate(pieces).astype(np.int64)
        origin = np.concatenate(owners).astype(np.int64)
    return vertices, faces, origin


def _slivers(vertices: FloatArray, faces: IntArray, report: HygieneReport) -> None:
    corners = vertices[faces]
    angles = []
    for k in range(3):
        u = corners[:, (k + 1) % 3] - corners[:, k]
        v = corners[:, (k + 2) % 3] - corners[:, k]
        cos = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        angles.append(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    smallest = np.min(np.stack(angles), axis=0)
    thin = smallest < SLIVER_ANGLE_DEG
    report.slivers = int(np.count_nonzero(thin))
    if report.slivers:
        worst = int(np.argmin(smallest))
        c = corners[worst].mean(axis=0)
        report.worst_sliver_at_m = (float(c[0]), float(c[1]), float(c[2]))
        report.worst_sliver_angle_deg = float(smallest[worst])


def _drop_unused(vertices: FloatArray, faces: IntArray) -> tuple[FloatArray, IntArray]:
    used, new_index = np.unique(faces, return_inverse=True)
    return vertices[used], new_index.reshape(faces.shape).astype(np.int64)


__all__ = [
    "DEFAULT_WELD_TOLERANCE_REL",
    "FOLD_ANGLE_DEG",
    "SLIVER_ANGLE_DEG",
    "HygieneReport",
    "MeshRefused",
    "RepairedMesh",
    "check_surface",
    "repair",
]
