"""Compiled kernels of the pin-jointed net: node placement and the wavefront fill.

Each kernel exists once, here, compiled with numba (``cache=True``: compiled once per
install). ``preform.drape.engine.net`` imports this module only when it drapes, so commands that do not
drape never import numba.

The per-node steps are plain scalar functions:

- :func:`_sphere_node`: the closed-form node on a sphere (PHYSICS §6); the plate's is
  ``preform.drape.kernels.surface_kernels.plane_node``, and every tool's closest point and normal
  ``preform.drape.kernels.surface_kernels`` (:func:`_query` picks them);
- :func:`_circle_frame` and :func:`_newton_update`: the general placement on the circle where
  the two distance spheres meet (``preform.drape.engine.net``'s module doc): the start where the
  circle crosses the tangent plane at the guess, then one damped Newton step along the circle
  at a time, given the surface's closest point and normal; the angle is carried as the
  offset (r cos φ, r sin φ) and turned without a sine, cosine or arctangent;
- :func:`_front_members`: which nodes front k holds and which are ready;
- :func:`_check_node` and :func:`_write_node`: the checks every new node goes through (past
  the tool's bounds, folded cell, residual) and its write into the net.

Two drivers use them. For a surface with compiled queries
(:class:`~preform.drape.engine.compiled_surface.CompiledQueries`), :func:`fill_fronts` fills the whole
net in one compiled loop (row by row within each quadrant); a mesh has its own
(``preform.plugins.surfaces.mesh_kernels``). For any other surface (a plugin's tool) the
front loop stays in Python and calls the vectorised wrappers below once per front, with the
surface's own vectorised ``closest_point``/``normal`` in between; the per-node arithmetic is
the same code.

The per-node steps are inlined into the loops (``_per_node``) and take points, frames and the
tool's parameters as tuples, not arrays: numba reference-counts an array handed to a function
(an atomic add and subtract), which at one call per node cost more than half of the fill. A
new kind of compiled surface gets its code in ``compiled_surface`` and its query in
``surface_kernels`` (closest point, unit normal, distance), reading its parameters by
constant index: the fill hands it the ``MAX_PARAMS``-tuple of :func:`_param_tuple`.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from preform.base.kernel_cache import cache_by_content
from preform.drape.engine.compiled_surface import PLANE, SPHERE, TRIMMED_SPHERE
from preform.drape.engine.result import NodeStatus
from preform.drape.kernels import surface_kernels

#: The preform modules compiled into these kernels (inlined functions, frozen constants):
#: their sources are part of the key these kernels are cached under
#: (``preform.base.kernel_cache``).
COMPILED_IN = (
    "preform.drape.kernels.surface_kernels",
    "preform.drape.engine.compiled_surface",
    "preform.drape.engine.result",
)
cache_by_content(__name__)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
StatusArray = NDArray[np.int8]
#: A point or vector (x, y, z) [m] held in registers: the per-node steps take and return
#: tuples, not array views (see ``_per_node``).
Vec = tuple[float, float, float]

_PLACED = np.int8(NodeStatus.PLACED)
_OFF_TOOL = np.int8(NodeStatus.OFF_TOOL)
_NO_INTERSECTION = np.int8(NodeStatus.NO_INTERSECTION)
_FOLDED = np.int8(NodeStatus.FOLDED)
_NOT_REACHED = np.int8(NodeStatus.NOT_REACHED)

#: As ``preform.plugins.surfaces.basic._EDGE_TOLERANCE``: points this fraction of the node
#: spacing past a trimmed sphere's floor still count as on it.
_EDGE_TOLERANCE = 1e-9

# error_model="numpy": a division by zero gives inf/NaN (handled where it can occur) instead
# of raising, as in the vectorised numpy code these kernels replace.
_jit = numba.njit(cache=True, error_model="numpy", fastmath=False)
# The per-node steps are inlined into the loops that call them (numba's own inlining, before
# its reference counting): an array handed to a function that is not inlined is reference
# counted at every call, an atomic add and subtract per array per node that cost more than
# half of the fill.
_per_node = numba.njit(cache=True, error_model="numpy", fastmath=False, inline="always")


@_per_node
def _row(array: FloatArray, i: int) -> Vec:
    """Row i of an (m, 3) array as a tuple."""
    return array[i, 0], array[i, 1], array[i, 2]


#: Machine epsilon.
_EPS = float(np.finfo(float).eps)

#: Most parameters a kind of compiled surface may take (``compiled_surface``).
MAX_PARAMS = 16


@_jit
def _param_tuple(params: FloatArray):
    """A surface's parameters (as ``compiled_surface.kernel_parameters`` gives them) as a
    tuple of ``MAX_PARAMS`` numbers (NaN past its own): what the fill hands its per-node steps,
    held in registers (an array would be reference counted at every node). The queries index
    it as they would the array."""
    values = params.ravel()  # a sphere's vector or another tool's row (kernel_parameters)
    if values.shape[0] > MAX_PARAMS:
        raise ValueError("a compiled surface takes at most MAX_PARAMS parameters")
    p = np.full(MAX_PARAMS, np.nan)
    p[: values.shape[0]] = values
    return (
        p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7],
        p[8], p[9], p[10], p[11], p[12], p[13], p[14], p[15],
    )  # fmt: skip


# --------------------------------------------------------------------------------------------
# Compiled surface queries


@_per_node
def _query(kind: int, params, x: float, y: float, z: float):
    """The closest point of the tool of ``kind`` to (x, y, z) [m], the unit outward normal
    there and the distance [m], from its parameters as a tuple (:func:`_param_tuple`): the
    sphere's query inlined here, any other tool's called (``surface_kernels``)."""
    if kind == SPHERE or kind == TRIMMED_SPHERE:
        return surface_kernels._sphere(kind, params, x, y, z)
    return surface_kernels._other_kinds(kind, params, x, y, z)


# --------------------------------------------------------------------------------------------
# The closed-form node on a sphere


@_per_node
def _sphere_node(kind: int, params: FloatArray, a: Vec, b: Vec, c: Vec, spacing: float):
    """Node at chord ``spacing`` from A and B on the sphere, away from C; and its status.

    Relative to the centre, P·A = P·B = R² − d²/2 and |P| = R: P lies in the plane spanned by
    s = A + B and n = A × B, P = h·s + k·n with h = (2R² − d²)/|s|² (then P·A = P·B as
    required) and k² |n|² = R² − h²|s|² (then |P| = R); of the two roots the one on the far
    side of the plane (0, A, B) from C is the node. Written with squared lengths: one square
    root and two divisions a node, the fill's largest cost (they share one unit of the core)."""
    ox, oy, oz, r = params[0], params[1], params[2], params[3]
    pax, pay, paz = a[0] - ox, a[1] - oy, a[2] - oz
    pbx, pby, pbz = b[0] - ox, b[1] - oy, b[2] - oz
    pcx, pcy, pcz = c[0] - ox, c[1] - oy, c[2] - oz
    sx, sy, sz = pax + pbx, pay + pby, paz + pbz
    nx = pay * pbz - paz * pby
    ny = paz * pbx - pax * pbz
    nz = pax * pby - pay * pbx
    n2 = nx * nx + ny * ny + nz * nz
    chord = 2.0 * r * r - spacing * spacing
    h = chord / (sx * sx + sy * sy + sz * sz)
    off2 = r * r - h * chord  # R² − (h|s|)²
    limit = 1e-12 * r * spacing
    if not (off2 >= 0.0 and n2 > limit * limit):
        return np.nan, np.nan, np.nan, _NO_INTERSECTION
    away = -1.0 if pcx * nx + pcy * ny + pcz * nz > 0.0 else 1.0
    k = away * math.sqrt(off2 / n2)
    px = h * sx + k * nx + ox
    py = h * sy + k * ny + oy
    pz = h * sz + k * nz + oz
    if kind == TRIMMED_SPHERE:
        if not pz >= params[4] - _EDGE_TOLERANCE * spacing:
            return np.nan, np.nan, np.nan, _OFF_TOOL
    elif not math.isfinite(px):
        return np.nan, np.nan, np.nan, _OFF_TOOL
    return px, py, pz, _PLACED


