"""Generator fibre paths: the two fibres through the start point that fix a pin-jointed net.

A generator is built as half-lines from the start node, each carrying nodes at successive chord
distance d (the net is inextensible between pins, so the chord, not the arc, is d). Three kinds:

- geodesic: the straightest path on the tool. A surface may give it in closed form
  (:class:`ClosedFormGeodesics`, e.g. great circles on a sphere); otherwise it is marched in
  sub-steps h = d / substeps by straight continuation, x_{k+1} = closest(x_k + h·t_k) with t_k
  the last chord direction. The second difference of a geodesic is along the surface normal,
  which this continuation honours up to O(h³) per step, so the sideways drift is O(h²) over
  the generator's length, not the O(d) drift of building a generator cell by cell.
- plan: the tool surface above a straight line in plan.
- a user polyline in plan (:class:`PlanPolylines`), likewise lifted onto the tool.

Every function here is vectorised over the half-lines and loops only along them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, cast, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from preform.base.arrays import BoolArray, FloatArray, StatusArray
from preform.drape.engine.compiled_surface import CompiledQueries, checked_kind, kernel_parameters
from preform.drape.engine.result import NodeStatus
from preform.drape.engine.surface import Surface


@runtime_checkable
class ClosedFormGeodesics(Protocol):
    """Optional surface method: generator nodes along geodesics in closed form."""

    def geodesic_nodes(
        self, start: FloatArray, direction: FloatArray, spacing: float, count: int
    ) -> tuple[FloatArray, StatusArray]:
        """``count`` nodes (m, count, 3) [m] along the geodesics leaving ``start`` (m, 3) in
        tangent ``direction`` (m, 3), successive chords ``spacing`` [m] long, with NodeStatus
        codes (m, count): PLACED, or OFF_TOOL where the geodesic has left the tool."""
        ...


@dataclass(frozen=True)
class PlanPolylines:
    """User generator paths in plan [m]: polylines (k ≥ 2, 2) for the first (+u) and second
    (+v) fibre families, each running through the start point in its positive direction
    (vertex order = +u / +v). Beyond their ends they are continued straight."""

    first_xy_m: FloatArray
    second_xy_m: FloatArray

    def __init__(self, first_xy_m: ArrayLike, second_xy_m: ArrayLike) -> None:
        for name, value in (("first_xy_m", first_xy_m), ("second_xy_m", second_xy_m)):
            arr = np.asarray(value, dtype=float)
            if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) < 2:
                raise ValueError(f"{name} must be a (k >= 2, 2) plan polyline, got {arr.shape}")
            object.__setattr__(self, name, arr)


@dataclass(frozen=True)
class GeneratorNodes:
    """Nodes along m generator half-lines."""

    #: Positions (m, count, 3) [m]; NaN where status != PLACED.
    points: FloatArray
    #: NodeStatus codes (m, count): PLACED, then OFF_TOOL once, then NOT_REACHED.
    status: StatusArray
    #: Residual (m, count) [m]: max of |chord − d| and the distance to the surface.
    residual: FloatArray


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...i,...i->...", a, b)


def _unit(a: FloatArray) -> FloatArray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / np.sqrt(_dot(a, a))[..., None]


def _finish(points: FloatArray, on_tool: BoolArray, residual: FloatArray) -> GeneratorNodes:
    """Statuses along each half-line: the first node off the tool is OFF_TOOL, the rest of that
    half-line NOT_REACHED (it hangs from a node that does not exist)."""
    alive = np.logical_and.accumulate(on_tool, axis=1)
    first_dead = ~alive & np.concatenate(
        [np.ones((len(alive), 1), dtype=bool), alive[:, :-1]], axis=1
    )
    status = np.full(alive.shape, NodeStatus.NOT_REACHED, dtype=np.int8)
    status[alive] = NodeStatus.PLACED
    status[first_dead] = NodeStatus.OFF_TOOL
    points = points.copy()
    points[~alive] = np.nan
    residual = np.where(alive, residual, 0.0)
    return GeneratorNodes(points, status, residual)


def _residual(
    surface: Surface, points: FloatArray, start: FloatArray, spacing: float
) -> FloatArray:
    """|chord − d| to the previous node and distance to the surface, (m, count) [m]."""
    m, count, _ = points.shape
    prev = np.concatenate([np.broadcast_to(start, (m, 1, 3)), points[:, :-1]], axis=1)
    chord = np.sqrt(_dot(points - prev, points - prev))
    flat = points.reshape(-1, 3)
    finite = np.isfinite(flat[:, 0])
    dist = np.zeros(len(flat))
    if finite.any():
        dist[finite] = surface.closest_point(flat[finite])[1]
    return np.maximum(np.abs(chord - spacing), dist.reshape(m, count))


def geodesic_generators(
    surface: Surface,
    start: FloatArray,
    directions: FloatArray,
    spacing: float,
    count: int,
    *,
    substeps: int = 16,
    tolerance: float = 1e-9,
    use_closed_form: bool = True,
) -> GeneratorNodes:
    """Nodes along geodesics from ``start`` (3,) [m] in unit tangent ``directions`` (m, 3).

    ``count`` nodes per half-line at chord ``spacing`` [m]. The closed form of the surface is
    used when it has one and ``use_closed_form``; otherwise the geodesic is marched in
    ``substeps`` sub-steps per node spacing and each node is put at chord d from the previous
    one to ``tolerance``·d.
    """
    m = len(directions)
    starts = np.broadcast_to(start, (m, 3)).copy()
    if count == 0:
        return GeneratorNodes(np.zeros((m, 0, 3)), np.zeros((m, 0), np.int8), np.zeros((m, 0)))
    if use_closed_form and isinstance(surface, ClosedFormGeodesics):
        points, status = surface.geodesic_nodes(starts, directions, spacing, count)
        on_tool = status == NodeStatus.PLACED
        points = np.where(on_tool[..., None], points, np.nan)
        return _finish(points, on_tool, _residual(surface, points, start, spacing))
    return _march_geodesics(surface, starts, directions, spacing, count, substeps, tolerance)


def _surface_queries(
    surface: Surface,
) -> Callable[[FloatArray], tuple[FloatArray, FloatArray, FloatArray]]:
    """Closest points, the normals there and distances for points (m, 3) [m]: compiled for a
    tool with compiled queries, else the tool's own vectorised methods."""
    if isinstance(surface, CompiledQueries):
        from preform.drape.kernels import surface_kernels

        kind, params = surface.compiled_queries()
        code, values = checked_kind(kind), kernel_parameters(kind, params)

        def compiled(points: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
            return cast(
                tuple[FloatArray, FloatArray, FloatArray],
                surface_kernels.query_points(code, values, np.ascontiguousarray(points)),
            )

        return compiled

    def own(points: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        foot, dist = surface.closest_point(points)
        return foot, surface.normal(foot), dist

    return own


def _march_geodesics(
    surface: Surface,
    starts: FloatArray,
    directions: FloatArray,
    spacing: float,
    count: int,
    substeps: int,
    tolerance: float,
) -> GeneratorNodes:
    from preform.drape.kernels import generator_kernels as kernels

    query = _surface_queries(surface)
    m = len(starts)
    h = spacing / max(int(substeps), 1)
    points = np.full((m, count, 3), np.nan)
    on_tool = np.zeros((m, count), dtype=bool)
    found = np.zeros(m, dtype=int)
    running = np.ones(m, dtype=bool)
    x = np.ascontiguousarray(starts, dtype=float).copy()
    t = np.ascontiguousarray(_unit(np.asarray(directions, dtype=float)))
    normal = np.ascontiguousarray(surface.normal(starts), dtype=float)
    last = x.copy()
    # A generator that keeps turning back (a closed geodesic shorter than d) must still stop.
    for _ in range(4 * count * max(int(substeps), 1) + 16):
        act = np.flatnonzero(running & (found < count))
        if act.size == 0:
            break
        # Straight continuation, brought back to the tool along the normal at x_k (the
        # discrete geodesic equation): projecting along the normal at the new point instead
        # would leave an O(h³) sideways error per step, i.e. an O(h) drift overall.
        straight = kernels.ahead(x, t, act, h)
        foot, n_foot, _ = query(straight)
        # A sharp crease (a mesh edge onto a vertical wall): the tangent plane turns by more
        # than 60° within one sub-step, and the correction along the old normal is undefined.
        corrected, crease = kernels.along_old_normal(
            straight, np.ascontiguousarray(foot), np.ascontiguousarray(n_foot), normal, act
        )
        x_new, _, dist = query(corrected)
        x_new, dist = np.array(x_new, dtype=float), np.array(dist, dtype=float)
        if crease.any():
            x_new[crease], dist[crease] = _across_crease(
                surface, t[act][crease], normal[act][crease], foot[crease], n_foot[crease], h
            )
        # Past the edge the closest point sticks to the boundary: no progress, or far away.
        reach, before, guess = kernels.advance(
            act, x_new, dist, crease, np.ascontiguousarray(n_foot), x, t, normal, last, running,
            h, spacing,
        )  # fmt: skip
        if reach.any():
            idx = act[reach]
            node = _slide_to_chord(query, last[idx], guess[reach], spacing, tolerance)
            folded = crease[reach]
            if folded.any():
                # across a crease the straight chord cuts through the tool: find the node on
                # the two flat pieces of the path (start -> crease -> new point) instead
                node[folded] = _chord_on_bent_path(
                    last[idx][folded],
                    before[reach][folded],
                    foot[reach][folded],
                    x_new[reach][folded],
                    spacing,
                )
            points[idx, found[idx]] = node
            on_tool[idx, found[idx]] = True
            found[idx] += 1
            last[idx] = node
    return _finish(points, on_tool, _residual(surface, points, starts[0], spacing))


def _across_crease(
    surface: Surface,
    t: FloatArray,
    n_old: FloatArray,
    foot: FloatArray,
    n_new: FloatArray,
    h: float,
) -> tuple[FloatArray, FloatArray]:
    """Continue geodesics across a sharp crease by unfolding it: the component of the
    direction along the crease edge is kept, the rest turns into the new face, away from the
    crease (downhill past a convex edge, uphill at a concave one). Returns the points one
    sub-step ``h`` [m] into the new face and their distances to the surface [m]."""
    edge = _unit(np.cross(n_old, n_new))
    along = np.clip(_dot(t, edge), -1.0, 1.0)
    across = _unit(np.cross(n_new, edge))
    # past a convex edge (the new face falls away ahead) the path leaves against the old
    # normal; at a concave one (a wall rising ahead) along it
    convex = _dot(n_new, t) > 0
    wanted = np.where(convex, -1.0, 1.0)
    flip = np.sign(_dot(across, n_old)) != wanted
    across[flip] *= -1.0
    t_new = along[:, None] * edge + np.sqrt(1.0 - along**2)[:, None] * across
    return surface.closest_point(foot + h * t_new)


def _chord_on_bent_path(
    anchor: FloatArray, a: FloatArray, corner: FloatArray, b: FloatArray, spacing: float
) -> FloatArray:
    """Points on the polyline a → corner → b [m] at chord ``spacing`` [m] from ``anchor``,
    by bisection on the path parameter (the distance from the anchor grows along the path
    while the path leads away from it, which holds within one sub-step)."""
    first = np.linalg.norm(corner - a, axis=-1)
    second = np.linalg.norm(b - corner, axis=-1)
    total = first + second

    def at(length: FloatArray) -> FloatArray:
        on_first = length <= first
        f1 = np.where(first > 0, length / np.where(first > 0, first, 1.0), 0.0)
        f2 = np.where(second > 0, (length - first) / np.where(second > 0, second, 1.0), 1.0)
        return np.where(
            on_first[:, None],
            a + f1[:, None] * (corner - a),
            corner + np.clip(f2, 0.0, 1.0)[:, None] * (b - corner),
        )

    lo, hi = np.zeros_like(total), total.copy()
    for _ in range(60):  # halves the bracket to below 1e-18 of a sub-step
        mid = 0.5 * (lo + hi)
        beyond = np.linalg.norm(at(mid) - anchor, axis=-1) >= spacing
        hi = np.where(beyond, mid, hi)
        lo = np.where(beyond, lo, mid)
    return at(hi)


def _slide_to_chord(
    query: Callable[[FloatArray], tuple[FloatArray, FloatArray, FloatArray]],
    anchor: FloatArray,
    guess: FloatArray,
    spacing: float,
    tolerance: float,
) -> FloatArray:
    """Move surface points ``guess`` to chord ``spacing`` from ``anchor`` keeping their
    direction: alternate rescaling and projection (each round shrinks the error by ~(d/R)²)."""
    from preform.drape.kernels import generator_kernels as kernels

    node = np.ascontiguousarray(guess, dtype=float)
    anchor = np.ascontiguousarray(anchor, dtype=float)
    for _ in range(8):
        node = np.ascontiguousarray(query(kernels.to_chord(anchor, node, spacing))[0])
        chord = np.sqrt(_dot(node - anchor, node - anchor))
        if np.all(np.abs(chord - spacing) <= tolerance * spacing):
            break
    return np.array(node, dtype=float)


class _PlanPaths:
    """m plan polylines starting at a common start, parametrised by plan arc length [m]."""

    def __init__(self, polylines: list[FloatArray], reach: float) -> None:
        self.arc: list[FloatArray] = []
        self.xy: list[FloatArray] = []
        for line in polylines:
            # Continue the last segment far beyond the tool so np.interp never clamps.
            tail = line[-1] - line[-2]
            tail = tail / np.hypot(*tail)
            line = np.vstack([line, line[-1] + reach * tail])
            seg = np.hypot(*np.diff(line, axis=0).T)
            keep = np.concatenate([[True], seg > 0])
            line = line[keep]
            self.xy.append(line)
            self.arc.append(np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))]))

    def at(self, rows: NDArray[np.intp], s: FloatArray) -> FloatArray:
        out = np.empty((len(rows), 2))
        for k, (row, sk) in enumerate(zip(rows, s, strict=True)):
            out[k, 0] = np.interp(sk, self.arc[row], self.xy[row][:, 0])
            out[k, 1] = np.interp(sk, self.arc[row], self.xy[row][:, 1])
        return out


