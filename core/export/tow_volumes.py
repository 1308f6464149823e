"""Tows as solids: each tow's elliptical cross-section swept along its centreline, as wedges.

For the unit-cell VTU (``preform.export.vtu.write_unit_cell_vtu``), so ParaView shows the tows'
volumes (widths, heights, the gaps between tows, a sheared cell's compacted tows), not only their
centre-lines. At every centreline point the section is a polygon of ``sides`` corners on the
ellipse of the tow's width (in the fabric plane, across the tow) and height, in the plane normal
to the path; consecutive sections are joined by one wedge per polygon side (centre, corner k,
corner k + 1). The polygon is scaled so that its area equals the ellipse's, (π/4)·w·h: the
wedges of a straight tow then hold exactly the tow's volume. Lengths in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from preform.base.arrays import FloatArray, IntArray
from preform.geometry.unit_cell import TowPath, UnitCell

#: Corners of the section polygon: 12 keeps an ellipse round on screen at modest file size.
SIDES = 12


@dataclass(frozen=True)
class TowSolids:
    """Wedges of every tow of a cell: ``points`` (n, 3) [m], ``wedges`` (m, 6) point indices
    (VTK wedge order: a triangle, then the matching triangle of the next section) and
    ``tow`` (m,) the index of each wedge's tow in ``cell.tows``."""

    points: FloatArray
    wedges: IntArray
    tow: IntArray


def section_frames(points: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unit vectors (n, 3) across the path (in the fabric plane) and up (normal to the path
    and to ``across``) at each centreline point. Across a vertical stretch (a stitch through
    the thickness) the last in-plane direction is carried on, as the ribbons of the figure do."""
    tangent = np.gradient(points, axis=0)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-300)
    across = np.column_stack([-tangent[:, 1], tangent[:, 0], np.zeros(len(points))])
    norm = np.linalg.norm(across, axis=1)
    flat = norm > 1e-9
    if not np.any(flat):
        across[:] = (1.0, 0.0, 0.0)
    else:
        idx = np.where(flat, np.arange(len(points)), 0)
        np.maximum.accumulate(idx, out=idx)
        idx[: int(np.argmax(flat))] = int(np.argmax(flat))
        across = across[idx] / norm[idx, None]
    up = np.cross(across, tangent)
    up /= np.maximum(np.linalg.norm(up, axis=1, keepdims=True), 1e-300)
    return across, up


def tow_solid(tow: TowPath, sides: int = SIDES) -> tuple[FloatArray, IntArray]:
    """Points (n·(sides + 1), 3) [m] and wedges (m, 6) of one tow (indices from 0)."""
    pts = np.asarray(tow.points, dtype=float).reshape(-1, 3)
    if len(pts) < 2:
        return np.empty((0, 3)), np.empty((0, 6), dtype=np.int64)
    across, up = section_frames(pts)
    # polygon area (sides/2)·sin(2π/sides)·a·b equals the ellipse's π·a·b after this scaling
    scale = math.sqrt(math.pi / (0.5 * sides * math.sin(2.0 * math.pi / sides)))
    theta = 2.0 * math.pi * np.arange(sides) / sides
    a, b = 0.5 * tow.width * scale, 0.5 * tow.height * scale
    ring = (
        pts[:, None, :]
        + a * np.cos(theta)[None, :, None] * across[:, None, :]
        + b * np.sin(theta)[None, :, None] * up[:, None, :]
    )
    section = np.concatenate([pts[:, None, :], ring], axis=1)  # centre first
    per = sides + 1
    k = np.arange(sides)
    wedges = []
    for i in range(len(pts) - 1):
        lo, hi = i * per, (i + 1) * per
        tri_lo = np.column_stack([np.full(sides, lo), lo + 1 + k, lo + 1 + (k + 1) % sides])
        wedges.append(np.hstack([tri_lo, tri_lo - lo + hi]))
    return section.reshape(-1, 3), np.vstack(wedges).astype(np.int64)


def tow_solids(cell: UnitCell, sides: int = SIDES) -> TowSolids:
    """Every tow of ``cell`` as wedges (see ``TowSolids``)."""
    points: list[FloatArray] = []
    wedges: list[IntArray] = []
    owner: list[IntArray] = []
    offset = 0
    for index, tow in enumerate(cell.tows):
        p, w = tow_solid(tow, sides)
        if len(w):
            points.append(p)
            wedges.append(w + offset)
            owner.append(np.full(len(w), index, dtype=np.int64))
            offset += len(p)
    if not wedges:
        return TowSolids(np.empty((0, 3)), np.empty((0, 6), np.int64), np.empty(0, np.int64))
    return TowSolids(np.vstack(points), np.vstack(wedges), np.concatenate(owner))