@_per_node
def _closed_form_normal(kind: int, params, x: float, y: float, z: float):
    """The outward normal direction at a closed-form node (any positive multiple of the unit
    normal: the fold check reads only its sign) and the distance to the tool [m].

    On a sphere (above a trimmed sphere's floor, with a margin) that is the offset from the
    centre and | |p − o| − R |, one square root where the full query (``_query``) takes two
    and three divisions; elsewhere (below the floor, the plate) the full query."""
    ox, oy, oz, r = params[0], params[1], params[2], params[3]
    if kind != SPHERE and not (kind == TRIMMED_SPHERE and z > params[4] + 1e-9 * r):
        _, _, _, nx, ny, nz, dist = _query(kind, params, x, y, z)
        return nx, ny, nz, dist
    rx, ry, rz = x - ox, y - oy, z - oz
    return rx, ry, rz, abs(math.sqrt(rx * rx + ry * ry + rz * rz) - r)


@_per_node
def _closed_form_node(kind: int, params, a: Vec, b: Vec, c: Vec, spacing: float):
    """The closed-form node of a tool that has one (``CLOSED_FORM_KINDS``): the sphere's, or
    the plate's (``surface_kernels.plane_node``); parameters as :func:`_param_tuple` gives."""
    if kind == PLANE:
        return surface_kernels.plane_node(
            params, a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], spacing
        )
    return _sphere_node(kind, params, a, b, c, spacing)


