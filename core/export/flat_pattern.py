"""The flat ply: where each net node lies in the undeformed fabric, and the exact outline (a
staircase of whole cells) of the cells that cover the part.

A pin-jointed net keeps its fibre segments at length d, so the fabric before draping is the same
net unsheared: node (i, j) sits at ((i − i0)·d, (j − j0)·d) in the fabric's own frame, the u
fibres along x and the v fibres along y (the fabric is 0/90 in its own frame), with the start
node at the origin. Coordinates in the pattern are millimetres.

This is the geometry the cutting pattern (``preform.export.cut_pattern``) starts from; it
writes no file of its own. The ``flat_pattern`` output that wrote this staircase was replaced
by ``cut_pattern`` (the part clipped in the flat, smooth); ``cut_pattern(result,
smoothing=0)`` draws the staircase itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.result import CellStatus, DrapeResult

# Corner offsets of each cell edge, walked counter-clockwise in the flat (u = x, v = y), and the
# neighbour across the edge: the edge is on the outline when that neighbour is not in the part.
_EDGES = (
    ((0, 0), (1, 0), (0, -1)),  # along u at j
    ((1, 0), (1, 1), (1, 0)),  # along v at i + 1
    ((1, 1), (0, 1), (0, 1)),  # back along u at j + 1
    ((0, 1), (0, 0), (-1, 0)),  # back along v at i
)


@dataclass(frozen=True)
class FlatPattern:
    """Closed outline loops of the ply in the flat [mm].

    Each loop is an (n, 2) array of vertices without the first repeated at the end. Outer loops
    run counter-clockwise, holes clockwise; ``holes[k]`` says which. Only corners are kept
    (collinear vertices along a straight edge are dropped).
    """

    loops: tuple[FloatArray, ...]
    holes: tuple[bool, ...]
    #: Node spacing d [mm].
    node_spacing_mm: float
    #: Number of net cells inside the outline.
    cell_count: int

    @property
    def area_mm2(self) -> float:
        """Area enclosed [mm²]: outer loops minus holes."""
        return float(sum(_signed_area(loop) for loop in self.loops))

    @property
    def bounds_mm(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max) [mm]; all NaN for an empty pattern."""
        if not self.loops:
            return (np.nan, np.nan, np.nan, np.nan)
        pts = np.concatenate(self.loops)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))


def _signed_area(loop: FloatArray) -> float:
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def flat_node_positions(result: DrapeResult) -> FloatArray:
    """Position of every node (ni, nj, 2) [m] in the undeformed fabric, start node at 0."""
    ni, nj = result.shape
    i0, j0 = result.start_index
    ii, jj = np.meshgrid(np.arange(ni) - i0, np.arange(nj) - j0, indexing="ij")
    return result.node_spacing * np.stack([ii, jj], axis=-1).astype(float)


def part_cells(result: DrapeResult) -> BoolArray:
    """Cells that make up the ply (ni−1, nj−1): valid and inside the part."""
    return np.asarray(result.cell_status == CellStatus.VALID) & np.asarray(
        result.in_part, dtype=bool
    )


def outline_loops(cells: BoolArray) -> list[list[tuple[int, int]]]:
    """Outline of a set of net cells as closed loops of node indices (i, j).

    Every cell edge with a cell of the set on one side only is chained into loops with the set
    on the left, so outer loops run counter-clockwise and holes clockwise. Where two cells of
    the set touch only at a corner the walk turns left, keeping them apart: a ply piece hanging
    on a single pin is a separate piece for a cutter.
    """
    cells = np.asarray(cells, dtype=bool)
    padded = np.pad(cells, 1)
    a, b = np.nonzero(cells)
    starts: list[NDArray[np.int64]] = []
    ends: list[NDArray[np.int64]] = []
    for (s0, s1), (e0, e1), (n0, n1) in _EDGES:
        open_side = ~padded[a + 1 + n0, b + 1 + n1]
        sa, sb = a[open_side], b[open_side]
        starts.append(np.column_stack([sa + s0, sb + s1]))
        ends.append(np.column_stack([sa + e0, sb + e1]))
    start = np.concatenate(starts)
    end = np.concatenate(ends)

    outgoing: dict[tuple[int, int], list[int]] = {}
    for k, (p, q) in enumerate(start.tolist()):
        outgoing.setdefault((p, q), []).append(k)
    heading = end - start
    # The edge after each edge: at a pinch vertex (two edges out) take the left turn. Every
    # vertex has as many edges in as out, so this is a permutation and its cycles are the loops.
    following = np.empty(len(start), dtype=np.int64)
    for k, (p, q) in enumerate(end.tolist()):
        candidates = np.asarray(outgoing[(p, q)])
        turn = heading[k, 0] * heading[candidates, 1] - heading[k, 1] * heading[candidates, 0]
        following[k] = candidates[np.argmax(turn)]
    # Start each loop at its lowest-left edge so the output does not depend on dict order.
    order = np.lexsort((start[:, 1], start[:, 0]))
    used = np.zeros(len(start), dtype=bool)
    loops: list[list[tuple[int, int]]] = []
    for first in order.tolist():
        edge = first
        loop: list[tuple[int, int]] = []
        while not used[edge]:
            used[edge] = True
            loop.append((int(start[edge, 0]), int(start[edge, 1])))
            edge = int(following[edge])
        if loop:
            loops.append(_drop_collinear(loop))
    return loops


def _drop_collinear(loop: list[tuple[int, int]]) -> list[tuple[int, int]]:
    pts = np.asarray(loop)
    before = pts - np.roll(pts, 1, axis=0)
    after = np.roll(pts, -1, axis=0) - pts
    turn = before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0]
    # Outline edges never reverse, so a zero turn is a vertex in the middle of a straight side.
    return [loop[k] for k in np.nonzero(turn != 0)[0].tolist()]


def flat_pattern(result: DrapeResult, cells: BoolArray | None = None) -> FlatPattern:
    """The flat pattern of a draped net: outline [mm] of ``cells`` in the undeformed fabric.

    ``cells`` defaults to the part (valid cells with ``in_part``). Outer loops come first,
    largest first, then holes.
    """
    chosen = part_cells(result) if cells is None else np.asarray(cells, dtype=bool)
    positions_mm = 1e3 * flat_node_positions(result)
    loops = []
    for loop in outline_loops(chosen):
        idx = np.asarray(loop)
        loops.append(positions_mm[idx[:, 0], idx[:, 1]])
    areas = [_signed_area(loop) for loop in loops]
    order = sorted(range(len(loops)), key=lambda k: (areas[k] < 0, -abs(areas[k])))
    return FlatPattern(
        loops=tuple(loops[k] for k in order),
        holes=tuple(areas[k] < 0 for k in order),
        node_spacing_mm=1e3 * result.node_spacing,
        cell_count=int(np.count_nonzero(chosen)),
    )
