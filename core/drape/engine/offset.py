"""The tool offset by the plies below: the surface the next ply of a layup is draped on.

A ply of a stack lies on the plies under it, so it is draped on the tool moved outward, along
its normal, by their thickness (``preform.stack``). Two ways, by what the tool is:

- **Exact** (analytic tools that know their offset: ``offset(distance_m)``): the plate moves
  along +z, the sphere, hemisphere and cylinder grow their radius, R → R + h, so a stack of
  plies of thickness t lies on R + k·t exactly. These offsets take one distance; a thickness
  that varies over the tool is offset by one value the caller chooses (the layup uses each
  ply's area-weighted mean and says how far the ply's thickness strays from it).
- **Vertex normals** (triangle meshes, and CAD tools, which are meshed): every vertex moves
  along its area-weighted vertex normal by the stack's thickness there, so a ply's drop-off
  or a sheared, thickened region shows in the next ply's tool. Where the tool is concave with a
  radius smaller than the distance, the offset surface crosses itself: its triangles turn
  over (their normal turns against the tool's). That is found and reported with where it is
  and how far the offset was there (:class:`OffsetFolds`), never passed on silently.

Tools that neither know their offset nor are meshes (the cone, the domes, a plugin's analytic
tool) are refused with what to do: give the tool as a mesh. Lengths in metres.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from preform.base.arrays import FloatArray

MM = 1e-3
#: The two ways a tool is offset, in the words the summaries use.
EXACT = "exact (analytic)"
VERTEX_NORMALS = "vertex normals (mesh)"


class OffsetError(ValueError):
    """The tool cannot be offset (or its offset folds over itself), in words."""


@dataclass(frozen=True)
class OffsetFolds:
    """Triangles of a mesh offset that turned over: the offset crosses itself there."""

    #: Number of turned-over triangles and their area on the tool [m²].
    triangles: int
    area_m2: float
    #: Centroid [m] of the turned-over triangle where the offset is largest, and that offset [m].
    where_m: tuple[float, float, float]
    distance_m: float

    def reason(self) -> str:
        x, y, z = (c / MM for c in self.where_m)
        return (
            f"the tool offset by the plies below folds over itself: {self.triangles} "
            f"triangle(s) ({self.area_m2 / MM**2:.4g} mm²) turn over, e.g. at ({x:.5g}, "
            f"{y:.5g}, {z:.5g}) mm where the offset is {self.distance_m / MM:.4g} mm; the tool "
            "is concave there with a radius smaller than the stack's thickness, so no ply can "
            "lie on it as modelled (enlarge the tool's radius there or drop plies before it)"
        )


@dataclass(frozen=True)
class Offset:
    """An offset tool and how it was made."""

    surface: Any
    #: ``EXACT`` or ``VERTEX_NORMALS``.
    method: str
    #: Smallest and largest offset distance [m] (equal for an exact offset).
    distance_min_m: float
    distance_max_m: float


def is_mesh(surface: Any) -> bool:
    """True for a triangle-mesh tool that can be moved vertex by vertex."""
    return all(hasattr(surface, a) for a in ("vertices", "faces", "vertex_normals", "moved"))


def offset_tool(surface: Any, distance_m: float | FloatArray) -> Offset:
    """``surface`` offset outward by ``distance_m`` [m]: one distance, or for a mesh one per
    vertex (n,). Raises :class:`OffsetError` for a tool with no offset, a per-vertex distance
    on an analytic tool, or a mesh offset that folds over itself (module docstring)."""
    distance = np.asarray(distance_m, dtype=float)
    if not np.all(np.isfinite(distance)) or np.any(distance < 0.0):
        raise OffsetError("offset distances must be finite and non-negative")
    if is_mesh(surface):
        vertices = np.asarray(surface.vertices, dtype=float)
        per_vertex = np.broadcast_to(distance, (vertices.shape[0],)).astype(float)
        moved = offset_vertices(surface, per_vertex)
        folds = turned_over(surface, moved, per_vertex)
        if folds is not None:
            raise OffsetError(folds.reason())
        return Offset(
            surface.moved(moved),
            VERTEX_NORMALS,
            float(per_vertex.min()),
            float(per_vertex.max()),
        )
    offset = getattr(surface, "offset", None)
    if offset is None:
        raise OffsetError(
            f"the tool ({type(surface).__name__}) has no exact offset surface and is not a "
            "mesh, so the plies above the first cannot be placed on it; give the tool as a "
            "mesh (an STL or OBJ file of it) to offset it along its vertex normals"
        )
    if distance.ndim:
        raise OffsetError(
            "an analytic tool is offset by one distance; a thickness that varies over it is "
            "offset by one value (preform.stack) or the tool is given as a mesh"
        )
    h = float(distance)
    return Offset(surface if h == 0.0 else offset(h), EXACT, h, h)


def offset_vertices(mesh: Any, distance_m: FloatArray) -> FloatArray:
    """Mesh vertices (n, 3) [m] moved along their unit vertex normals by ``distance_m`` (n,)."""
    normals = np.asarray(mesh.vertex_normals, dtype=float)
    return np.asarray(mesh.vertices, dtype=float) + distance_m[:, None] * normals


def turned_over(mesh: Any, moved: FloatArray, distance_m: FloatArray) -> OffsetFolds | None:
    """The triangles of ``mesh`` whose offset (vertices ``moved`` (n, 3) [m]) faces against
    the tool's own (their normals' dot product ≤ 0), or None when none does. A vertex-normal
    offset by h turns a triangle over where the tool is concave with radius below h."""
    faces = np.asarray(mesh.faces)
    before = np.asarray(mesh.vertices, dtype=float)[faces]
    after = moved[faces]
    n0 = np.cross(before[:, 1] - before[:, 0], before[:, 2] - before[:, 0])
    n1 = np.cross(after[:, 1] - after[:, 0], after[:, 2] - after[:, 0])
    flipped = np.einsum("ij,ij->i", n0, n1) <= 0.0
    if not flipped.any():
        return None
    area = 0.5 * np.linalg.norm(n0[flipped], axis=1)
    reach = distance_m[faces[flipped]].max(axis=1)
    worst = int(np.argmax(reach))
    centre = before[flipped].mean(axis=1)[worst]
    return OffsetFolds(
        int(np.count_nonzero(flipped)),
        float(area.sum()),
        (float(centre[0]), float(centre[1]), float(centre[2])),
        float(reach[worst]),
    )