@_jit
def closed_form_nodes(
    kind: int, params: FloatArray, a: FloatArray, b: FloatArray, c: FloatArray, spacing: float
):
    """The tools' ``place_nodes`` (sphere, plate) over m nodes: points (m, 3) [m] (NaN unless
    placed) and NodeStatus codes (m,); ``params`` as ``kernel_parameters`` gives them."""
    par = _param_tuple(params)
    m = a.shape[0]
    points = np.empty((m, 3))
    status = np.empty(m, dtype=np.int8)
    for i in range(m):
        px, py, pz, st = _closed_form_node(kind, par, _row(a, i), _row(b, i), _row(c, i), spacing)
        points[i, 0], points[i, 1], points[i, 2] = px, py, pz
        status[i] = st
    return points, status


# --------------------------------------------------------------------------------------------
# The general node: Newton on the constraint circle

#: Frame of one node's circle: mid (3), a1 (3), a2 (3), radius; see ``_circle_frame``.
FRAME = 10


@_per_node
def _circle_frame(a: Vec, b: Vec, c: Vec, guess: Vec, n0: Vec, spacing: float):
    """The frame of the node at chord ``spacing`` from a and b, away from c: the circle
    P(φ) = M + r(cos φ·a1 + sin φ·a2), a1 the surface normal ``n0`` (at ``guess``, the closest
    point to a + b − c) seen from the chord, a2 pointing away from c, as the tuple (M, a1, a2,
    r) (``FRAME`` numbers). Returns (the start as its offset from M along a1 and a2, r·cos φ
    and r·sin φ [m], both NaN when there is no circle (|AB| ≥ 2d or a degenerate frame); the
    frame).

    The start is where the circle crosses the tangent plane at ``guess`` on the side away
    from c. On a pin-jointed net (a Chebyshev net: ∂²r/∂u∂v is normal to the surface) the
    node differs from the parallelogram point a + b − c by a mostly normal offset, so the
    guess is within O(d³) of it along the surface and the crossing within O(d⁶) of the
    surface: the first point on the circle is the node, with no Newton step, on smooth tools
    at the usual spacings (the sphere at 145² and finer: every node). Where the circle misses
    that plane (|cos φ| > 1, a tangency or an edge of the tool) the start is the guess's
    direction from M in the circle's plane instead, φ kept in [0, π]."""
    mx, my, mz = 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])
    ex, ey, ez = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    half2 = 0.25 * (ex * ex + ey * ey + ez * ez)
    radius2 = spacing * spacing - half2
    # one division and three products per unit vector (the divisions and square roots bound
    # the fill; a product by the reciprocal differs from the quotient by an ulp at most)
    inv_e = 1.0 / math.sqrt(4.0 * half2)
    ex, ey, ez = ex * inv_e, ey * inv_e, ez * inv_e
    along = n0[0] * ex + n0[1] * ey + n0[2] * ez
    a1x, a1y, a1z = n0[0] - along * ex, n0[1] - along * ey, n0[2] - along * ez
    a1_len2 = a1x * a1x + a1y * a1y + a1z * a1z
    inv_a1 = 1.0 / math.sqrt(a1_len2)
    a1x, a1y, a1z = a1x * inv_a1, a1y * inv_a1, a1z * inv_a1
    a2x = ey * a1z - ez * a1y
    a2y = ez * a1x - ex * a1z
    a2z = ex * a1y - ey * a1x
    if (c[0] - mx) * a2x + (c[1] - my) * a2y + (c[2] - mz) * a2z > 0.0:
        a2x, a2y, a2z = -a2x, -a2y, -a2z
    radius = math.sqrt(max(radius2, 0.0))
    frame = (mx, my, mz, a1x, a1y, a1z, a2x, a2y, a2z, radius)
    rx, ry, rz = guess[0] - mx, guess[1] - my, guess[2] - mz
    # (P(φ) − guess)·n0 = 0 with a2·n0 = 0 and a1·n0 = |n0 − (n0·e)e| (unit n0 or not):
    # r cos φ = (guess − M)·n0 / |n0 − (n0·e)e|, r sin φ ≥ 0 (the side away from c)
    p1 = (rx * n0[0] + ry * n0[1] + rz * n0[2]) * inv_a1
    if p1 * p1 <= radius2:
        p2 = math.sqrt(radius2 - p1 * p1)
    else:
        along_a1 = rx * a1x + ry * a1y + rz * a1z
        along_a2 = rx * a2x + ry * a2y + rz * a2z
        length = math.sqrt(along_a1 * along_a1 + along_a2 * along_a2)
        if along_a2 < 0.0 or length == 0.0:
            p1, p2 = radius, 0.0
        else:
            to_circle = radius / length
            p1, p2 = along_a1 * to_circle, along_a2 * to_circle
    if not (radius2 > 0.0 and math.isfinite(a1x) and math.isfinite(p1)):
        return np.nan, np.nan, frame
    return p1, p2, frame


