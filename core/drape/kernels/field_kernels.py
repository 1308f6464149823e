"""Compiled kernels of a draped net's fields: per-cell geometry, cut-cell shares, node shear.

One pass over the net each, with no whole-net temporaries (a million-cell net's numpy
temporaries cost more in page faults than in arithmetic). The definitions are those of
``preform.drape.engine.fields`` (cell shear, centroid, area, fibre directions; node shear) and
``preform.drape.engine.part`` (a cell's undeformed share inside the part); this module is their only
implementation, imported when a net's fields are computed, so numba stays out of start-up.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from preform.base.kernel_cache import cache_by_content
from preform.drape.engine.result import CellStatus, NodeStatus

#: The preform modules compiled into these kernels (inlined functions, frozen constants):
#: their sources are part of the key these kernels are cached under
#: (``preform.base.kernel_cache``).
COMPILED_IN = ("preform.drape.engine.result",)
cache_by_content(__name__)

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
Vec = tuple[float, float, float]

_PLACED = np.int8(NodeStatus.PLACED)
_NODE_FOLDED = np.int8(NodeStatus.FOLDED)
_NODE_OUTSIDE = np.int8(NodeStatus.OUTSIDE_PLY)
_VALID = np.int8(CellStatus.VALID)
_INCOMPLETE = np.int8(CellStatus.INCOMPLETE)
_CELL_FOLDED = np.int8(CellStatus.FOLDED)
_CELL_OUTSIDE = np.int8(CellStatus.OUTSIDE_PLY)
_HALF_PI = 0.5 * math.pi

_jit = numba.njit(cache=True, error_model="numpy")
# Steps that take an array are inlined into their loop (numba's own inlining): an array handed
# to a function that is not inlined is reference counted, an atomic add and subtract, per call.
_per_cell = numba.njit(cache=True, error_model="numpy", inline="always")


@_per_cell
def _corner(nodes: FloatArray, i: int, j: int) -> tuple[float, float, float]:
    """Node (i, j) of an (ni, nj, 3) array as a tuple."""
    return nodes[i, j, 0], nodes[i, j, 1], nodes[i, j, 2]


@_jit
def _angle(ax: float, ay: float, az: float, bx: float, by: float, bz: float) -> float:
    """Angle [rad, 0..π] between two vectors; atan2 keeps it accurate near 0 and π too."""
    cx = ay * bz - az * by
    cy = az * bx - ax * bz
    cz = ax * by - ay * bx
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)


@_jit
def _cross_norm(ax: float, ay: float, az: float, bx: float, by: float, bz: float) -> float:
    cx = ay * bz - az * by
    cy = az * bx - ax * bz
    cz = ax * by - ay * bx
    return math.sqrt(cx * cx + cy * cy + cz * cz)


@_jit
def _pair_number(a: Vec, b: Vec, c: Vec, d: Vec):
    """(re, im) of the product of |a×b| − i(a·b) and |c×d| − i(c·d): its argument is
    (ω_ab − 90°) + (ω_cd − 90°) for the angles ω between a and b and between c and d.

    ω − 90° is the argument of |a×b| − i(a·b), a number in [−90°, 90°] read accurately near
    0 as near ±90° (as atan2 reads ω itself); two such arguments add up to the argument of the
    product of the two numbers, which lies in [−180°, 180°]."""
    re1 = _cross_norm(a[0], a[1], a[2], b[0], b[1], b[2])
    im1 = -(a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
    re2 = _cross_norm(c[0], c[1], c[2], d[0], d[1], d[2])
    im2 = -(c[0] * d[0] + c[1] * d[1] + c[2] * d[2])
    return re1 * re2 - im1 * im2, re1 * im2 + im1 * re2


@_jit
def _four_corner_deviation(u0: Vec, v0: Vec, u1: Vec, v1: Vec) -> float:
    """Σ (ω − 90°) [rad] over the four corners (u0, v0), (u1, v1), (u0, v1), (u1, v0).

    The corners are paired across the diagonals (``_pair_number``); when both pairs' sums lie
    within ±90° (positive real parts: a shear below 45° on either diagonal, every cell of a
    drape that has not locked) the whole sum lies within ±180° and is the argument of the
    product of the two pair numbers, one atan2 for four corners, the cell kernels' largest
    cost; else one atan2 per pair. The pairs multiply in either order to the same bits, so a
    mirrored net still gets the mirrored sum."""
    ra, ia = _pair_number(u0, v0, u1, v1)
    rb, ib = _pair_number(u0, v1, u1, v0)
    if ra > 0.0 and rb > 0.0:
        re = ra * rb - ia * ib
        im = ra * ib + ia * rb
        # the product of four corner numbers, each |a||b|: keep clear of underflow
        if abs(re) + abs(im) > 1e-280:
            return math.atan2(im, re)
    return math.atan2(ia, ra) + math.atan2(ib, rb)


@_jit
def cell_geometry(
    nodes: FloatArray,
    valid: BoolArray,
    shear: FloatArray,
    centroid: FloatArray,
    area: FloatArray,
    fibre_u: FloatArray,
    fibre_v: FloatArray,
) -> None:
    """Fill the cell arrays (ni−1, nj−1[, 3]) from node positions (ni, nj, 3) [m] on the
    ``valid`` cells (``preform.drape.engine.fields.cell_fields`` for the definitions); other cells get
    0 (NaN for the centroid)."""
    ci, cj = valid.shape
    for i in range(ci):
        for j in range(cj):
            if not valid[i, j]:
                shear[i, j] = 0.0
                area[i, j] = 0.0
                for k in range(3):
                    centroid[i, j, k] = np.nan
                    fibre_u[i, j, k] = 0.0
                    fibre_v[i, j, k] = 0.0
                continue
            # corners as tuples, not array views (a view is reference counted per cell)
            x00, x10 = _corner(nodes, i, j), _corner(nodes, i + 1, j)
            x01, x11 = _corner(nodes, i, j + 1), _corner(nodes, i + 1, j + 1)
            ulx, uly, ulz = x10[0] - x00[0], x10[1] - x00[1], x10[2] - x00[2]
            uhx, uhy, uhz = x11[0] - x01[0], x11[1] - x01[1], x11[2] - x01[2]
            vlx, vly, vlz = x01[0] - x00[0], x01[1] - x00[1], x01[2] - x00[2]
            vrx, vry, vrz = x11[0] - x10[0], x11[1] - x10[1], x11[2] - x10[2]
            # γ = mean of the four corner angles ω − 90°
            shear[i, j] = 0.25 * _four_corner_deviation(
                (ulx, uly, ulz), (vlx, vly, vlz), (uhx, uhy, uhz), (vrx, vry, vrz)
            )
            for k in range(3):
                centroid[i, j, k] = 0.25 * (x00[k] + x10[k] + x01[k] + x11[k])
            dx, dy, dz = x11[0] - x00[0], x11[1] - x00[1], x11[2] - x00[2]
            ax, ay, az = x01[0] - x10[0], x01[1] - x10[1], x01[2] - x10[2]
            # Split along (i, j)-(i+1, j+1), then along (i+1, j)-(i, j+1); average.
            split_a = _cross_norm(ulx, uly, ulz, dx, dy, dz) + _cross_norm(
                dx, dy, dz, vlx, vly, vlz
            )
            split_b = _cross_norm(ulx, uly, ulz, ax, ay, az) + _cross_norm(
                ax, ay, az, vrx, vry, vrz
            )
            area[i, j] = 0.25 * (split_a + split_b)
            sx, sy, sz = ulx + uhx, uly + uhy, ulz + uhz
            # one division and three products a fibre (divisions and roots share one unit of
            # the core and bound this kernel; the unit vector changes by an ulp at most)
            inverse = 1.0 / math.sqrt(sx * sx + sy * sy + sz * sz)
            fibre_u[i, j, 0], fibre_u[i, j, 1], fibre_u[i, j, 2] = (
                sx * inverse,
                sy * inverse,
                sz * inverse,
            )
            sx, sy, sz = vlx + vrx, vly + vry, vlz + vrz
            inverse = 1.0 / math.sqrt(sx * sx + sy * sy + sz * sz)
            fibre_v[i, j, 0], fibre_v[i, j, 1], fibre_v[i, j, 2] = (
                sx * inverse,
                sy * inverse,
                sz * inverse,
            )


@_jit
def _before(x: float, y: float) -> bool:
    """Sort order with NaN last (as numpy sorts)."""
    return x < y or (math.isnan(y) and not math.isnan(x))


@_jit
def _triangle_share(f0: float, f1: float, f2: float) -> float:
    """Share (0..1) of a triangle where the linear function with corner values f0, f1, f2 is
    ≥ 0. With the corners sorted a ≤ b ≤ c the zero set cuts off a corner triangle, whose
    share is a product of the two edge fractions."""
    a, b, c = f0, f1, f2
    if _before(b, a):
        a, b = b, a
    if _before(c, b):
        b, c = c, b
    if _before(b, a):
        a, b = b, a
    if a >= 0.0:
        return 1.0
    if b < 0.0 and c >= 0.0:
        # One corner inside (a ≤ b < 0 ≤ c): the inside is the triangle at c.
        share = (c / (c - a)) * (c / (c - b))
        if math.isnan(share):
            share = 0.0
    elif a < 0.0 and b >= 0.0:
        # Two corners inside (a < 0 ≤ b): the outside is the triangle at a.
        share = 1.0 - (a / (a - b)) * (a / (a - c))
        if math.isnan(share):
            share = 1.0
    else:
        return 0.0
    return min(max(share, 0.0), 1.0)


@_jit
def _square_share(f00: float, f10: float, f01: float, f11: float) -> float:
    """Share (0..1) of a cell's undeformed square inside the part from φ at its corners (i, j),
    (i+1, j), (i, j+1), (i+1, j+1): the mean of the two ways of splitting it into triangles,
    each exact for an affine φ (``preform.drape.engine.part``)."""
    split_a = 0.5 * (_triangle_share(f00, f10, f11) + _triangle_share(f00, f11, f01))
    split_b = 0.5 * (_triangle_share(f00, f10, f01) + _triangle_share(f10, f11, f01))
    return 0.5 * (split_a + split_b)


@_jit
def grid_part_share(phi: FloatArray, valid: BoolArray, out: FloatArray) -> None:
    """:func:`_square_share` of every ``valid`` cell into ``out`` (ni−1, nj−1), φ at the nodes
    (ni, nj); 0 for other cells and where φ is NaN (outputs are allocated by the caller, where
    numpy's memory accounting sees them)."""
    ci, cj = phi.shape[0] - 1, phi.shape[1] - 1
    for i in range(ci):
        for j in range(cj):
            if not valid[i, j]:
                out[i, j] = 0.0
                continue
            share = _square_share(phi[i, j], phi[i + 1, j], phi[i, j + 1], phi[i + 1, j + 1])
            out[i, j] = 0.0 if math.isnan(share) else share


@_jit
def cell_status_codes(status: NDArray[np.int8], out: NDArray[np.int8]) -> None:
    """CellStatus (ni−1, nj−1) into ``out`` from the NodeStatus of the corners (ni, nj), with
    the precedence of ``preform.drape.engine.fields.cell_status``: OUTSIDE_PLY, FOLDED, INCOMPLETE,
    VALID."""
    for i in range(status.shape[0] - 1):
        for j in range(status.shape[1] - 1):
            missing = folded = outside = False
            for corner in (status[i, j], status[i + 1, j], status[i, j + 1], status[i + 1, j + 1]):
                missing |= corner != _PLACED
                folded |= corner == _NODE_FOLDED
                outside |= corner == _NODE_OUTSIDE
            if outside:
                out[i, j] = _CELL_OUTSIDE
            elif folded:
                out[i, j] = _CELL_FOLDED
            elif missing:
                out[i, j] = _INCOMPLETE
            else:
                out[i, j] = _VALID


@_jit
def corner_part_share(
    f00: FloatArray, f10: FloatArray, f01: FloatArray, f11: FloatArray
) -> FloatArray:
    """:func:`_square_share` elementwise over flat corner arrays."""
    out = np.empty(f00.shape[0])
    for i in range(f00.shape[0]):
        out[i] = _square_share(f00[i], f10[i], f01[i], f11[i])
    return out


@_jit
def node_shear(nodes: FloatArray, status: NDArray[np.int8], out: FloatArray) -> None:
    """Signed shear γ [rad] at every node (ni, nj), NaN where it cannot be formed: the mean of
    the up to four corner angles ω between the ±u and ±v edges (each taken in its + sense)
    minus 90° (``preform.drape.engine.fields.node_shear``), written to ``out`` (ni, nj)."""
    ni, nj = status.shape
    u = np.empty((2, 3))
    v = np.empty((2, 3))
    for i in range(ni):
        for j in range(nj):
            if status[i, j] != _PLACED:
                out[i, j] = np.nan
                continue
            have_u = (i + 1 < ni, i > 0)
            have_v = (j + 1 < nj, j > 0)
            if have_u[0]:
                for k in range(3):
                    u[0, k] = nodes[i + 1, j, k] - nodes[i, j, k]
            if have_u[1]:
                for k in range(3):
                    u[1, k] = nodes[i, j, k] - nodes[i - 1, j, k]
            if have_v[0]:
                for k in range(3):
                    v[0, k] = nodes[i, j + 1, k] - nodes[i, j, k]
            if have_v[1]:
                for k in range(3):
                    v[1, k] = nodes[i, j, k] - nodes[i, j - 1, k]
            if have_u[0] and have_u[1] and have_v[0] and have_v[1]:
                interior = True
                for k in range(3):
                    interior = interior and math.isfinite(u[0, k]) and math.isfinite(u[1, k])
                    interior = interior and math.isfinite(v[0, k]) and math.isfinite(v[1, k])
                if interior:
                    # all four corners, as for a cell
                    out[i, j] = 0.25 * _four_corner_deviation(
                        (u[0, 0], u[0, 1], u[0, 2]), (v[0, 0], v[0, 1], v[0, 2]),
                        (u[1, 0], u[1, 1], u[1, 2]), (v[1, 0], v[1, 1], v[1, 2]),
                    )  # fmt: skip
                    continue
            total = 0.0
            count = 0
            for p in range(2):
                if not have_u[p]:
                    continue
                for q in range(2):
                    if not have_v[q]:
                        continue
                    omega = _angle(u[p, 0], u[p, 1], u[p, 2], v[q, 0], v[q, 1], v[q, 2])
                    if math.isfinite(omega):
                        total += omega
                        count += 1
            out[i, j] = total / count - _HALF_PI if count > 0 else np.nan


@_jit
def shear_extremes(shear: FloatArray, counted: BoolArray, gamma: FloatArray, in_part: BoolArray):
    """(largest |γ| over the ``counted`` cells' shear, largest |γ| over the node shear
    ``gamma`` at nodes ``in_part`` where it is finite) [rad], 0 where there is none and NaN
    when a counted cell's shear is NaN (as numpy's max): ``preform.drape.engine.fields.extremes``
    without the boolean-indexed copies."""
    cells = 0.0
    for i in range(shear.shape[0]):
        for j in range(shear.shape[1]):
            if counted[i, j]:
                value = abs(shear[i, j])
                if math.isnan(value) or math.isnan(cells):
                    cells = np.nan
                elif value > cells:
                    cells = value
    largest = 0.0
    for i in range(gamma.shape[0]):
        for j in range(gamma.shape[1]):
            value = abs(gamma[i, j])
            if in_part[i, j] and value > largest:  # NaN: no shear formed there
                largest = value
    return cells, largest


@_jit
def counted_values(values: FloatArray, counted: BoolArray) -> FloatArray:
    """``values[counted]`` (flat, in row order) for a law evaluated on counted cells only."""
    total = 0
    for i in range(counted.shape[0]):
        for j in range(counted.shape[1]):
            if counted[i, j]:
                total += 1
    out = np.empty(total)
    k = 0
    for i in range(counted.shape[0]):
        for j in range(counted.shape[1]):
            if counted[i, j]:
                out[k] = values[i, j]
                k += 1
    return out


@_jit
def energy_cells(
    shear: FloatArray,
    counted: BoolArray,
    law_energy: FloatArray,
    share: FloatArray,
    locking: float,
    failure: float,
    failure_negative: float,
    density: FloatArray,
    thickness_ratio: FloatArray,
    past_locking: BoolArray,
    past_failure: BoolArray,
) -> float:
    """Fill the energy field's cell arrays and return Σ W·s over the counted cells [J/m²·cell]
    (``preform.drape.engine.fields.energy_field``): W from ``law_energy`` (the law at the counted
    cells' shear, in row order), s from ``share`` (the part weight), t/t0 = 1/cos γ, and the
    cells past the locking (|γ| > locking) and failure angles (γ > failure, or
    γ < −failure_negative for a stitch that also breaks the other way) [rad] (inf for a law
    without one). Cells not counted get W = 0, t/t0 = 1 and no flag."""
    total = 0.0
    k = 0
    for i in range(shear.shape[0]):
        for j in range(shear.shape[1]):
            if not counted[i, j]:
                density[i, j] = 0.0
                thickness_ratio[i, j] = 1.0
                past_locking[i, j] = False
                past_failure[i, j] = False
                continue
            gamma = shear[i, j]
            w = law_energy[k]
            k += 1
            density[i, j] = w
            thickness_ratio[i, j] = 1.0 / max(math.cos(gamma), 1e-12)
            past_locking[i, j] = abs(gamma) > locking
            past_failure[i, j] = gamma > failure or gamma < -failure_negative
            total += w * share[i, j]
    return total


@_jit
def code_counts(codes: NDArray[np.int8], n_codes: int) -> NDArray[np.int64]:
    """How many of ``codes`` (any shape, C order) equal 0, 1, …, n_codes − 1."""
    out = np.zeros(n_codes, dtype=np.int64)
    for code in codes.ravel():
        if 0 <= code < n_codes:
            out[code] += 1
    return out


@_jit
def cell_sums(
    cell_status: NDArray[np.int8],
    in_part: BoolArray,
    share: FloatArray,
    has_share: bool,
    shear: FloatArray,
    area: FloatArray,
    past_locking: BoolArray,
    has_energy: bool,
):
    """The cell sums of ``preform.drape.engine.fields.summary`` in one pass: (valid cells, counted
    cells (valid and in the part), counted cells cut by the part's edge (weight < 1), Σ w,
    Σ area·w [m²], Σ |γ|·w [rad], Σ w over cells past locking), w the part weight (``share``
    on counted cells when ``has_share``, else 1 there; 0 elsewhere)."""
    valid_cells = counted_cells = cut_cells = 0
    weights = draped = shear_sum = locked = 0.0
    for i in range(cell_status.shape[0]):
        for j in range(cell_status.shape[1]):
            if cell_status[i, j] != _VALID:
                continue
            valid_cells += 1
            if not in_part[i, j]:
                continue
            counted_cells += 1
            w = share[i, j] if has_share else 1.0
            if w < 1.0:
                cut_cells += 1
            weights += w
            draped += area[i, j] * w
            shear_sum += abs(shear[i, j]) * w
            if has_energy and past_locking[i, j]:
                locked += w
    return valid_cells, counted_cells, cut_cells, weights, draped, shear_sum, locked
