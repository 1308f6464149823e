"""The ply outline in the flat: which nodes of the pin-jointed net are fabric at all.

Flat coordinates (ξ, η) [m] describe the undeformed ply: origin at the start point, ξ along the
first fibre family (+u), η along the second (+v). The fibres are orthogonal in the flat, so node
(i, j) of the net sits at ((i − i0)·d, (j − j0)·d), with (i0, j0) the start node and d the node
spacing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from preform.base.arrays import BoolArray, FloatArray

#: Nodes within this fraction of d of the outline count as inside, so a ply of side 10·d has
#: 11 nodes along it despite rounding.
_EDGE_TOLERANCE = 1e-9
#: Node count along a fibre that stands for "more than can be counted" (10¹⁸).
MAX_COUNT = 10**18


@dataclass(frozen=True)
class PlyGrid:
    """The node grid a ply outline needs at a given spacing."""

    #: Number of nodes along u and v.
    shape: tuple[int, int]
    #: Index of the start node.
    start_index: tuple[int, int]
    #: Nodes inside the outline (ni, nj).
    inside: BoolArray


@dataclass(frozen=True)
class PlyOutline:
    """A ply outline as a simple polygon in flat coordinates (ξ, η) [m] (see module docstring).

    Build it with :meth:`rectangle` or :meth:`polygon`.
    """

    #: Polygon vertices (n, 2) [m], either winding, not closed (the last edge is implied).
    vertices: FloatArray

    @classmethod
    def rectangle(
        cls,
        size_m: tuple[float, float],
        *,
        offset_m: tuple[float, float] = (0.0, 0.0),
        angle_rad: float = 0.0,
    ) -> PlyOutline:
        """A rectangle of sides ``size_m`` = (along ξ, along η) [m] centred at ``offset_m`` [m]
        from the start point, turned by ``angle_rad`` [rad] counter-clockwise from the +u fibres
        (0: sides along the fibres; π/4: a ±45° ply cut square to its own edges)."""
        half_u, half_v = 0.5 * float(size_m[0]), 0.5 * float(size_m[1])
        if not (half_u > 0 and half_v > 0):
            raise ValueError(f"ply size must be positive, got {size_m!r} m")
        corners = np.array(
            [[-half_u, -half_v], [half_u, -half_v], [half_u, half_v], [-half_u, half_v]]
        )
        c, s = np.cos(angle_rad), np.sin(angle_rad)
        rotation = np.array([[c, -s], [s, c]])
        return cls(corners @ rotation.T + np.asarray(offset_m, dtype=float))

    @classmethod
    def polygon(cls, vertices_m: ArrayLike) -> PlyOutline:
        """A polygon with vertices (n ≥ 3, 2) in flat coordinates [m]."""
        vertices = np.asarray(vertices_m, dtype=float)
        if vertices.ndim != 2 or vertices.shape[1] != 2 or len(vertices) < 3:
            raise ValueError(f"ply polygon needs (n >= 3, 2) vertices, got {vertices.shape}")
        if not np.all(np.isfinite(vertices)):
            raise ValueError("ply polygon vertices must be finite")
        return cls(vertices)

    def contains(self, flat_xy: FloatArray, tolerance_m: float) -> BoolArray:
        """Points (n, 2) [m] inside the outline or within ``tolerance_m`` [m] of it."""
        px, py = flat_xy[:, 0], flat_xy[:, 1]
        crossings = np.zeros(len(flat_xy), dtype=bool)
        near_edge = np.zeros(len(flat_xy), dtype=bool)
        start = self.vertices
        end = np.roll(self.vertices, -1, axis=0)
        for (x1, y1), (x2, y2) in zip(start, end, strict=True):
            # Even-odd rule: count edges crossed by a ray towards +ξ.
            straddles = (y1 > py) != (y2 > py)
            with np.errstate(divide="ignore", invalid="ignore"):
                x_cross = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
            crossings ^= straddles & (px < x_cross)
            ex, ey = x2 - x1, y2 - y1
            length2 = ex * ex + ey * ey
            t = np.clip(((px - x1) * ex + (py - y1) * ey) / length2, 0.0, 1.0)
            near_edge |= np.hypot(px - x1 - t * ex, py - y1 - t * ey) <= tolerance_m
        return crossings | near_edge

    def _axis_aligned_box(self) -> tuple[float, float, float, float] | None:
        """(ξmin, ξmax, ηmin, ηmax) when the outline is a rectangle along the fibres."""
        if len(self.vertices) != 4:
            return None
        x_lo, y_lo = self.vertices.min(axis=0)
        x_hi, y_hi = self.vertices.max(axis=0)
        corners = np.array([[x_lo, y_lo], [x_lo, y_hi], [x_hi, y_lo], [x_hi, y_hi]])
        given = self.vertices[np.lexsort((self.vertices[:, 1], self.vertices[:, 0]))]
        span = max(x_hi - x_lo, y_hi - y_lo)
        if np.allclose(given, corners, rtol=0.0, atol=1e-12 * span):
            return float(x_lo), float(x_hi), float(y_lo), float(y_hi)
        return None

    def _index_range(self, spacing_m: float) -> tuple[int, int, int, int]:
        """(i_lo, i_hi, j_lo, j_hi): node indices (from the start node) the outline spans."""
        d = float(spacing_m)
        eps = _EDGE_TOLERANCE * d
        x_lo, y_lo = self.vertices.min(axis=0)
        x_hi, y_hi = self.vertices.max(axis=0)
        i_lo, i_hi = int(np.ceil((x_lo - eps) / d)), int(np.floor((x_hi + eps) / d))
        j_lo, j_hi = int(np.ceil((y_lo - eps) / d)), int(np.floor((y_hi + eps) / d))
        return i_lo, i_hi, j_lo, j_hi

    def grid_shape(self, spacing_m: float) -> tuple[int, int]:
        """Nodes (along u, along v) of :meth:`node_grid` at ``spacing_m`` [m], computed without
        building the grid: a resource limit can then refuse a ply of 10¹⁰ nodes up front.

        In floating point, so that a spacing of 1e-300 m (a count past any integer a float
        converts to) gives :data:`MAX_COUNT` instead of an overflow."""
        d = float(spacing_m)
        eps = _EDGE_TOLERANCE * d
        x_lo, y_lo = self.vertices.min(axis=0)
        x_hi, y_hi = self.vertices.max(axis=0)
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            counts = [
                float(np.floor((hi + eps) / d) - np.ceil((lo - eps) / d) + 1.0)
                for lo, hi in ((x_lo, x_hi), (y_lo, y_hi))
            ]
        ni, nj = (
            MAX_COUNT if not np.isfinite(c) or c >= MAX_COUNT else max(int(c), 0) for c in counts
        )
        return ni, nj

    def node_grid(self, spacing_m: float) -> PlyGrid:
        """The smallest node grid at spacing ``spacing_m`` [m] that covers the outline.

        Raises ValueError when the start point (the flat origin) lies outside the outline: the
        generators run through the start, so it must be fabric.
        """
        d = float(spacing_m)
        eps = _EDGE_TOLERANCE * d
        ni, nj = self.grid_shape(d)
        if MAX_COUNT in (ni, nj):
            raise ValueError(f"a node spacing of {d!r} m gives the ply more than 1e18 nodes")
        i_lo, i_hi, j_lo, j_hi = self._index_range(d)
        if not self.contains(np.zeros((1, 2)), eps)[0] or i_lo > 0 or j_lo > 0:
            raise ValueError("the start point lies outside the ply outline")
        xi = np.arange(i_lo, i_hi + 1) * d
        eta = np.arange(j_lo, j_hi + 1) * d
        box = self._axis_aligned_box()
        if box is not None:
            # Separable test: exact and cheap for the common rectangular ply.
            in_u = (xi >= box[0] - eps) & (xi <= box[1] + eps)
            in_v = (eta >= box[2] - eps) & (eta <= box[3] + eps)
            inside = in_u[:, None] & in_v[None, :]
        else:
            grid = np.stack(np.meshgrid(xi, eta, indexing="ij"), axis=-1).reshape(-1, 2)
            inside = self.contains(grid, eps).reshape(len(xi), len(eta))
        return PlyGrid(
            shape=(len(xi), len(eta)),
            start_index=(-i_lo, -j_lo),
            inside=np.asarray(inside, dtype=bool),
        )