@_per_node
def _frame_row(frames: FloatArray, i: int):
    """Row i of an (m, FRAME) array of frames as a frame tuple."""
    f = frames[i]
    return f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8], f[9]


@_per_node
def _on_circle(frame, p1: float, p2: float) -> Vec:
    """P(φ) = M + p1·a1 + p2·a2 [m] of a frame, the angle given as the offset (p1, p2) =
    (r cos φ, r sin φ) [m] from M (how the Newton step carries it, see ``_newton_update``)."""
    return (
        frame[0] + p1 * frame[3] + p2 * frame[6],
        frame[1] + p1 * frame[4] + p2 * frame[7],
        frame[2] + p1 * frame[5] + p2 * frame[8],
    )


#: Outcomes of one Newton update.
_GOING, _DONE, _FAILED_OFF_TOOL, _FAILED = 0, 1, 2, 3


@_per_node
def _newton_update(
    frame,
    p1: float,
    p2: float,
    x: float,
    y: float,
    z: float,
    fx: float,
    fy: float,
    fz: float,
    nx: float,
    ny: float,
    nz: float,
    dist: float,
    tolerance_m: float,
    last_try: bool,
):
    """One damped Newton step on the signed distance g = (P − foot)·n from the surface along
    the circle, given the angle as the offset (p1, p2) = (r cos φ, r sin φ) [m] of P(φ) =
    (x, y, z) from M, the closest point ``foot`` of P, its normal and distance. Returns (new
    p1, new p2, outcome).

    The step is Newton's in t = tan(Δφ/2), the half-angle tangent of the turn from φ: the turn
    by cos Δφ = (1 − t²)/(1 + t²), sin Δφ = 2t/(1 + t²) keeps the point on the circle with one
    division and no sine or cosine, and since dφ/dt = 2 at t = 0 the step t = −g/(2 g'(φ)) is
    half the step in φ and converges as fast. Damped to |Δφ| ≤ 2·atan(0.25) ≈ 0.49 rad (|t| ≤
    0.25, the step in φ clamped to ±0.5 rad); φ stays in [0, π] (sin φ ≥ 0, the side away
    from the opposite node)."""
    if dist <= tolerance_m:
        return p1, p2, _DONE
    ox, oy, oz = x - fx, y - fy, z - fz
    g = ox * nx + oy * ny + oz * nz
    n_a1 = nx * frame[3] + ny * frame[4] + nz * frame[5]
    n_a2 = nx * frame[6] + ny * frame[7] + nz * frame[8]
    slope = -p2 * n_a1 + p1 * n_a2  # g'(φ) = r(−sin φ n·a1 + cos φ n·a2)
    step = -g / slope
    if math.isnan(step):
        step = 0.0
    step = min(max(step, -0.5), 0.5)
    t = 0.5 * step
    w = 1.0 / (1.0 + t * t)
    cos_t, sin_t = (1.0 - t * t) * w, 2.0 * t * w
    new_p1 = p1 * cos_t - p2 * sin_t
    new_p2 = p2 * cos_t + p1 * sin_t
    # Stuck: the turn is below 1e-15·π rad, or g is zero to its rounding (the offset from the
    # foot is tangential: past an edge of the tool, where Newton then only turns by rounding
    # noise); past φ = 0 or φ = π (|Δφ| < π/2) the point stops there, stuck if it was there.
    noise = 8.0 * _EPS * (abs(x) + abs(y) + abs(z) + abs(fx) + abs(fy) + abs(fz))
    stuck = abs(step) <= 1e-15 * math.pi or abs(g) <= noise
    if new_p2 < 0.0:
        r = frame[9]
        new_p1, new_p2 = (r if new_p1 > 0.0 else -r), 0.0
        stuck = p2 <= 1e-15 * math.pi * r or abs(g) <= noise
    if not (stuck or last_try):
        return new_p1, new_p2, _GOING
    # A point whose closest point is an edge of the tool has an offset with a tangential
    # part; an interior closest point has a purely normal one.
    tx, ty, tz = ox - g * nx, oy - g * ny, oz - g * nz
    if math.sqrt(tx * tx + ty * ty + tz * tz) > 0.5 * dist:
        return new_p1, new_p2, _FAILED_OFF_TOOL
    return new_p1, new_p2, _FAILED