def plan_generators(
    surface: Surface,
    start: FloatArray,
    polylines: list[FloatArray],
    spacing: float,
    count: int,
    *,
    substeps: int = 16,
    tolerance: float = 1e-9,
) -> GeneratorNodes:
    """Nodes along the tool surface above plan polylines (each (k, 2) [m], starting at the
    start's plan position): successive chords ``spacing`` [m] to ``tolerance``·d.

    Each node is bracketed by stepping d / ``substeps`` in plan arc length from the previous
    one, then found by regula falsi (Illinois) on chord(s) − d. A plan position that is not
    over the tool ends the half-line (OFF_TOOL).
    """
    m = len(polylines)
    points = np.full((m, count, 3), np.nan)
    on_tool = np.zeros((m, count), dtype=bool)
    if count == 0:
        return GeneratorNodes(points, on_tool.astype(np.int8), np.zeros((m, 0)))
    (x0, y0, _), (x1, y1, _) = surface.bounds
    reach = 4.0 * (np.hypot(x1 - x0, y1 - y0) + count * spacing)
    paths = _PlanPaths(polylines, reach)
    h = spacing / max(int(substeps), 1)
    s_prev = np.zeros(m)
    last = np.broadcast_to(start, (m, 3)).copy()
    running = np.ones(m, dtype=bool)

    def chord_at(rows: NDArray[np.intp], s: FloatArray) -> tuple[FloatArray, BoolArray]:
        pts, mask = surface.point_at_plan(paths.at(rows, s))
        with np.errstate(invalid="ignore"):
            f = np.sqrt(_dot(pts - last[rows], pts - last[rows])) - spacing
        return f, mask & np.isfinite(f)

    for k in range(count):
        rows = np.flatnonzero(running)
        if rows.size == 0:
            break
        lo = s_prev[rows].copy()
        f_lo = np.full(len(rows), -spacing)
        hi = lo.copy()
        f_hi = f_lo.copy()
        bracketed = np.zeros(len(rows), dtype=bool)
        alive = np.ones(len(rows), dtype=bool)
        for _ in range(64 * max(int(substeps), 1)):
            todo = np.flatnonzero(alive & ~bracketed)
            if todo.size == 0:
                break
            lo[todo], f_lo[todo] = hi[todo], f_hi[todo]
            hi[todo] = lo[todo] + h
            f, ok = chord_at(rows[todo], hi[todo])
            f_hi[todo] = f
            alive[todo[~ok]] = False
            bracketed[todo[ok & (f >= 0)]] = True
        alive &= bracketed
        running[rows[~alive]] = False
        rows, lo, hi, f_lo, f_hi = rows[alive], lo[alive], hi[alive], f_lo[alive], f_hi[alive]
        if rows.size == 0:
            break
        s = hi.copy()
        side = np.zeros(len(rows), dtype=int)
        for _ in range(100):
            s = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            f, _ok = chord_at(rows, s)
            if np.all(np.abs(f) <= tolerance * spacing):
                break
            # Illinois: halve the stale end's value so the bracket shrinks from both sides.
            right = f > 0
            hi, f_hi = np.where(right, s, hi), np.where(right, f, f_hi)
            lo, f_lo = np.where(right, lo, s), np.where(right, f_lo, f)
            f_lo = np.where(right & (side == 1), 0.5 * f_lo, f_lo)
            f_hi = np.where(~right & (side == -1), 0.5 * f_hi, f_hi)
            side = np.where(right, 1, -1)
        node, _mask = surface.point_at_plan(paths.at(rows, s))
        points[rows, k] = node
        on_tool[rows, k] = True
        last[rows] = node
        s_prev[rows] = s
    return _finish(points, on_tool, _residual(surface, points, np.asarray(start), spacing))
