"""The part: the region of the tool that is made, separate from the tool the fabric lies on.

DESIGN "Tools, parts and what a result is": the net is draped over the tool as far as the ply
reaches and then clipped to the part; energies and extremes are of the part. A part here is a
level function φ on points of the tool [m], φ ≥ 0 inside, φ < 0 outside, whose zero set is the
part's edge:

- :class:`HeightCut`: z ≥ z0 (a hemisphere above its rim, a part trimmed at a flange height);
- :class:`PlanPolygon`: inside a closed polygon in plan (x, y) (a blank's trim line seen from
  above); φ is the signed plan distance to the polygon, so it is affine near each straight edge;
- :class:`Intersection`: inside every one of several parts (φ = min).

A closed curve drawn on a tool whose plan view is one-to-one (every analytic dome here) is a
plan polygon of its projected points. Named or numbered faces of a tool read from a file (CAD
faces, OBJ groups) are a part too: ``preform.plugins.surfaces.tool_mesh.FaceSet``.

Cells cut by the edge [D]
-------------------------
A pin-jointed cell is the image of a square d × d of undeformed fabric, its four corners the
images of the square's corners. The part's share of the cell is measured in that undeformed
square: φ is sampled at the four corners and taken as linear on each of the two triangles of
the square along one diagonal; the share of each triangle where the linear φ ≥ 0 is exact
(clipping a triangle by a half-plane), and the two ways of splitting the square are averaged so
a mirrored net has mirrored shares (as the cell areas in ``preform.drape.engine.fields``).

Exactness: a flat cell is a parallelogram (pin-jointed: a rhombus), so the map from the
undeformed square to it is affine; a straight edge makes φ affine on the tool's plane, so φ is
affine on the square and equal to its linear interpolation on either triangle: the share is
exact. On a curved tool or a curved edge φ differs from its interpolation by O(d²) over the
cell, the edge moves by O(d²) inside a cell of side d, so each cut cell's share is off by O(d)
of its area and the total over the O(1/d) cut cells by O(d²) of the part's area.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from preform.base.arrays import BoolArray, FloatArray


class Part:
    """A region of the tool (module docstring). Subclasses give :meth:`level`."""

    #: Area of the part on the tool [m²] when known in closed form (else None).
    area_m2: float | None = None

    def level(self, points: FloatArray) -> FloatArray:
        """φ at points (..., 3) [m]: ≥ 0 inside the part, < 0 outside; [m]."""
        raise NotImplementedError

    def contains(self, points: FloatArray) -> BoolArray:
        """Whether points (..., 3) [m] lie in the part (φ ≥ 0)."""
        with np.errstate(invalid="ignore"):
            return np.asarray(self.level(points) >= 0.0)

    def __call__(self, points: FloatArray) -> BoolArray:
        # A part is also a centroid predicate, the ``trim`` of the drape engine.
        return self.contains(points)

    def describe(self) -> str:
        """The part in words, in mm."""
        return type(self).__name__


@dataclass(frozen=True, eq=False)
class HeightCut(Part):
    """Everything of the tool at or above height ``z_min_m`` [m]."""

    z_min_m: float
    area_m2: float | None = None

    def level(self, points: FloatArray) -> FloatArray:
        return np.asarray(np.asarray(points, dtype=float)[..., 2] - self.z_min_m)

    def describe(self) -> str:
        return f"z ≥ {self.z_min_m * 1e3:g} mm"


@dataclass(frozen=True, eq=False)
class PlanPolygon(Part):
    """Everything of the tool whose plan position lies inside the closed polygon
    ``vertices_m`` (k, 2) [m] (either winding; the last vertex joins the first)."""

    vertices_m: FloatArray
    area_m2: float | None = None

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices_m, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3:
            raise ValueError("a plan polygon needs at least 3 (x, y) vertices [m]")
        if not np.all(np.isfinite(v)):
            raise ValueError("plan polygon vertices must be finite")
        from preform.drape.engine.polygon import outline_problem

        # the even-odd rule would give a bow tie an inside nobody meant (preform.drape.engine.polygon)
        problem = outline_problem(v * 1e3, "mm")
        if problem is not None:
            raise ValueError(f"plan polygon: {problem}")
        object.__setattr__(self, "vertices_m", v)

    def level(self, points: FloatArray) -> FloatArray:
        p = np.asarray(points, dtype=float)
        xy = p[..., :2].reshape(-1, 2)
        a = self.vertices_m
        b = np.roll(a, -1, axis=0)
        dist = np.full(len(xy), np.inf)
        inside = np.zeros(len(xy), dtype=bool)
        for (ax, ay), (bx, by) in zip(a, b, strict=True):
            ex, ey = bx - ax, by - ay
            px, py = xy[:, 0] - ax, xy[:, 1] - ay
            t = np.clip((px * ex + py * ey) / max(ex * ex + ey * ey, 1e-300), 0.0, 1.0)
            dist = np.minimum(dist, np.hypot(px - t * ex, py - t * ey))
            # Even-odd crossing rule along +x.
            crosses = (ay > xy[:, 1]) != (by > xy[:, 1])
            with np.errstate(divide="ignore", invalid="ignore"):
                x_at = ax + (xy[:, 1] - ay) * ex / ey
            inside ^= crosses & (xy[:, 0] < x_at)
        out = np.where(inside, dist, -dist)
        out[~np.all(np.isfinite(xy), axis=1)] = np.nan
        return out.reshape(p.shape[:-1])

    def describe(self) -> str:
        return f"plan polygon of {len(self.vertices_m)} vertices"


@dataclass(frozen=True, eq=False)
class Intersection(Part):
    """Inside every one of ``parts``."""

    parts: tuple[Part, ...]
    area_m2: float | None = None

    def level(self, points: FloatArray) -> FloatArray:
        levels = [np.asarray(p.level(points), dtype=float) for p in self.parts]
        return np.asarray(np.minimum.reduce(levels))

    def describe(self) -> str:
        return " and ".join(p.describe() for p in self.parts)


def combine(parts: Sequence[Part]) -> Part | None:
    """One part from several (their intersection); None for none."""
    if not parts:
        return None
    if len(parts) == 1:
        return parts[0]
    return Intersection(tuple(parts))


def cell_part_share(
    phi00: ArrayLike, phi10: ArrayLike, phi01: ArrayLike, phi11: ArrayLike
) -> FloatArray:
    """Share (0..1) of each cell's undeformed square inside the part, from φ at its corners
    (i, j), (i+1, j), (i, j+1), (i+1, j+1) (module docstring: exact for an affine φ). Split
    along (i, j)-(i+1, j+1), then along (i+1, j)-(i, j+1), and averaged; with the corners of a
    triangle sorted a ≤ b ≤ c the zero set cuts off a corner triangle, whose share is a product
    of two edge fractions (compiled: ``preform.drape.kernels.field_kernels``)."""
    from preform.drape.kernels import field_kernels

    corners = np.broadcast_arrays(
        *(np.asarray(f, dtype=float) for f in (phi00, phi10, phi01, phi11))
    )
    flat = [np.ascontiguousarray(f).reshape(-1) for f in corners]
    return np.asarray(field_kernels.corner_part_share(*flat)).reshape(corners[0].shape)


__all__ = [
    "HeightCut",
    "Intersection",
    "Part",
    "PlanPolygon",
    "cell_part_share",
    "combine",
]
