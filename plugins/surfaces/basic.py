"""Analytic tool surfaces: a flat plate, a sphere (and the upper hemisphere), a cylinder.

Each implements the ``preform.drape.engine.surface.Surface`` protocol vectorised over (n, 3) points,
through its compiled queries (``compiled_queries``: ``preform.drape.kernels.surface_kernels``, imported
when first asked), so its drape runs the compiled fill in one loop.
``Plane`` and ``Sphere``/``Hemisphere`` also offer the drape engine's optional closed forms
(``place_nodes`` for a net node, ``geodesic_nodes`` for a generator), so draping them needs no
iteration. Lengths in metres.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from preform.base.arrays import BoolArray, FloatArray, StatusArray
from preform.drape.engine.compiled_surface import (
    CYLINDER,
    PLANE,
    SPHERE,
    TRIMMED_SPHERE,
    CompiledTool,
    checked_kind,
    kernel_parameters,
)
from preform.drape.engine.part import HeightCut
from preform.drape.engine.result import NodeStatus

#: Points this fraction of the node spacing outside a trimmed surface still count as on it, so
#: rounding never turns a node lying exactly on an edge (a hemisphere's rim) into OFF_TOOL.
_EDGE_TOLERANCE = 1e-9


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...i,...i->...", a, b)


def _unit(a: FloatArray) -> FloatArray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / np.sqrt(_dot(a, a))[..., None]


def _compiled_place_nodes(
    tool: Plane | Sphere, a: FloatArray, b: FloatArray, opposite: FloatArray, spacing: float
) -> tuple[FloatArray, StatusArray]:
    """The tool's closed-form nodes through the compiled kernel (one implementation for the
    compiled fill and the vectorised callers)."""
    from preform.drape.kernels import net_kernels

    kind, params = tool.compiled_queries()
    ends = [np.ascontiguousarray(v, dtype=float).reshape(-1, 3) for v in (a, b, opposite)]
    points, status = net_kernels.closed_form_nodes(
        checked_kind(kind),
        kernel_parameters(kind, params),
        ends[0],
        ends[1],
        ends[2],
        float(spacing),
    )
    return np.asarray(points), np.asarray(status, dtype=np.int8)


class Plane(CompiledTool):
    """A flat rectangular plate, horizontal, of plan size ``size_m`` = (Lx, Ly) [m] centred at
    ``centre_m`` [m]; its outward normal is +z."""

    def __init__(
        self, size_m: tuple[float, float], *, centre_m: ArrayLike = (0.0, 0.0, 0.0)
    ) -> None:
        self.half = 0.5 * np.asarray(size_m, dtype=float)
        if self.half.shape != (2,) or not np.all(self.half > 0):
            raise ValueError(f"plane size must be two positive lengths, got {size_m!r} m")
        self.centre = np.asarray(centre_m, dtype=float)
        lo, hi = self.centre[:2] - self.half, self.centre[:2] + self.half
        z = float(self.centre[2])
        self.bounds = ((float(lo[0]), float(lo[1]), z), (float(hi[0]), float(hi[1]), z))
        self.size = float(2.0 * np.hypot(*self.half))

    def __repr__(self) -> str:
        return f"Plane(size_m={tuple(2 * self.half)}, centre_m={tuple(self.centre)})"

    def offset(self, distance_m: float) -> Plane:
        """The plate moved ``distance_m`` [m] along its normal (+z): its exact offset surface
        (the layup's next ply lies on it, ``preform.drape.engine.offset``). Its plan size is kept."""
        size = (float(2.0 * self.half[0]), float(2.0 * self.half[1]))
        return Plane(size, centre_m=self.centre + np.array([0.0, 0.0, float(distance_m)]))

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The plate for the compiled kernels: (PLANE, (centre x, y, z, half size x, y)) [m]."""
        return PLANE, np.array([*self.centre, *self.half], dtype=float)

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Plate points over plan positions (n, 2) [m], and which positions are over the plate."""
        xy = np.asarray(xy, dtype=float)
        mask = np.all(np.abs(xy - self.centre[:2]) <= self.half, axis=1)
        pts = np.column_stack([xy, np.full(len(xy), self.centre[2])])
        pts[~mask] = np.nan
        return pts, mask

    def _on_plate(self, p: FloatArray, spacing: float) -> BoolArray:
        slack = _EDGE_TOLERANCE * spacing
        return np.all(np.abs(p[..., :2] - self.centre[:2]) <= self.half + slack, axis=-1)

    def place_nodes(
        self, a: FloatArray, b: FloatArray, opposite: FloatArray, spacing: float
    ) -> tuple[FloatArray, StatusArray]:
        """Net nodes (m, 3) [m] at distance ``spacing`` [m] from ``a`` and ``b`` (m, 3) on the
        side away from ``opposite``, with NodeStatus codes (m,): in the plate, on the
        perpendicular bisector of ab (compiled: ``preform.drape.kernels.surface_kernels.plane_node``).
        """
        return _compiled_place_nodes(self, a, b, opposite, spacing)

    def geodesic_nodes(
        self, start: FloatArray, direction: FloatArray, spacing: float, count: int
    ) -> tuple[FloatArray, StatusArray]:
        """``count`` nodes (m, count, 3) [m] along the straight lines from ``start`` (m, 3) in
        ``direction`` (m, 3), spacing [m] apart, with NodeStatus codes (m, count)."""
        t = direction.copy()
        t[:, 2] = 0.0
        t = _unit(t)
        k = np.arange(1, count + 1, dtype=float)
        p = start[:, None, :] + spacing * k[None, :, None] * t[:, None, :]
        on = self._on_plate(p, spacing)
        status = np.where(on, NodeStatus.PLACED, NodeStatus.OFF_TOOL).astype(np.int8)
        return p, status


class Sphere(CompiledTool):
    """A full sphere of radius ``radius_m`` [m] centred at ``centre_m`` [m]; the centre's
    closest point is the top (+z), any point being closest."""

    def __init__(self, radius_m: float, *, centre_m: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        self.radius = float(radius_m)
        if not self.radius > 0:
            raise ValueError(f"sphere radius must be positive, got {radius_m!r} m")
        self.centre = np.asarray(centre_m, dtype=float)
        self.bounds = self._bounds()
        self.size = self.radius

    def _bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        lo, hi = self.centre - self.radius, self.centre + self.radius
        return (float(lo[0]), float(lo[1]), float(lo[2])), (
            float(hi[0]),
            float(hi[1]),
            float(hi[2]),
        )

    def __repr__(self) -> str:
        return f"{type(self).__name__}(radius_m={self.radius}, centre_m={tuple(self.centre)})"

    def _radial(self, points: FloatArray) -> FloatArray:
        """Unit directions from the centre; +z for the centre itself (any choice is closest)."""
        rel = np.asarray(points, dtype=float) - self.centre
        length = np.sqrt(_dot(rel, rel))
        at_centre = length == 0
        if at_centre.any():
            rel[at_centre] = (0.0, 0.0, 1.0)
            length[at_centre] = 1.0
        rel /= length[:, None]
        return rel

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """The top of the sphere over plan positions (n, 2) [m], and which lie over it."""
        rel = np.asarray(xy, dtype=float) - self.centre[:2]
        height2 = self.radius**2 - _dot(rel, rel)
        mask = height2 >= 0
        pts = np.column_stack([xy, self.centre[2] + np.sqrt(np.where(mask, height2, np.nan))])
        pts[~mask] = np.nan
        return pts, mask

    def _on_tool(self, p: FloatArray, spacing: float) -> BoolArray:
        """Where points of the (untrimmed) sphere belong to the tool: everywhere."""
        return np.isfinite(p[..., 0])

    def place_nodes(
        self, a: FloatArray, b: FloatArray, opposite: FloatArray, spacing: float
    ) -> tuple[FloatArray, StatusArray]:
        """Net nodes (m, 3) [m] at chord ``spacing`` [m] from ``a`` and ``b`` (m, 3) on the side
        away from ``opposite``, with NodeStatus codes (m,).

        Closed form (PHYSICS §6), compiled (``preform.drape.kernels.net_kernels._sphere_node``): relative
        to the centre, P·A = P·B = R² − d²/2 and |P| = R. P lies in the plane spanned by A + B
        and n = A × B; the root on the far side of the plane (0, A, B) from the opposite node is
        the new node. A node below a trimmed sphere's floor is OFF_TOOL.
        """
        return _compiled_place_nodes(self, a, b, opposite, spacing)

    def offset(self, distance_m: float) -> Sphere:
        """The concentric sphere of radius R + ``distance_m`` [m]: the exact offset surface
        (outward normals, ``preform.drape.engine.offset``)."""
        return Sphere(self.radius + float(distance_m), centre_m=self.centre)

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The sphere for the compiled net kernels: (SPHERE, (centre x, y, z, radius)) [m]."""
        return SPHERE, np.array([*self.centre, self.radius], dtype=float)

    def geodesic_nodes(
        self, start: FloatArray, direction: FloatArray, spacing: float, count: int
    ) -> tuple[FloatArray, StatusArray]:
        """``count`` nodes (m, count, 3) [m] along the great circles from ``start`` (m, 3) in
        tangent ``direction`` (m, 3), successive chords ``spacing`` [m], with NodeStatus codes
        (m, count). A chord longer than the diameter leaves the tool at once: OFF_TOOL."""
        r = self.radius
        radial = self._radial(start)
        t = _unit(direction - _dot(direction, radial)[:, None] * radial)
        m = len(start)
        if spacing > 2.0 * r:
            return np.full((m, count, 3), np.nan), np.full(
                (m, count), NodeStatus.OFF_TOOL, dtype=np.int8
            )
        step = 2.0 * np.arcsin(spacing / (2.0 * r))
        theta = step * np.arange(1, count + 1)
        p = self.centre + r * (
            np.cos(theta)[None, :, None] * radial[:, None, :]
            + np.sin(theta)[None, :, None] * t[:, None, :]
        )
        on = self._on_tool(p, spacing)
        status = np.where(on, NodeStatus.PLACED, NodeStatus.OFF_TOOL).astype(np.int8)
        p[~on] = np.nan
        return p, status


class Hemisphere(Sphere):
    """The upper half (z ≥ centre z) of a sphere of radius ``radius_m`` [m] centred at
    ``centre_m`` [m]: the classic drape test tool.

    ``run_off_m`` [m]: how far below the rim the tool continues for draping, as the same
    sphere (its analytic continuation). The fabric does not stop at a part's edge: it runs on
    over it and is trimmed, so a drape of the hemisphere drapes the sphere down to
    z = centre z − run_off and is clipped to the part z ≥ centre z (:meth:`part`). None (the
    default of the class) ends the tool at the rim: nodes below it are OFF_TOOL."""

    def __init__(
        self,
        radius_m: float,
        *,
        centre_m: ArrayLike = (0.0, 0.0, 0.0),
        run_off_m: float | None = None,
    ) -> None:
        super().__init__(radius_m, centre_m=centre_m)
        if run_off_m is not None and not 0.0 < float(run_off_m) <= self.radius:
            raise ValueError(
                f"the run-off below the rim must lie in (0, radius] m, got {run_off_m!r} m"
            )
        self.run_off = 0.0 if run_off_m is None else float(run_off_m)
        (x0, y0, _), (x1, y1, z1) = self.bounds
        self.bounds = ((x0, y0, float(self.centre[2]) - self.run_off), (x1, y1, z1))

    def __repr__(self) -> str:
        extra = f", run_off_m={self.run_off}" if self.run_off else ""
        return f"Hemisphere(radius_m={self.radius}, centre_m={tuple(self.centre)}{extra})"

    def offset(self, distance_m: float) -> Hemisphere:
        """The concentric hemisphere of radius R + ``distance_m`` [m], its exact offset
        (``preform.drape.engine.offset``); the run-off below the rim keeps its angular extent, so the
        offset tool continues as far round the sphere as this one."""
        radius = self.radius + float(distance_m)
        run_off = self.run_off * radius / self.radius if self.run_off else None
        return Hemisphere(radius, centre_m=self.centre, run_off_m=run_off)

    def part(self) -> HeightCut:
        """The part this tool makes: the hemisphere above its rim, z ≥ centre z (area 2πR²)."""
        return HeightCut(float(self.centre[2]), area_m2=2.0 * np.pi * self.radius**2)

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The tool for the compiled net kernels: (TRIMMED_SPHERE, (centre x, y, z, radius,
        floor z)) [m]. Points below the floor have their closest tool point on the edge circle
        there."""
        floor = float(self.centre[2]) - self.run_off
        return TRIMMED_SPHERE, np.array([*self.centre, self.radius, floor], dtype=float)

    def _on_tool(self, p: FloatArray, spacing: float) -> BoolArray:
        floor = self.centre[2] - self.run_off
        with np.errstate(invalid="ignore"):
            return np.asarray(p[..., 2] >= floor - _EDGE_TOLERANCE * spacing)


class Cylinder(CompiledTool):
    """The lateral surface of a circular cylinder with a horizontal ``axis`` ("x" or "y"),
    radius ``radius_m`` [m] and length ``length_m`` [m], centred at ``centre_m`` [m]; its
    normals are radial, and a point on the axis has the top (+z) as its closest point."""

    def __init__(
        self,
        radius_m: float,
        length_m: float,
        axis: Literal["x", "y"] = "x",
        *,
        centre_m: ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        if axis not in ("x", "y"):
            # A vertical cylinder has no top seen from above, so point_at_plan is undefined.
            raise ValueError(f"cylinder axis must be 'x' or 'y' (horizontal), got {axis!r}")
        self.radius, self.length = float(radius_m), float(length_m)
        if not (self.radius > 0 and self.length > 0):
            raise ValueError("cylinder radius and length must be positive")
        self.axis = axis
        self._ax, self._across = (0, 1) if axis == "x" else (1, 0)
        self.centre = np.asarray(centre_m, dtype=float)
        lo = self.centre - self.radius
        hi = self.centre + self.radius
        lo[self._ax] = self.centre[self._ax] - 0.5 * self.length
        hi[self._ax] = self.centre[self._ax] + 0.5 * self.length
        self.bounds = (
            (float(lo[0]), float(lo[1]), float(lo[2])),
            (float(hi[0]), float(hi[1]), float(hi[2])),
        )
        self.size = float(np.hypot(2.0 * self.radius, self.length))

    def __repr__(self) -> str:
        return (
            f"Cylinder(radius_m={self.radius}, length_m={self.length}, axis={self.axis!r}, "
            f"centre_m={tuple(self.centre)})"
        )

    def offset(self, distance_m: float) -> Cylinder:
        """The coaxial cylinder of radius R + ``distance_m`` [m] and the same length: the exact
        offset of the lateral surface (``preform.drape.engine.offset``)."""
        return Cylinder(
            self.radius + float(distance_m), self.length, self.axis, centre_m=self.centre
        )

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The cylinder for the compiled kernels: (CYLINDER, (centre x, y, z, radius, half
        length [m], axis: 0 along x, 1 along y)). Points past an end have their closest point
        on its end circle."""
        half = 0.5 * self.length
        return CYLINDER, np.array([*self.centre, self.radius, half, self._ax], dtype=float)

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """The top of the cylinder over plan positions (n, 2) [m], and which lie over it."""
        xy = np.asarray(xy, dtype=float)
        across = xy[:, self._across] - self.centre[self._across]
        along = xy[:, self._ax] - self.centre[self._ax]
        height2 = self.radius**2 - across**2
        mask = (height2 >= 0) & (np.abs(along) <= 0.5 * self.length)
        pts = np.column_stack([xy, self.centre[2] + np.sqrt(np.where(mask, height2, 0.0))])
        pts[~mask] = np.nan
        return pts, mask
