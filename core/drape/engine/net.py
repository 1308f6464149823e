"""The kinematic drape engine: a pin-jointed net placed on a tool front by front.

Mack & Taylor's net (PHYSICS §6): inextensible tows pinned at crossovers that turn freely.
Two generator fibres through the start point fix it; node (i, j) is then the point on the tool
at chord d from (i∓1, j) and (i, j∓1), on the far side from (i∓1, j∓1). A node depends only on
nodes of the two previous anti-diagonals |i − i0| + |j − j0| = k − 1, k − 2, so every node of
a front (all four quadrants stacked) is placed in one vectorised step:

- in closed form when the surface offers it (:class:`ClosedFormPlacement`, e.g. the sphere);
- exactly on a faceted tool that walks from the parents' facets (:class:`WalkingPlacement`,
  triangle meshes): each node's facet is kept as the hint for its children;
- otherwise on the circle where the two distance spheres meet: P(φ) = M + r(cos φ·a1 +
  sin φ·a2), a1 the surface normal seen from the chord A→B, a2 pointing away from the opposite
  node. Both distance constraints then hold exactly for every φ and only the signed distance
  to the surface g(φ) is left: a few vectorised, damped Newton steps in φ solve it to
  ``tolerance``·d.

The arithmetic is compiled (:mod:`preform.drape.kernels.net_kernels`, imported when a net
is draped): on a tool with compiled queries
(:class:`~preform.drape.engine.compiled_surface.CompiledQueries`) one compiled loop fills the
whole net, sweeping each quadrant row by row (a node needs only its three parents, so the net
is the same); a walking tool with a compiled fill of its own (:class:`WalkingFill`, triangle
meshes) does the same with its walk; on any other tool the fronts above are filled in turn,
the tool's own vectorised queries between the same compiled per-node steps.

:func:`drape` is four stages, each reading the :class:`DrapeSettings`: :func:`place_start`,
:func:`place_generators`, :func:`place_fronts`, :func:`net_fields`. Every node ends with a
:class:`~preform.drape.engine.result.NodeStatus` and a residual; a node whose parent failed
is NOT_REACHED, never a silent NaN.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, NamedTuple, Protocol, cast, runtime_checkable

import numpy as np

from preform.base.arrays import FloatArray, IntArray, StatusArray
from preform.drape.engine.compiled_surface import CompiledQueries, checked_kind, kernel_parameters
from preform.drape.engine.fields import cell_fields
from preform.drape.engine.generators import (
    GeneratorNodes,
    PlanPolylines,
    geodesic_generators,
    plan_generators,
)
from preform.drape.engine.result import DrapeResult, NodeStatus
from preform.drape.engine.settings import DrapeError, DrapeSettings
from preform.drape.engine.surface import Surface

_PLACED = np.int8(NodeStatus.PLACED)
_NOT_REACHED = np.int8(NodeStatus.NOT_REACHED)


@runtime_checkable
class ClosedFormPlacement(Protocol):
    """Optional surface method: net nodes in closed form, vectorised over a front."""

    def place_nodes(
        self, a: FloatArray, b: FloatArray, opposite: FloatArray, spacing: float
    ) -> tuple[FloatArray, StatusArray]:
        """Points (m, 3) [m] on the tool at chord ``spacing`` [m] from both ``a`` and ``b``
        (m, 3), the root on the far side from ``opposite`` (m, 3); and NodeStatus codes (m,):
        PLACED, NO_INTERSECTION (no such point), OFF_TOOL (it lies past the tool's edge)."""
        ...


class FacePlacement(NamedTuple):
    """Nodes placed on a faceted tool, with what the engine would otherwise search for."""

    #: Positions (m, 3) [m], NaN where not placed.
    points: FloatArray
    #: NodeStatus codes (m,): PLACED, NO_INTERSECTION, OFF_TOOL, FOLDED (parents coincide).
    status: StatusArray
    #: The facet each node lies on (m,), −1 where not placed; the hint for its children.
    faces: IntArray
    #: Unit outward normals (m, 3) there (for the fold test), and the residual (m,) [m] of the
    #: placement's own constraints: spacing (chord, or length along the surface over a feature
    #: crease) and distance to the facet.
    normals: FloatArray
    residual: FloatArray


@runtime_checkable
class WalkingPlacement(Protocol):
    """Optional surface methods: exact placement walking from the parents' facets (meshes)."""

    def locate_faces(self, points: FloatArray) -> IntArray:
        """The facet (n,) each surface point (n, 3) [m] lies on."""
        ...

    def spacings(
        self, a: FloatArray, b: FloatArray, face_a: IntArray, face_b: IntArray, spacing: float
    ) -> FloatArray:
        """Spacings (m,) [m] from ``a`` on facets ``face_a`` to ``b`` on ``face_b`` under the
        surface's own rule (the chord, or the length along the surface over a crease)."""
        ...

    def place_nodes_from_faces(
        self,
        a: FloatArray,
        b: FloatArray,
        opposite: FloatArray,
        spacing: float,
        face_a: IntArray,
        face_b: IntArray,
        face_opposite: IntArray,
    ) -> FacePlacement:
        """As :meth:`ClosedFormPlacement.place_nodes`, starting from the facets of a and b
        (the opposite node's facet says on which side of a crease it lies)."""
        ...


#: Where a net's fronts lie in its flat node arrays: (nodes per row nj, the start node's flat
#: index, and per quadrant its signs along i and j and its extents along them, (q,) each; the
#: last front), as ``preform.drape.kernels.net_kernels`` sweeps them.
NetLayout = tuple[int, int, IntArray, IntArray, IntArray, IntArray, int]


@runtime_checkable
class WalkingFill(Protocol):
    """Optional method of a :class:`WalkingPlacement` tool: the whole fill in one compiled
    loop, each node placed as ``place_nodes_from_faces`` would and checked as
    ``net_kernels.finish_front`` checks it, so the net is the front-by-front loop's."""

    def fill_fronts(
        self,
        pos: FloatArray,
        status: StatusArray,
        residual: FloatArray,
        face: IntArray,
        layout: NetLayout,
        spacing: float,
        lo: FloatArray,
        hi: FloatArray,
    ) -> int:
        """Every front of the net, in place on the flat node positions ``pos`` (n, 3) [m],
        statuses, residuals [m] and facets ``face`` (the generators' already there), at node
        spacing ``spacing`` [m], nodes past the bounds ``lo``/``hi`` (3,) [m] OFF_TOOL;
        returns the number of fronts placed."""
        ...


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


# --------------------------------------------------------------------------------------------
# One front, general surfaces


def _solve_on_circle(
    surface: Surface,
    a: FloatArray,
    b: FloatArray,
    c: FloatArray,
    spacing: float,
    tolerance_m: float,
    max_iterations: int,
) -> tuple[FloatArray, StatusArray, int]:
    """Nodes at chord ``spacing`` from a and b on the surface, away from c (see module doc),
    for a surface queried through its own vectorised methods; the per-node arithmetic is the
    compiled one of :mod:`preform.drape.kernels.net_kernels`.

    Returns points (m, 3) (NaN where not placed), NodeStatus codes and the iterations used.
    """
    from preform.drape.kernels import net_kernels as kernels

    m = len(a)
    points = np.full((m, 3), np.nan)
    status = np.full(m, NodeStatus.NO_INTERSECTION, dtype=np.int8)
    guess, _ = surface.closest_point(a + b - c)
    n0 = np.asarray(surface.normal(guess), dtype=float)
    frames, angle = kernels.circle_frames(a, b, c, np.asarray(guess, dtype=float), n0, spacing)
    active = np.flatnonzero(np.isfinite(angle[:, 0]))
    used = 0
    for used in range(1, max_iterations + 1):  # the last value is reported
        if active.size == 0:
            break
        x = kernels.circle_points(frames, angle, active)
        foot, dist = surface.closest_point(x)
        n = surface.normal(foot)
        active = kernels.newton_updates(
            active,
            x,
            np.asarray(foot, dtype=float),
            np.asarray(n, dtype=float),
            np.asarray(dist, dtype=float),
            frames,
            angle,
            points,
            status,
            tolerance_m,
            used == max_iterations,
        )
    return points, status, used


# --------------------------------------------------------------------------------------------
# The start


def _lift_to_tangent(direction_xy: FloatArray, normal: FloatArray) -> FloatArray | None:
    """The unit tangent whose plan projection points along ``direction_xy`` (None if none)."""
    dx, dy = direction_xy / np.hypot(*direction_xy)
    if normal[2] > 1e-9:
        t = np.array([dx, dy, -(normal[0] * dx + normal[1] * dy) / normal[2]])
    elif abs(normal[0] * dx + normal[1] * dy) <= 1e-9:
        # Vertical wall: only a horizontal tangent keeps its plan direction.
        t = np.array([dx, dy, 0.0])
    else:
        return None
    return np.asarray(t / np.linalg.norm(t), dtype=float)


def _split_polyline(
    line: FloatArray, at_xy: FloatArray, tol: float
) -> tuple[FloatArray, FloatArray]:
    """Forward and backward half-lines (both starting at ``at_xy``) of a plan polyline that
    passes within ``tol`` [m] of ``at_xy``."""
    seg0, seg1 = line[:-1], line[1:]
    ext = seg1 - seg0
    len2 = np.maximum(np.einsum("ij,ij->i", ext, ext), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", at_xy - seg0, ext) / len2, 0.0, 1.0)
    foot = seg0 + t[:, None] * ext
    dist = np.hypot(*(foot - at_xy).T)
    k = int(np.argmin(dist))
    if dist[k] > tol:
        raise DrapeError(
            f"the generator polyline passes {dist[k]:.3g} m from the start point; it must run "
            "through it"
        )
    forward = np.vstack([at_xy, line[k + 1 :]])
    backward = np.vstack([at_xy, line[: k + 1][::-1]])
    if len(backward) == 2 and np.hypot(*(backward[1] - at_xy)) == 0.0:
        backward = np.vstack([at_xy, at_xy - ext[k]])
    if np.hypot(*(forward[-1] - at_xy)) == 0.0:
        forward = np.vstack([at_xy, at_xy + ext[k]])
    # Drop a leading vertex that coincides with the start.
    forward = forward[np.r_[True, np.hypot(*(forward[1:] - at_xy).T) > 0]]
    backward = backward[np.r_[True, np.hypot(*(backward[1:] - at_xy).T) > 0]]
    return forward, backward


class NetStart(NamedTuple):
    """Where the net starts (:func:`place_start`): the point on the tool (3,) and in plan (2,)
    [m]; the unit tangents (3,) of +u and +v there; the plan direction of +u [rad from the
    tool's x axis] and α [rad]; for PlanPolylines, their halves +u, −u, +v, −v in plan [m]."""

    point: FloatArray
    xy: FloatArray
    t_u: FloatArray
    t_v: FloatArray
    orientation: float
    generator_angle: float
    polyline_halves: list[FloatArray] | None = None


def place_start(surface: Surface, settings: DrapeSettings) -> NetStart:
    """The start point on the tool and the generators' directions there. Raises
    :class:`DrapeError` for a start off the tool, α outside (0, π) or unknown generators."""
    point, xy = _start_point(surface, settings)
    normal = surface.normal(point[None, :])[0]
    generators = settings.generators
    if isinstance(generators, PlanPolylines):
        return _polyline_start(generators, settings, point, xy, normal)
    if not (hasattr(generators, "nodes") or generators in ("geodesic", "plan")):
        raise DrapeError(
            f"generators must be 'geodesic', 'plan' or PlanPolylines, got {generators!r}"
        )
    if settings.orientation_rad is None or settings.generator_angle_rad is None:
        raise DrapeError("orientation_rad and generator_angle_rad are required")
    theta, alpha = float(settings.orientation_rad), float(settings.generator_angle_rad)
    if not 0 < alpha < np.pi:
        raise DrapeError(f"generator angle must lie in (0, π) rad, got {alpha!r}")
    t_u = _lift_to_tangent(np.array([np.cos(theta), np.sin(theta)]), normal)
    if t_u is None:
        raise DrapeError(
            "the tool is vertical at the start point and the orientation is not tangential to it"
        )
    t_v = np.cos(alpha) * t_u + np.sin(alpha) * _cross(normal[None], t_u[None])[0]
    return NetStart(point, xy, t_u, t_v, theta, alpha)


def _start_point(surface: Surface, settings: DrapeSettings) -> tuple[FloatArray, FloatArray]:
    """The start point on the tool (3,) [m] and its plan position (2,) [m]."""
    if (settings.start_xy_m is None) == (settings.start_point is None):
        raise DrapeError("give exactly one of start_xy_m (plan) and start_point (3-D)")
    if settings.start_xy_m is not None:
        xy = np.asarray(settings.start_xy_m, dtype=float).reshape(2)
        pts, mask = surface.point_at_plan(xy[None, :])
        if not bool(mask[0]) or not np.all(np.isfinite(pts[0])):
            raise DrapeError(
                f"the start point (x, y) = ({xy[0]:.6g}, {xy[1]:.6g}) m is not over the tool "
                f"(bounds {surface.bounds} m)"
            )
        return pts[0], xy
    point = np.asarray(settings.start_point, dtype=float).reshape(1, 3)
    foot, dist = surface.closest_point(point)
    if not dist[0] <= max(1e-6 * surface.size, settings.tolerance_m):
        raise DrapeError(f"the start point is {dist[0]:.3g} m from the tool surface")
    return foot[0], foot[0][:2].copy()


def _polyline_start(
    lines: PlanPolylines,
    settings: DrapeSettings,
    point: FloatArray,
    xy: FloatArray,
    normal: FloatArray,
) -> NetStart:
    """The start of generators along plan polylines, which set orientation and α themselves."""
    theta_rad, alpha_rad = settings.orientation_rad, settings.generator_angle_rad
    if None not in (theta_rad, alpha_rad) and (theta_rad, alpha_rad) != (0.0, 0.5 * np.pi):
        raise DrapeError("with PlanPolylines the polylines set orientation and angle")
    d = float(settings.node_spacing_m)
    fu, bu = _split_polyline(lines.first_xy_m, xy, 1e-6 * d)
    fv, bv = _split_polyline(lines.second_xy_m, xy, 1e-6 * d)
    t_u = _lift_to_tangent(fu[1] - fu[0], normal)
    t_v = _lift_to_tangent(fv[1] - fv[0], normal)
    if t_u is None or t_v is None:
        raise DrapeError("a generator polyline crosses a vertical wall at the start point")
    alpha = float(np.arctan2(_cross(t_u[None], t_v[None])[0] @ normal, t_u @ t_v))
    theta = float(np.arctan2(fu[1, 1] - fu[0, 1], fu[1, 0] - fu[0, 0]))
    if not 0 < alpha < np.pi:
        raise DrapeError(
            f"the second generator polyline is {np.degrees(alpha):.3g}° from the first; it "
            "must be counter-clockwise from it (seen from the outward normal), 0 < α < 180°"
        )
    return NetStart(point, xy, t_u, t_v, theta, alpha, [fu, bu, fv, bv])


# --------------------------------------------------------------------------------------------
# The generators


class Net(NamedTuple):
    """The net being placed, filled in place: its grid shape (ni, nj), the start node's index
    (i0, j0); positions (n, 3) [m] (NaN where not placed), NodeStatus codes (n,), residuals
    (n,) [m] over the flat grid; the generator nodes placed and each one's neighbour towards
    the start (flat indices)."""

    shape: tuple[int, int]
    start_index: tuple[int, int]
    pos: FloatArray
    status: StatusArray
    residual: FloatArray
    on_generators: IntArray
    before: IntArray

    @property
    def start_flat(self) -> int:
        return self.start_index[0] * self.shape[1] + self.start_index[1]


def place_generators(surface: Surface, settings: DrapeSettings, start: NetStart) -> Net:
    """The net's grid over the ply with the start node and the four half-generators +u, −u,
    +v, −v placed; a generator ends where it leaves the tool or the ply."""
    try:
        grid = settings.ply.node_grid(float(settings.node_spacing_m))
    except ValueError as exc:
        raise DrapeError(str(exc)) from exc
    (ni, nj), (i0, j0) = grid.shape, grid.start_index
    pos = np.full((ni * nj, 3), np.nan)
    status = np.full(ni * nj, NodeStatus.NOT_REACHED, dtype=np.int8)
    status[~grid.inside.ravel()] = NodeStatus.OUTSIDE_PLY
    residual = np.zeros(ni * nj)
    start_flat = i0 * nj + j0
    pos[start_flat], status[start_flat] = start.point, NodeStatus.PLACED
    residual[start_flat] = float(surface.closest_point(start.point[None, :])[1][0])
    counts = (ni - 1 - i0, i0, nj - 1 - j0, j0)
    gen = _march_generators(surface, settings, start, max(counts))
    on_generators, before = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
    for row, (count, stride) in enumerate(zip(counts, (nj, -nj, 1, -1), strict=True)):
        if count == 0:
            continue
        flat = start_flat + stride * np.arange(1, count + 1)
        gen_status = gen.status[row, :count].copy()
        inside = status[flat] != NodeStatus.OUTSIDE_PLY
        # A generator node outside the ply cuts the generator there like an edge of the tool.
        alive = np.logical_and.accumulate((gen_status == _PLACED) & inside)
        first_dead = ~alive & np.r_[True, alive[:-1]]
        new = np.where(alive, _PLACED, _NOT_REACHED).astype(np.int8)
        new[first_dead & (gen_status != _PLACED)] = NodeStatus.OFF_TOOL
        new[~inside] = NodeStatus.OUTSIDE_PLY
        status[flat] = new
        pos[flat[alive]] = gen.points[row, :count][alive]
        residual[flat[alive]] = gen.residual[row, :count][alive]
        on_generators.append(flat[alive])
        before.append(flat[alive] - stride)
    return Net(
        (ni, nj), (i0, j0), pos, status, residual, np.concatenate(on_generators),
        np.concatenate(before),
    )  # fmt: skip


def _march_generators(
    surface: Surface, settings: DrapeSettings, start: NetStart, count: int
) -> GeneratorNodes:
    """``count`` nodes on each of the four half-generators +u, −u, +v, −v."""
    kind, d = settings.generators, float(settings.node_spacing_m)
    t_u, t_v = start.t_u, start.t_v
    marching: dict[str, Any] = {"substeps": settings.substeps, "tolerance": settings.tolerance}
    if kind == "geodesic":
        directions = np.stack([t_u, -t_u, t_v, -t_v])
        return geodesic_generators(
            surface, start.point, directions, d, count, **marching,
            use_closed_form=settings.use_closed_form or isinstance(surface, WalkingPlacement),
        )  # fmt: skip
    if kind == "plan":
        lines = []
        for t in (t_u, -t_u, t_v, -t_v):
            if np.hypot(t[0], t[1]) <= 1e-9:
                raise DrapeError(
                    "a generator is vertical at the start point, so it has no plan direction; "
                    "use geodesic generators"
                )
            lines.append(np.vstack([start.xy, start.xy + d * t[:2] / np.hypot(*t[:2])]))
        return plan_generators(surface, start.point, lines, d, count, **marching)
    if hasattr(kind, "nodes"):
        # Paths that build their own nodes, e.g. preform.optimise.curved.CurvedGenerators.
        return cast(Any, kind).nodes(surface, start.point, t_u, t_v, d, count, **marching)
    assert start.polyline_halves is not None
    return plan_generators(surface, start.point, start.polyline_halves, d, count, **marching)


# --------------------------------------------------------------------------------------------
# The fronts


def _compiled_closed_form(surface: object) -> bool:
    """Whether a surface with compiled queries also has a compiled closed-form node."""
    from preform.drape.engine.compiled_surface import CLOSED_FORM_KINDS

    return cast(CompiledQueries, surface).compiled_queries()[0] in CLOSED_FORM_KINDS


def _fill_fronts_python(
    surface: Surface,
    settings: DrapeSettings,
    net: Net,
    layout: NetLayout,
    bounds: tuple[FloatArray, FloatArray],
    closed_form: bool,
    face: IntArray | None,
) -> tuple[int, int]:
    """The fronts of a net on a surface queried through its vectorised methods: the front
    bookkeeping and node checks are the compiled kernels', the placement and queries the
    surface's. ``face``: each node's facet (flat, −1 where not placed) for a surface that
    places by walking from the parents' facets (:class:`WalkingPlacement`), else None.
    Returns (fronts placed, most Newton passes over a front)."""
    from preform.drape.kernels import net_kernels as kernels

    pos, status, residual, (lo_bound, hi_bound) = net.pos, net.status, net.residual, bounds
    d, tol_m, max_iterations = (
        float(settings.node_spacing_m),
        settings.tolerance_m,
        settings.max_iterations,
    )
    nj, start_flat, q_sa, q_sb, q_na, q_nb, last_front = layout
    longest = 4 * (max(int(q_na.max()), int(q_nb.max())) + 1) if len(q_sa) else 1
    members = np.empty((longest, 5), dtype=np.int64)
    newton_iterations = 0
    fronts = 0
    for k in range(2, last_front + 1):
        count = kernels.front_members(k, nj, start_flat, q_sa, q_sb, q_na, q_nb, status, members)
        if count == 0:
            if k > 2:
                # Every node of front k has a parent in front k − 1 off the generators.
                break
            continue
        fronts += 1
        front = members[:count]
        a, b, c = pos[front[:, 1]], pos[front[:, 2]], pos[front[:, 3]]
        at_p: FacePlacement | None = None
        if face is not None:
            # an exact placement that walks from the parents' facets (meshes)
            at_p = cast(WalkingPlacement, surface).place_nodes_from_faces(
                a, b, c, d, face[front[:, 1]], face[front[:, 2]], face[front[:, 3]]
            )
            p, st = at_p.points, np.asarray(at_p.status, dtype=np.int8).copy()
            face[front[:, 0]] = at_p.faces
        elif closed_form:
            # closed_form: the surface has its own exact placement
            p, st = cast(Any, surface).place_nodes(a, b, c, d)
            st = np.asarray(st, dtype=np.int8).copy()
        else:
            p, st, used = _solve_on_circle(surface, a, b, c, d, tol_m, max_iterations)
            newton_iterations = max(newton_iterations, used)
        p = np.ascontiguousarray(p, dtype=float)
        ok = st == _PLACED
        normals = np.full((count, 3), np.nan)
        dist = np.full(count, np.nan)
        if at_p is not None:
            # the walk has them already, on the facet it found
            normals[ok] = np.asarray(at_p.normals, dtype=float)[ok]
            dist[ok] = np.asarray(at_p.residual, dtype=float)[ok]
        elif ok.any():
            normals[ok] = surface.normal(p[ok])
            dist[ok] = surface.closest_point(p[ok])[1]
        kernels.finish_front(
            pos, status, residual, front, p, st, normals, dist, d, lo_bound, hi_bound
        )
        if at_p is not None:
            # The walk's residual is under its own spacing rule (the length along the surface
            # over a feature crease, where the chord is shorter than d by design).
            placed = status[front[:, 0]] == _PLACED
            residual[front[placed, 0]] = np.asarray(at_p.residual, dtype=float)[placed]
    return fronts, newton_iterations


class Fronts(NamedTuple):
    """How the fronts were filled (:func:`place_fronts`), for the result's ``info``: the
    placement, fronts and most Newton passes over one, wall and CPU time of the fill [s]."""

    placement: str
    fronts: int
    newton_iterations_max: int
    fill_seconds: float
    fill_cpu_seconds: float


def place_fronts(surface: Surface, settings: DrapeSettings, net: Net) -> Fronts:
    """Every node off the generators, front by front, in place in ``net``: in one compiled
    loop on a tool with compiled queries, else through the tool's own vectorised queries."""
    clock, cpu = time.perf_counter(), time.process_time()
    from preform.drape.kernels import net_kernels as kernels

    d, tol_m = float(settings.node_spacing_m), settings.tolerance_m
    compiled = isinstance(surface, CompiledQueries)
    closed_form = settings.use_closed_form and (
        isinstance(surface, ClosedFormPlacement) or (compiled and _compiled_closed_form(surface))
    )
    # a faceted tool that places nodes exactly by walking from the parents' facets (meshes);
    # it has no closed form to leave, so it walks whatever use_closed_form says
    walking = isinstance(surface, WalkingPlacement)
    (ni, nj), (i0, j0) = net.shape, net.start_index
    (bx0, by0, bz0), (bx1, by1, bz1) = surface.bounds
    lo_bound = np.array([bx0, by0, bz0]) - tol_m
    hi_bound = np.array([bx1, by1, bz1]) + tol_m
    quadrants = [
        (sa, sb, na, nb)
        for sa, na in ((1, ni - 1 - i0), (-1, i0))
        for sb, nb in ((1, nj - 1 - j0), (-1, j0))
        if na > 0 and nb > 0
    ]
    last_front = max((na + nb for _, _, na, nb in quadrants), default=1)
    q_sa, q_sb, q_na, q_nb = (
        np.array([q[col] for q in quadrants], dtype=np.int64) for col in range(4)
    )
    layout: NetLayout = (nj, net.start_flat, q_sa, q_sb, q_na, q_nb, last_front)
    if compiled and not walking and (not closed_form or _compiled_closed_form(surface)):
        # The whole fill in one compiled loop (preform.drape.kernels.net_kernels).
        kind, params = cast(CompiledQueries, surface).compiled_queries()
        fronts, newton_iterations = kernels.fill_fronts(
            net.pos, net.status, net.residual, *layout, d, tol_m, settings.max_iterations,
            lo_bound, hi_bound, checked_kind(kind), kernel_parameters(kind, params), closed_form,
        )  # fmt: skip
    elif walking and isinstance(surface, WalkingFill):
        # The whole fill in one compiled loop of the tool's own (a mesh's walk).
        fronts = surface.fill_fronts(
            net.pos, net.status, net.residual, _walking_faces(surface, net, d), layout, d,
            lo_bound, hi_bound,
        )  # fmt: skip
        newton_iterations = 0
    else:
        fronts, newton_iterations = _fill_fronts_python(
            surface, settings, net, layout, (lo_bound, hi_bound), closed_form,
            _walking_faces(surface, net, d) if walking else None,
        )  # fmt: skip
    placement = (
        "walking exact"
        if walking
        else "closed form"
        if closed_form
        else "newton on the constraint circle"
    )
    return Fronts(
        placement, fronts, newton_iterations, time.perf_counter() - clock, time.process_time() - cpu
    )


def _walking_faces(surface: Surface, net: Net, d: float) -> IntArray:
    """Each node's facet (flat, −1 where not placed) on a tool that places by walking from the
    parents' facets, seeded on the start and generators; their residuals are measured anew."""
    walker = cast(WalkingPlacement, surface)
    face = np.full(len(net.status), -1, dtype=np.int64)
    seeded = np.flatnonzero(net.status == _PLACED)
    face[seeded] = walker.locate_faces(net.pos[seeded])
    # The mesh spaces its generators by its own rule (the length along the surface over a
    # feature crease), so their spacing residual is measured by that rule too.
    on_gen, before = net.on_generators, net.before
    if on_gen.size:
        along = walker.spacings(net.pos[before], net.pos[on_gen], face[before], face[on_gen], d)
        dist = surface.closest_point(net.pos[on_gen])[1]
        net.residual[on_gen] = np.maximum(np.abs(along - d), dist)
    return face


# --------------------------------------------------------------------------------------------
# The fields, and the engine


def net_fields(
    net: Net, start: NetStart, settings: DrapeSettings, fronts: Fronts, clock: float
) -> DrapeResult:
    """The drape result of a placed net: its cell fields (shear, directions, part shares) and
    what the placement cost (``info``); ``clock`` is the drape's start [s, perf_counter]."""
    ni, nj = net.shape
    nodes, node_status = net.pos.reshape(ni, nj, 3), net.status.reshape(ni, nj)
    fields = cell_fields(nodes, node_status, trim=settings.trim)
    placed = net.status == _PLACED
    generators = settings.generators
    info: dict[str, object] = {
        "placement": fronts.placement,
        "generators": generators if isinstance(generators, str) else "plan polylines",
        "tolerance_m": settings.tolerance_m,
        "max_residual_m": float(net.residual[placed].max()) if placed.any() else 0.0,
        "newton_iterations_max": fronts.newton_iterations_max,
        "fronts": fronts.fronts,
        "seconds": time.perf_counter() - clock,
        "fill_seconds": fronts.fill_seconds,
        "fill_cpu_seconds": fronts.fill_cpu_seconds,
    }
    return DrapeResult(
        nodes=nodes,
        status=node_status,
        residual=net.residual.reshape(ni, nj),
        start_index=net.start_index,
        node_spacing=float(settings.node_spacing_m),
        generator_angle=start.generator_angle,
        orientation=start.orientation,
        info=info,
        **fields,
    )


def drape(surface: Surface, settings: DrapeSettings | None = None, **keywords: Any) -> DrapeResult:
    """Drape a ply over ``surface`` (any :class:`~preform.drape.engine.surface.Surface`) as a
    pin-jointed net: :func:`place_start`, :func:`place_generators`, :func:`place_fronts`,
    :func:`net_fields`.

    ``settings``: a :class:`~preform.drape.engine.settings.DrapeSettings` (node spacing, ply, start,
    orientation, generator angle, generators, trim, tolerances, sub-steps, closed forms, in SI
    units); ``keywords`` are its fields, given alone or replacing those of ``settings``.

    Raises :class:`DrapeError` for a set-up that cannot give a net at all (start off the tool,
    start outside the ply, α outside (0, π), d ≤ 0). Everything else, including a net that
    runs off the tool, comes back as node statuses.
    """
    clock = time.perf_counter()
    if settings is None:
        settings = DrapeSettings(**keywords)
    elif keywords:
        settings = dataclasses.replace(settings, **keywords)
    start = place_start(surface, settings)
    net = place_generators(surface, settings, start)
    fronts = place_fronts(surface, settings, net)
    return net_fields(net, start, settings, fronts, clock)
