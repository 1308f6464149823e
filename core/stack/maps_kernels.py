"""Compiled kernel of the stack's maps: which cell of a ply holds each point.

The rule is ``preform.stack.maps.ply_at``'s (its docstring): a point is held by a cell when
its coordinates in the cell's parallelogram (the mean edges a, b and the unit normal n about
the cell's centroid) lie within half a cell along a and b and its gap along n within the
limit. Tried first on the point's nearest cell by centroid, then on that cell's eight
neighbours in the net (on a sheared net a point near a cell's acute corner lies nearer a
neighbour's centroid than its own: the centroids' Voronoi cells are hexagons across the
rhombic cells' edges); what none holds but lies near is left for the exact closest-point
search. One loop over the points, no temporaries (the numpy form of the same arithmetic built
a dozen (k, 3) arrays a ply; benchmarks/README.md, section (o)).

Imported when a stack is read (numba is not loaded by ``import preform``); cached by content
(``preform.base.kernel_cache``).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from preform.base.kernel_cache import cache_by_content

#: The preform modules compiled into these kernels: none (``preform.base.kernel_cache``).
COMPILED_IN: tuple[str, ...] = ()
cache_by_content(__name__)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]


@numba.njit(cache=True, inline="always")
def _held(
    point: FloatArray,
    nodes_mm: FloatArray,
    centroid_mm: FloatArray,
    i: int,
    j: int,
    gap_limit_mm: float,
    d_mm: float,
) -> bool:
    """Whether cell (i, j)'s parallelogram holds ``point`` [mm] (module docstring)."""
    x00, x10 = nodes_mm[i, j], nodes_mm[i + 1, j]
    x01, x11 = nodes_mm[i, j + 1], nodes_mm[i + 1, j + 1]
    ax = 0.5 * ((x10[0] - x00[0]) + (x11[0] - x01[0]))
    ay = 0.5 * ((x10[1] - x00[1]) + (x11[1] - x01[1]))
    az = 0.5 * ((x10[2] - x00[2]) + (x11[2] - x01[2]))
    bx = 0.5 * ((x01[0] - x00[0]) + (x11[0] - x10[0]))
    by = 0.5 * ((x01[1] - x00[1]) + (x11[1] - x10[1]))
    bz = 0.5 * ((x01[2] - x00[2]) + (x11[2] - x10[2]))
    px = point[0] - centroid_mm[i, j, 0]
    py = point[1] - centroid_mm[i, j, 1]
    pz = point[2] - centroid_mm[i, j, 2]
    nx, ny, nz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    size = max(math.sqrt(nx * nx + ny * ny + nz * nz), 1e-300)
    nx, ny, nz = nx / size, ny / size, nz / size
    # the coordinates along a, b, n by Cramer's rule: triple products over det = a·(b×n)
    bnx, bny, bnz = by * nz - bz * ny, bz * nx - bx * nz, bx * ny - by * nx
    det = ax * bnx + ay * bny + az * bnz
    if not abs(det) > 1e-12 * d_mm * d_mm:
        return False
    s = (px * bnx + py * bny + pz * bnz) / det
    pnx, pny, pnz = py * nz - pz * ny, pz * nx - px * nz, px * ny - py * nx
    t = (ax * pnx + ay * pny + az * pnz) / det
    bpx, bpy, bpz = by * pz - bz * py, bz * px - bx * pz, bx * py - by * px
    g = (ax * bpx + ay * bpy + az * bpz) / det
    return abs(s) <= 0.5 and abs(t) <= 0.5 and abs(g) <= gap_limit_mm


@numba.njit(cache=True)
def holding_cells(
    points_mm: FloatArray,
    nearest_i: IntArray,
    nearest_j: IntArray,
    far: BoolArray,
    nodes_mm: FloatArray,
    centroid_mm: FloatArray,
    region: BoolArray,
    gap_limit_mm: FloatArray,
    d_mm: float,
) -> tuple[BoolArray, IntArray, IntArray, BoolArray]:
    """For each point [mm] (k, 3): (present, cell i, cell j, in doubt). ``nearest_i/j``: the
    region cell whose centroid is nearest the point; ``far``: no centroid lies within the
    search bound (neither present nor in doubt). In doubt: no cell of the nine holds the point
    but it lies within 2 d + its gap limit [mm] of its nearest centroid (module docstring)."""
    k = points_mm.shape[0]
    ni, nj = region.shape
    present = np.zeros(k, dtype=np.bool_)
    doubt = np.zeros(k, dtype=np.bool_)
    cell_i = nearest_i.copy()
    cell_j = nearest_j.copy()
    for q in range(k):
        if far[q]:
            continue
        point = points_mm[q]
        i0, j0 = nearest_i[q], nearest_j[q]
        if _held(point, nodes_mm, centroid_mm, i0, j0, gap_limit_mm[q], d_mm):
            present[q] = True
            continue
        for di in range(-1, 2):
            for dj in range(-1, 2):
                i, j = i0 + di, j0 + dj
                if present[q] or (di == 0 and dj == 0) or not (0 <= i < ni and 0 <= j < nj):
                    continue
                if region[i, j] and _held(
                    point, nodes_mm, centroid_mm, i, j, gap_limit_mm[q], d_mm
                ):
                    present[q] = True
                    cell_i[q], cell_j[q] = i, j
        if not present[q]:
            dx = point[0] - centroid_mm[i0, j0, 0]
            dy = point[1] - centroid_mm[i0, j0, 1]
            dz = point[2] - centroid_mm[i0, j0, 2]
            doubt[q] = math.sqrt(dx * dx + dy * dy + dz * dz) <= 2.0 * d_mm + gap_limit_mm[q]
    return present, cell_i, cell_j, doubt