@_jit
def circle_frames(
    a: FloatArray, b: FloatArray, c: FloatArray, guess: FloatArray, n0: FloatArray, spacing: float
):
    """Frames (m, FRAME) and starting angles (m, 2) of m nodes, as offsets (r cos φ, r sin φ)
    [m] from the circle's centre (NaN: no circle)."""
    m = a.shape[0]
    frames = np.empty((m, FRAME))
    angle = np.empty((m, 2))
    for i in range(m):
        angle[i, 0], angle[i, 1], f = _circle_frame(
            _row(a, i), _row(b, i), _row(c, i), _row(guess, i), _row(n0, i), spacing
        )
        frames[i, 0], frames[i, 1], frames[i, 2], frames[i, 3], frames[i, 4] = f[:5]
        frames[i, 5], frames[i, 6], frames[i, 7], frames[i, 8], frames[i, 9] = f[5:]
    return frames, angle


@_jit
def circle_points(frames: FloatArray, angle: FloatArray, rows: IntArray) -> FloatArray:
    """P(φ) (len(rows), 3) [m] of the nodes ``rows``, their angles as (r cos φ, r sin φ)."""
    out = np.empty((rows.shape[0], 3))
    for k in range(rows.shape[0]):
        i = rows[k]
        out[k, 0], out[k, 1], out[k, 2] = _on_circle(
            _frame_row(frames, i), angle[i, 0], angle[i, 1]
        )
    return out


