"""Whether an outline is a polygon that bounds a region: simple (no edge meets another except
its two neighbours at their shared vertex) and of nonzero area.

A ply outline or a part's plan outline that crosses itself (a bow tie) has no inside a user
meant: the even-odd rule of ``preform.drape.engine.part.PlanPolygon`` would pick one, silently. One
that encloses no area (every vertex on one line) selects nothing. Both are refused when the
scene is validated, with where the outline crosses itself, rather than draped.

The test is exact for coordinates whose products are exact in floating point (integers, the
usual millimetre outlines): orientations are signs of 2×2 determinants, no tolerance. Edges
are paired only where their x ranges overlap (sorted by their left end), so a typical outline
of short edges costs O(n log n + pairs), not n²; at worst (every edge spanning the outline in
x, a star) it is n² pairs, in bounded chunks: 10⁴ vertices, the scene's limit, take seconds.
So where shapely is installed (``preform[cutting]``) its GEOS test, O(n log n), answers first
and says where; this module's test is the fallback, and the second implementation the tests
compare shapely's against.
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import ArrayLike, NDArray

from preform.base.arrays import FloatArray

#: Pairs of edges tested at once (memory bound of the pair arrays, ~10 arrays of this length).
_CHUNK_PAIRS = 1 << 20


def _cross(
    ox: FloatArray, oy: FloatArray, ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray
) -> FloatArray:
    """Orientation of (o, a, b): > 0 counter-clockwise, 0 collinear."""
    return np.asarray((ax - ox) * (by - oy) - (ay - oy) * (bx - ox))


def _distinct_vertices(vertices: FloatArray) -> FloatArray:
    """The vertices without consecutive repeats (and without a closing repeat of the first)."""
    keep = np.any(vertices != np.roll(vertices, 1, axis=0), axis=1)
    if not keep.any():
        return vertices[:1]
    return vertices[keep]


def self_crossing(vertices: ArrayLike) -> tuple[int, int, tuple[float, float]] | None:
    """The first pair of edges (k, m), k < m, of the closed polygon ``vertices`` (n, 2) that
    meet other than at a shared vertex of neighbours, and a point where they meet (in the
    vertices' unit); None for a simple polygon. Edge k runs from vertex k to vertex k + 1 of the
    polygon with consecutive repeated vertices removed."""
    v = _distinct_vertices(np.asarray(vertices, dtype=float).reshape(-1, 2))
    n = len(v)
    if n < 3:
        return None
    a, b = v, np.roll(v, -1, axis=0)
    # Neighbours k, k + 1 share vertex k + 1: they meet elsewhere only when the outline turns
    # straight back along itself (collinear, opposite directions).
    d0, d1 = b - a, np.roll(b - a, -1, axis=0)
    turn = d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]
    back = (turn == 0.0) & (np.einsum("ij,ij->i", d0, d1) < 0.0)
    if back.any():
        k = int(np.argmax(back))
        m = (k + 1) % n
        x, y = b[k]
        return (min(k, m), max(k, m), (float(x), float(y)))
    # Every other pair: sorted by the left end, edge s can meet only edges s' > s whose left end
    # lies at or before its right end.
    lo = np.minimum(a[:, 0], b[:, 0])
    hi = np.maximum(a[:, 0], b[:, 0])
    order = np.argsort(lo, kind="stable")
    lo_sorted = lo[order]
    stop = np.searchsorted(lo_sorted, hi[order], side="right")
    counts = np.maximum(stop - np.arange(n) - 1, 0)
    start = 0
    while start < n:
        end = start
        total = 0
        while end < n and (total == 0 or total + counts[end] <= _CHUNK_PAIRS):
            total += int(counts[end])
            end += 1
        rows = np.repeat(np.arange(start, end), counts[start:end])
        offsets = np.arange(len(rows)) - np.repeat(
            np.cumsum(counts[start:end]) - counts[start:end], counts[start:end]
        )
        i, j = order[rows], order[rows + 1 + offsets]
        hit = _meet(a, b, i, j, n)
        if hit.any():
            first = int(np.argmax(hit))
            k, m = sorted((int(i[first]), int(j[first])))
            return (k, m, _meeting_point(a[k], b[k], a[m], b[m]))
        start = end
    return None


def _meet(
    a: FloatArray, b: FloatArray, i: NDArray[np.int64], j: NDArray[np.int64], n: int
) -> NDArray[np.bool_]:
    """Whether edges i and j (arrays of edge numbers) meet, neighbours excluded."""
    neighbours = ((i + 1) % n == j) | ((j + 1) % n == i)
    ax, ay, bx, by = a[i, 0], a[i, 1], b[i, 0], b[i, 1]
    cx, cy, dx, dy = a[j, 0], a[j, 1], b[j, 0], b[j, 1]
    o1 = np.sign(_cross(ax, ay, bx, by, cx, cy))
    o2 = np.sign(_cross(ax, ay, bx, by, dx, dy))
    o3 = np.sign(_cross(cx, cy, dx, dy, ax, ay))
    o4 = np.sign(_cross(cx, cy, dx, dy, bx, by))
    boxes = (
        (np.minimum(ax, bx) <= np.maximum(cx, dx))
        & (np.minimum(cx, dx) <= np.maximum(ax, bx))
        & (np.minimum(ay, by) <= np.maximum(cy, dy))
        & (np.minimum(cy, dy) <= np.maximum(ay, by))
    )
    return np.asarray(~neighbours & (o1 * o2 <= 0) & (o3 * o4 <= 0) & boxes)


def _meeting_point(
    a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray
) -> tuple[float, float]:
    """A point common to segments ab and cd (which meet)."""
    r, s = b - a, d - c
    denominator = r[0] * s[1] - r[1] * s[0]
    if denominator != 0.0:
        t = ((c[0] - a[0]) * s[1] - (c[1] - a[1]) * s[0]) / denominator
        p = a + t * r
        return (float(p[0]), float(p[1]))
    # collinear and overlapping: an end of one segment lies on the other
    for p, (q0, q1) in ((c, (a, b)), (d, (a, b)), (a, (c, d)), (b, (c, d))):
        if np.all(np.minimum(q0, q1) <= p) and np.all(p <= np.maximum(q0, q1)):
            return (float(p[0]), float(p[1]))
    return (float(c[0]), float(c[1]))  # pragma: no cover - segments that meet share a point


def _crossing_point(v: FloatArray) -> tuple[float, float] | None:
    """Where the polygon ``v`` meets itself, or None when it is simple (module docstring)."""
    distinct = _distinct_vertices(v)
    if len(distinct) < 3:
        return None
    try:
        import shapely
    except ImportError:
        crossing = self_crossing(distinct)
        return None if crossing is None else crossing[2]
    reason = shapely.is_valid_reason(shapely.Polygon(distinct))
    if reason == "Valid Geometry":
        return None
    numbers = re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", reason)
    if len(numbers) >= 2:
        return (float(numbers[-2]), float(numbers[-1]))
    crossing = self_crossing(distinct)  # a reason without a point: find one here
    return None if crossing is None else crossing[2]


def signed_area(vertices: ArrayLike) -> float:
    """Shoelace area of the closed polygon (n, 2), positive counter-clockwise (unit²)."""
    v = np.asarray(vertices, dtype=float).reshape(-1, 2)
    x, y = v[:, 0], v[:, 1]
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def outline_problem(vertices: ArrayLike, unit: str = "mm") -> str | None:
    """Why the closed outline ``vertices`` (n, 2) bounds no region, in words with its
    coordinates in ``unit``; None when it is a simple polygon of nonzero area."""
    v = np.asarray(vertices, dtype=float).reshape(-1, 2)
    if not np.all(np.isfinite(v)):
        return "the outline's vertices must be finite numbers"
    distinct = _distinct_vertices(v)
    # every vertex on one line (or one point): no area, whatever the order (a bow tie's signed
    # area is zero too, so the test is of collinearity, not of the area)
    centred = distinct - distinct.mean(axis=0)
    span = float(np.abs(centred).max()) if len(distinct) else 0.0
    if len(distinct) < 3 or np.linalg.svd(centred, compute_uv=False)[-1] <= 1e-12 * span:
        return (
            "the outline encloses no area (its vertices lie on one line or repeat one point), "
            "so it selects nothing"
        )
    point = _crossing_point(v)
    if point is not None:
        x, y = point
        return (
            f"the outline crosses itself near (x, y) = ({x:.6g}, {y:.6g}) {unit}; an outline "
            "must be a simple polygon, its edges meeting only their neighbours at their shared "
            "vertex: reorder the vertices along the boundary"
        )
    return None


__all__ = ["outline_problem", "self_crossing", "signed_area"]
