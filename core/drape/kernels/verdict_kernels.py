"""Compiled passes of the drape verdict (``preform.drape.judging.verdict``): the dependency shadows and
the coverage's node and cell counts.

Each pass replaces a chain of whole-net numpy masks (a million-node net's masks cost a pass
over memory each). The definitions are those of ``preform.drape.judging.verdict``; this module is
their only implementation, imported when a drape is judged, so numba stays out of start-up.
"""

from __future__ import annotations

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

BoolArray = NDArray[np.bool_]
StatusArray = NDArray[np.int8]

_jit = numba.njit(cache=True, error_model="numpy")

_NOT_REACHED = np.int8(NodeStatus.NOT_REACHED)
_NO_INTERSECTION = np.int8(NodeStatus.NO_INTERSECTION)
_FOLDED = np.int8(NodeStatus.FOLDED)
_VALID = np.int8(CellStatus.VALID)
_CELL_OUTSIDE = np.int8(CellStatus.OUTSIDE_PLY)

#: What a node is to the coverage, as bits: the five causes of uncovered area in the order
#: the verdict gives a cell to the first of them (``CAUSES``), then past the tool's edge,
#: missing (over the tool, not placed), and lost behind a fold.
CAUSES = ("folded", "no_intersection", "stopped_on_tool", "behind_failure", "behind_outline")
_PAST_EDGE, _MISSING, _FOLD_NODE = 32, 64, 128


@_jit
def dependency_shadow(mask: BoolArray, i0: int, j0: int, out: BoolArray) -> None:
    """``preform.drape.judging.verdict.dependency_shadow`` into ``out`` (ni, nj): True where the
    rectangle between a node and the start node (i0, j0) holds a True node of ``mask``.

    Per quadrant, outward from the start, S(i, j) = mask(i, j) or S(i ∓ 1, j) or S(i, j ∓ 1)
    (the rectangle's OR). On the start's row and column the rectangle is a segment of that
    row or column whichever quadrant sweeps it, so the quadrants agree there."""
    ni, nj = mask.shape
    if ni == 0 or nj == 0:
        return
    for si in (1, -1):
        i_end = ni if si > 0 else -1
        for sj in (1, -1):
            j_end = nj if sj > 0 else -1
            for i in range(i0, i_end, si):
                for j in range(j0, j_end, sj):
                    value = mask[i, j]
                    if i != i0:
                        value = value or out[i - si, j]
                    if j != j0:
                        value = value or out[i, j - sj]
                    out[i, j] = value


@_jit
def coverage_nodes(
    status: StatusArray,
    stopped: BoolArray,
    lost: BoolArray,
    past_edge: BoolArray,
    behind_failure: BoolArray,
    behind_outline: BoolArray,
    behind_fold: BoolArray,
    over: BoolArray,
    i0: int,
    j0: int,
    bits: NDArray[np.uint8],
):
    """The coverage's node counts, and each node's bits (``CAUSES``, past edge, missing, lost
    behind a fold) into ``bits`` (ni, nj), from the verdict's masks (``lost``: not placed,
    in the ply, not past the edge; ``over``: lost and over the tool in plan).

    Returns (counts: lost and stopped on the tool, lost with no intersection, lost folded,
    not reached behind a failure, not reached behind the outline only, not reached for no
    reason, overhang (past the edge, or lost and not over the tool), missing; the flat index
    of the missing node nearest the start (|i − i0| + |j − j0|, the first in row order), −1
    for none)."""
    counts = np.zeros(8, dtype=np.int64)
    first = -1
    nearest = 0
    ni, nj = status.shape
    for i in range(ni):
        for j in range(nj):
            code = 0
            if past_edge[i, j]:
                code |= _PAST_EDGE
                counts[6] += 1
            if lost[i, j]:
                st = status[i, j]
                if st == _FOLDED:
                    code |= 1
                    counts[2] += 1
                if st == _NO_INTERSECTION:
                    code |= 2
                    counts[1] += 1
                if stopped[i, j]:
                    code |= 4
                    counts[0] += 1
                if behind_fold[i, j]:
                    code |= _FOLD_NODE
                if over[i, j]:
                    code |= _MISSING
                    counts[7] += 1
                    if behind_failure[i, j]:
                        code |= 8
                    if behind_outline[i, j]:
                        code |= 16
                    if st == _NOT_REACHED:
                        if behind_failure[i, j]:
                            counts[3] += 1
                        elif behind_outline[i, j]:
                            counts[4] += 1
                        else:
                            counts[5] += 1
                    distance = abs(i - i0) + abs(j - j0)
                    if first < 0 or distance < nearest:
                        first, nearest = i * nj + j, distance
                else:
                    counts[6] += 1  # lost where the tool is not: overhang too
            bits[i, j] = code
    return counts, first


@_jit
def coverage_cells(
    cell_status: StatusArray,
    bits: NDArray[np.uint8],
    fold_cells: BoolArray,
    lost_cells: BoolArray,
):
    """The coverage's cell counts from the corners' bits (:func:`coverage_nodes`): (cells
    asked, cells covered (valid), the asked cells not covered by the first cause among their
    corners (``CAUSES`` order, then none: 6 counts)); ``fold_cells`` (ni−1, nj−1): the
    cells in the ply, not valid, with no corner past the edge and one lost behind a fold; and
    ``lost_cells`` (ni−1, nj−1): the asked cells not covered, and the fold cells.

    A cell is asked when valid, or in the ply with a missing corner and none past the edge."""
    asked = covered = 0
    uncovered = np.zeros(6, dtype=np.int64)
    for i in range(cell_status.shape[0]):
        for j in range(cell_status.shape[1]):
            corners = bits[i, j] | bits[i + 1, j] | bits[i, j + 1] | bits[i + 1, j + 1]
            st = cell_status[i, j]
            valid = st == _VALID
            usable = st != _CELL_OUTSIDE and not valid and not (corners & _PAST_EDGE)
            fold_cells[i, j] = usable and (corners & _FOLD_NODE) != 0
            lost_cells[i, j] = fold_cells[i, j] or (usable and (corners & _MISSING) != 0)
            if valid:
                asked += 1
                covered += 1
            elif usable and (corners & _MISSING):
                asked += 1
                cause = 0
                while cause < 5 and not (corners & (1 << cause)):
                    cause += 1
                uncovered[cause] += 1
    return asked, covered, uncovered