@_jit
def newton_updates(
    rows: IntArray,
    x: FloatArray,
    foot: FloatArray,
    normal: FloatArray,
    dist: FloatArray,
    frames: FloatArray,
    angle: FloatArray,
    points: FloatArray,
    status: StatusArray,
    tolerance_m: float,
    last_try: bool,
) -> IntArray:
    """One Newton update of the nodes ``rows`` (their P(φ) ``x``, closest points, normals and
    distances given; their angles (r cos φ, r sin φ) updated in ``angle``); writes placed
    ``points`` and ``status`` and returns the rows still going."""
    going = np.empty(rows.shape[0], dtype=np.int64)
    count = 0
    for k in range(rows.shape[0]):
        i = rows[k]
        angle[i, 0], angle[i, 1], outcome = _newton_update(
            _frame_row(frames, i),
            angle[i, 0],
            angle[i, 1],
            x[k, 0],
            x[k, 1],
            x[k, 2],
            foot[k, 0],
            foot[k, 1],
            foot[k, 2],
            normal[k, 0],
            normal[k, 1],
            normal[k, 2],
            dist[k],
            tolerance_m,
            last_try,
        )
        if outcome == _DONE:
            points[i, 0], points[i, 1], points[i, 2] = x[k, 0], x[k, 1], x[k, 2]
            status[i] = _PLACED
        elif outcome == _FAILED_OFF_TOOL:
            status[i] = _OFF_TOOL
        elif outcome == _GOING:
            going[count] = i
            count += 1
    return going[:count]


@_per_node
def _newton_node(
    kind: int,
    params: FloatArray,
    a: Vec,
    b: Vec,
    c: Vec,
    spacing: float,
    tolerance_m: float,
    max_iterations: int,
):
    """The general node for a surface with compiled queries: (x, y, z, status, iterations,
    nx, ny, nz, distance), the last four the surface normal at the node and its distance to
    the tool (from the query that accepted it)."""
    gx, gy, gz, n0x, n0y, n0z, _ = _query(
        kind, params, a[0] + b[0] - c[0], a[1] + b[1] - c[1], a[2] + b[2] - c[2]
    )
    p1, p2, frame = _circle_frame(a, b, c, (gx, gy, gz), (n0x, n0y, n0z), spacing)
    nan = np.nan
    if math.isnan(p1):
        return nan, nan, nan, _NO_INTERSECTION, 0, nan, nan, nan, nan
    for used in range(1, max_iterations + 1):
        x, y, z = _on_circle(frame, p1, p2)
        fx, fy, fz, nx, ny, nz, dist = _query(kind, params, x, y, z)
        p1, p2, outcome = _newton_update(
            frame, p1, p2, x, y, z, fx, fy, fz, nx, ny, nz, dist, tolerance_m,
            used == max_iterations,
        )  # fmt: skip
        if outcome == _DONE:
            return x, y, z, _PLACED, used, nx, ny, nz, dist
        if outcome == _FAILED_OFF_TOOL:
            return nan, nan, nan, _OFF_TOOL, used, nan, nan, nan, nan
        if outcome == _FAILED:
            return nan, nan, nan, _NO_INTERSECTION, used, nan, nan, nan, nan
    return nan, nan, nan, _NO_INTERSECTION, max_iterations, nan, nan, nan, nan


# --------------------------------------------------------------------------------------------
# The fronts


@_per_node
def _ready(status: StatusArray, node: int, ia: int, ib: int, ic: int) -> bool:
    """Whether a node is ready to place: not reached yet, its three parents placed."""
    return (
        status[node] == _NOT_REACHED
        and status[ia] == _PLACED
        and status[ib] == _PLACED
        and status[ic] == _PLACED
    )


@_per_node
def _front_members(
    k: int,
    nj: int,
    start_flat: int,
    q_sa: IntArray,
    q_sb: IntArray,
    q_na: IntArray,
    q_nb: IntArray,
    status: StatusArray,
    members: IntArray,
) -> int:
    """The ready nodes of front k (|i − i0| + |j − j0| = k, all quadrants), written to
    ``members`` rows as (node, parent along u, parent along v, opposite corner, orientation);
    returns their count. Ready: not reached yet, its three parents placed.

    Node (i0 + sa·a, j0 + sb·b) with a + b = k has flat index i0·nj + j0 + sb·k +
    a·(sa·nj − sb): each quadrant's part of a front is an arithmetic run."""
    count = 0
    for q in range(q_sa.shape[0]):
        a_lo = max(1, k - q_nb[q])
        a_hi = min(q_na[q], k - 1)
        da, db = q_sa[q] * nj, q_sb[q]
        for a_off in range(a_lo, a_hi + 1):
            node = start_flat + q_sb[q] * k + a_off * (da - db)
            ia, ib = node - da, node - db
            ic = ia - db
            if _ready(status, node, ia, ib, ic):
                members[count, 0], members[count, 1] = node, ia
                members[count, 2], members[count, 3] = ib, ic
                # the cell this node completes is oriented +u × +v whatever the quadrant
                members[count, 4] = q_sa[q] * q_sb[q]
                count += 1
    return count


@_jit
def front_members(
    k: int,
    nj: int,
    start_flat: int,
    q_sa: IntArray,
    q_sb: IntArray,
    q_na: IntArray,
    q_nb: IntArray,
    status: StatusArray,
    members: IntArray,
) -> int:
    """:func:`_front_members` for the Python front loop."""
    return _front_members(k, nj, start_flat, q_sa, q_sb, q_na, q_nb, status, members)


@_per_node
def _check_node(
    p: Vec,
    st: np.int8,
    a: Vec,
    b: Vec,
    c: Vec,
    orient: int,
    nx: float,
    ny: float,
    nz: float,
    dist: float,
    spacing: float,
    lo: Vec,
    hi: Vec,
):
    """The checks every new node p goes through, from its parents a (along u), b (along v)
    and the opposite corner c: (status, residual). OFF_TOOL past the tool's bounds, FOLDED
    where the cell it completes (oriented ``orient``·(+u × +v)) faces against the surface
    normal (nx, ny, nz) at it (any positive multiple of the unit normal), else PLACED with its residual max(|PA| − d, |PB| − d, distance
    ``dist`` to the tool) [m] (0 when not placed)."""
    px, py, pz = p
    if st == _PLACED:
        past = px < lo[0] or py < lo[1] or pz < lo[2] or px > hi[0] or py > hi[1] or pz > hi[2]
        ux, uy, uz = px - c[0], py - c[1], pz - c[2]
        vx, vy, vz = a[0] - b[0], a[1] - b[1], a[2] - b[2]
        cx = uy * vz - uz * vy
        cy = uz * vx - ux * vz
        cz = ux * vy - uy * vx
        if past:
            st = _OFF_TOOL
        elif orient * (cx * nx + cy * ny + cz * nz) <= 0.0:
            st = _FOLDED
    if st != _PLACED:
        return st, 0.0
    # |PA| − d = (|PA|² − d²)/(|PA| + d), and |PA| + d = 2d to the residual's own relative size:
    # no square root, and the same rounding (an ulp of d²/2d against one of |PA|)
    to_a2 = (px - a[0]) ** 2 + (py - a[1]) ** 2 + (pz - a[2]) ** 2
    to_b2 = (px - b[0]) ** 2 + (py - b[1]) ** 2 + (pz - b[2]) ** 2
    d2, over_2d = spacing * spacing, 0.5 / spacing
    return st, max(abs(to_a2 - d2) * over_2d, abs(to_b2 - d2) * over_2d, dist)


@_per_node
def _write_node(
    pos: FloatArray,
    status: StatusArray,
    residual: FloatArray,
    node: int,
    p: Vec,
    st: np.int8,
    res: float,
) -> None:
    """Write a checked node: its status, and where placed its position and residual."""
    if st == _PLACED:
        pos[node, 0], pos[node, 1], pos[node, 2] = p
        residual[node] = res
    status[node] = st


@_jit
def finish_front(
    pos: FloatArray,
    status: StatusArray,
    residual: FloatArray,
    members: IntArray,
    points: FloatArray,
    point_status: StatusArray,
    normals: FloatArray,
    dist: FloatArray,
    spacing: float,
    lo: FloatArray,
    hi: FloatArray,
) -> None:
    """:func:`_check_node` over one front placed by the Python loop (normals and distances of
    the placed points given; anything where the status is not PLACED)."""
    low, high = (lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2])
    for i in range(members.shape[0]):
        node, ia, ib, ic = members[i, 0], members[i, 1], members[i, 2], members[i, 3]
        p = _row(points, i)
        st, res = _check_node(
            p, point_status[i], _row(pos, ia), _row(pos, ib), _row(pos, ic), members[i, 4],
            normals[i, 0], normals[i, 1], normals[i, 2], dist[i], spacing, low, high,
        )  # fmt: skip
        _write_node(pos, status, residual, node, p, st, res)


@_per_node
def _fronts_placed(ready_on_front: NDArray[np.bool_], last_front: int) -> int:
    """Fronts placed by a row-by-row sweep that marked each front holding a ready node, as the
    front-by-front loop counts them: it stops at the first front past the second with no ready
    node (no later front can have one)."""
    fronts = 0
    for k in range(2, last_front + 1):
        if not ready_on_front[k]:
            if k > 2:
                break
            continue
        fronts += 1
    return fronts


@_jit
def fill_fronts(
    pos: FloatArray,
    status: StatusArray,
    residual: FloatArray,
    nj: int,
    start_flat: int,
    q_sa: IntArray,
    q_sb: IntArray,
    q_na: IntArray,
    q_nb: IntArray,
    last_front: int,
    spacing: float,
    tolerance_m: float,
    max_iterations: int,
    lo: FloatArray,
    hi: FloatArray,
    kind: int,
    params: FloatArray,
    closed_form: bool,
):
    """Every front of the net on a surface with compiled queries, in place on ``pos``,
    ``status`` and ``residual`` (flat, ni·nj). ``closed_form``: the tool's closed-form node,
    else Newton on the constraint circle. Returns (fronts placed, most Newton passes over a
    front), as the Python loop counts them.

    A node needs only its three parents (i∓1, j), (i, j∓1), (i∓1, j∓1), so each quadrant is
    swept row by row, along memory, instead of front by front: every node sees the same
    parents, so the net is the same, and the sweep does not jump a row of the net per node."""
    ready_on_front = np.zeros(last_front + 2, dtype=np.bool_)
    low, high = (lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2])
    par = _param_tuple(params)
    most_used = 0
    for q in range(q_sa.shape[0]):
        da, db = q_sa[q] * nj, q_sb[q]
        orient = q_sa[q] * q_sb[q]  # the cell is oriented +u × +v whatever the quadrant
        na, nb = q_na[q], q_nb[q]
        for a_off in range(1, na + 1):
            row = start_flat + a_off * da
            for b_off in range(1, nb + 1):
                node = row + b_off * db
                ia, ib = node - da, node - db
                ic = ia - db
                if not _ready(status, node, ia, ib, ic):
                    continue
                ready_on_front[a_off + b_off] = True
                a, b, c = _row(pos, ia), _row(pos, ib), _row(pos, ic)
                if closed_form:
                    px, py, pz, st = _closed_form_node(kind, par, a, b, c, spacing)
                    nx = ny = nz = dist = np.nan
                    if st == _PLACED:
                        nx, ny, nz, dist = _closed_form_normal(kind, par, px, py, pz)
                else:
                    px, py, pz, st, used, nx, ny, nz, dist = _newton_node(
                        kind, par, a, b, c, spacing, tolerance_m, max_iterations
                    )
                    most_used = max(most_used, used)
                p = (px, py, pz)
                st, res = _check_node(p, st, a, b, c, orient, nx, ny, nz, dist, spacing, low, high)
                # written here, not by _write_node: the arrays handed even to an inlined
                # step were reference counted per node
                if st == _PLACED:
                    pos[node, 0], pos[node, 1], pos[node, 2] = px, py, pz
                    residual[node] = res
                status[node] = st
    fronts = _fronts_placed(ready_on_front, last_front)
    # the vectorised loop makes one more pass over a front to find no node left, unless capped
    newton_max = 0 if closed_form or fronts == 0 else min(most_used + 1, max_iterations)
    return fronts, newton_max
