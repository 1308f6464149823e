"""Compiled closest-point and normal queries of the analytic tools, one per kind code.

The kind codes and parameter vectors are defined in :mod:`preform.drape.engine.compiled_surface`
(which imports no numba); each tool's ``compiled_queries()`` says which it is. :func:`query`
answers one point for any kind, inside the compiled net kernels (``preform.drape.kernels.net_kernels``)
and, through :func:`query_points`, for the tools' own vectorised ``closest_point`` and
``normal``: each query exists once, here. This module is imported only when a tool is queried
or a net draped, so commands that do not drape never import numba.

Every query returns (closest point x, y, z [m], unit outward normal there, distance [m]). A
tool that ends at an edge (a rim, a flange edge, a floor) answers a point beyond it with the
nearest point of the edge, as its class documents.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from preform.base.kernel_cache import cache_by_content
from preform.drape.engine.compiled_surface import (
    CONE,
    CYLINDER,
    ELLIPSOID_DOME,
    FLANGED_HEMISPHERE,
    PARABOLOID_DOME,
    PLANE,
    TRIMMED_SPHERE,
)
from preform.drape.engine.result import NodeStatus

#: The preform modules compiled into these kernels (inlined functions, frozen constants):
#: their sources are part of the key these kernels are cached under
#: (``preform.base.kernel_cache``).
COMPILED_IN = ("preform.drape.engine.compiled_surface", "preform.drape.engine.result")
cache_by_content(__name__)

FloatArray = NDArray[np.float64]

_PLACED = np.int8(NodeStatus.PLACED)
_OFF_TOOL = np.int8(NodeStatus.OFF_TOOL)
_NO_INTERSECTION = np.int8(NodeStatus.NO_INTERSECTION)

#: As ``preform.plugins.surfaces.basic._EDGE_TOLERANCE``: points this fraction of the node
#: spacing past a trimmed tool's edge still count as on it.
_EDGE_TOLERANCE = 1e-9

#: Machine epsilon: the root solves stop when a step is a few ulps of the answer.
_EPS = float(np.finfo(float).eps)

# error_model="numpy": a division by zero gives inf/NaN (handled where it can occur) instead
# of raising, as in the vectorised numpy code these queries replace.
_jit = numba.njit(cache=True, error_model="numpy", fastmath=False)
_jit_inline = numba.njit(cache=True, error_model="numpy", fastmath=False, inline="always")


@_jit
def _unit_scaled(x: float, y: float, z: float):
    """(x, y, z) / |(x, y, z)|, scaled by the largest component first when the squares would
    be subnormal (their root inexact); (0, 0, 1) for the zero vector."""
    length = math.sqrt(x * x + y * y + z * z)
    if length < 1e-100:
        largest = max(abs(x), abs(y), abs(z))
        if largest == 0.0:
            return 0.0, 0.0, 1.0
        x, y, z = x / largest, y / largest, z / largest
        length = math.sqrt(x * x + y * y + z * z)
    return x / length, y / length, z / length


# --------------------------------------------------------------------------------------------
# Sphere (SPHERE, TRIMMED_SPHERE): centre x, y, z, radius [, floor z]


# Inlined where it is called (numba IR): ``query`` then holds the sphere's code itself, and the
# fill as many call levels from it as before the other tools had queries (measured: one level
# more made the closed-form sphere fill ~25 % slower).
@_jit_inline
def _sphere(kind: int, params: FloatArray, x: float, y: float, z: float):
    rx, ry, rz = x - params[0], y - params[1], z - params[2]
    radius = params[3]
    length = math.sqrt(rx * rx + ry * ry + rz * rz)
    if length >= 1e-100:
        # One division (the reciprocal's products differ from the quotients by an ulp at
        # most): the Newton fill queries twice a node, and divisions and square roots bound it.
        inv = 1.0 / length
        ux, uy, uz = rx * inv, ry * inv, rz * inv
    else:
        ux, uy, uz = _unit_scaled(rx, ry, rz)
    if kind == TRIMMED_SPHERE:
        floor = (params[4] - params[2]) / radius
        if uz < floor:
            # Below the floor: the nearest point is on the edge circle at height floor·R.
            # hypot: the squares of a tiny horizontal offset would be subnormal, their root
            # inexact, and the edge direction not a unit vector
            flat = math.hypot(ux, uy)
            if flat > 0.0:
                fx, fy = ux / flat, uy / flat
            else:
                fx, fy = 1.0, 0.0
            ring = math.sqrt(1.0 - floor * floor)
            ux, uy, uz = ring * fx, ring * fy, floor
            qx, qy, qz = params[0] + radius * ux, params[1] + radius * uy, params[2] + radius * uz
            return qx, qy, qz, ux, uy, uz, _distance(x, y, z, qx, qy, qz)
    qx = params[0] + radius * ux
    qy = params[1] + radius * uy
    qz = params[2] + radius * uz
    # on the sphere's radial line the distance is | |p − o| − R |, no second square root
    return qx, qy, qz, ux, uy, uz, abs(length - radius)


# --------------------------------------------------------------------------------------------
# Plane (PLANE): centre x, y, z, half size x, half size y


@_jit
def _plane(params: FloatArray, x: float, y: float, z: float):
    qx = min(max(x, params[0] - params[3]), params[0] + params[3])
    qy = min(max(y, params[1] - params[4]), params[1] + params[4])
    qz = params[2]
    dx, dy, dz = x - qx, y - qy, z - qz
    return qx, qy, qz, 0.0, 0.0, 1.0, math.sqrt(dx * dx + dy * dy + dz * dz)


@_jit
def plane_node(
    params: FloatArray,
    ax: float,
    ay: float,
    az: float,
    bx: float,
    by: float,
    bz: float,
    cx: float,
    cy: float,
    cz: float,
    spacing: float,
):
    """The node at distance ``spacing`` [m] from A and B on the plate, away from C, and its
    status: in the plate, on the perpendicular bisector of AB at √(d² − |AB|²/4) from the
    midpoint; OFF_TOOL past the plate's edge (by more than the edge tolerance)."""
    mx, my = 0.5 * (ax + bx), 0.5 * (ay + by)
    ex, ey, ez = bx - ax, by - ay, bz - az
    half2 = 0.25 * (ex * ex + ey * ey + ez * ez)
    radius2 = spacing * spacing - half2
    if not radius2 > 0.0:
        return np.nan, np.nan, np.nan, _NO_INTERSECTION
    e_len = math.sqrt(ex * ex + ey * ey + ez * ez)
    ex, ey = ex / e_len, ey / e_len
    s_len = math.sqrt(ey * ey + ex * ex)
    sx, sy = -ey / s_len, ex / s_len
    away = -1.0 if (cx - mx) * sx + (cy - my) * sy > 0.0 else 1.0
    off = away * math.sqrt(radius2)
    px, py = mx + off * sx, my + off * sy
    slack = _EDGE_TOLERANCE * spacing
    if not (abs(px - params[0]) <= params[3] + slack and abs(py - params[1]) <= params[4] + slack):
        return np.nan, np.nan, np.nan, _OFF_TOOL
    return px, py, params[2], _PLACED


# --------------------------------------------------------------------------------------------
# Cylinder (CYLINDER): centre x, y, z, radius, half length, axis (0: x, 1: y)


@_jit
def _cylinder(params: FloatArray, x: float, y: float, z: float):
    axis = int(params[5])
    rx, ry, rz = x - params[0], y - params[1], z - params[2]
    if axis == 0:
        rx = 0.0
    else:
        ry = 0.0
    ux, uy, uz = _unit_scaled(rx, ry, rz)
    radius, half = params[3], params[4]
    qx, qy, qz = params[0] + radius * ux, params[1] + radius * uy, params[2] + radius * uz
    if axis == 0:
        qx = min(max(x, params[0] - half), params[0] + half)
    else:
        qy = min(max(y, params[1] - half), params[1] + half)
    dx, dy, dz = x - qx, y - qy, z - qz
    return qx, qy, qz, ux, uy, uz, math.sqrt(dx * dx + dy * dy + dz * dz)


# --------------------------------------------------------------------------------------------
# The axisymmetric domes, in the meridian half-plane (r, z) of the query point


@_jit
def _azimuth(x: float, y: float):
    """(cos, sin) of the azimuth of (x, y): scaled by the larger plan coordinate first so it
    stays a unit vector for subnormal coordinates; +x on the axis (every meridian is as good)."""
    largest = max(abs(x), abs(y))
    if largest == 0.0:
        return 1.0, 0.0
    sx, sy = x / largest, y / largest
    unit = math.hypot(sx, sy)
    return sx / unit, sy / unit


@_jit
def _on_segment(r: float, z: float, r0: float, z0: float, r1: float, z1: float):
    """The closest point to (r, z) on the segment from (r0, z0) to (r1, z1)."""
    dr, dz = r1 - r0, z1 - z0
    length_sq = dr * dr + dz * dz
    if length_sq == 0.0:
        return r0, z0
    t = min(max(((r - r0) * dr + (z - z0) * dz) / length_sq, 0.0), 1.0)
    return r0 + t * dr, z0 + t * dz


@_jit
def _on_arc(
    r: float, z: float, cr: float, cz: float, radius: float, angle_start: float, angle_end: float
):
    """The closest point to (r, z) on the circular arc about (cr, cz) running anticlockwise
    from ``angle_start`` to ``angle_end`` [rad] (measured from +r towards +z)."""
    angle = math.atan2(z - cz, r - cr)
    if (angle - angle_start) % (2.0 * math.pi) <= angle_end - angle_start:
        return cr + radius * math.cos(angle), cz + radius * math.sin(angle)
    start_r, start_z = cr + radius * math.cos(angle_start), cz + radius * math.sin(angle_start)
    end_r, end_z = cr + radius * math.cos(angle_end), cz + radius * math.sin(angle_end)
    to_start = (r - start_r) ** 2 + (z - start_z) ** 2
    to_end = (r - end_r) ** 2 + (z - end_z) ** 2
    if to_start <= to_end:
        return start_r, start_z
    return end_r, end_z


@_jit
def _distance(x: float, y: float, z: float, qx: float, qy: float, qz: float) -> float:
    dx, dy, dz = x - qx, y - qy, z - qz
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@_jit
def _flanged_hemisphere(params: FloatArray, x: float, y: float, z: float):
    """Radius R, fillet radius ρ, fillet foot radius, flange half width W, seam elevation β,
    square flange (1) or disc (0). The nearest of the cap, the fillet and the flange (the
    first on a tie, in that order)."""
    radius, fillet, foot, width, beta = params[0], params[1], params[2], params[3], params[4]
    r = math.hypot(x, y)
    ca, sa = _azimuth(x, y)
    # cap
    cr, cz = _on_arc(r, z, 0.0, 0.0, radius, beta, 0.5 * math.pi)
    best_x, best_y, best_z = cr * ca, cr * sa, cz
    best = _distance(x, y, z, best_x, best_y, best_z)
    nr, nz = cr / radius, cz / radius
    # fillet, concave: its normal points to the fillet circle's centre
    fr, fz = _on_arc(r, z, foot, fillet, fillet, math.pi + beta, 1.5 * math.pi)
    d = _distance(x, y, z, fr * ca, fr * sa, fz)
    if d < best:
        best, best_x, best_y, best_z = d, fr * ca, fr * sa, fz
        nr, nz = (foot - fr) / fillet, (fillet - fz) / fillet
    # The flange, in plan (a square one is not axisymmetric): clamp into its outline, then
    # push out of the fillet foot disc (the part of the plane the fillet and cap cover).
    if params[5] != 0.0:
        px, py = min(max(x, -width), width), min(max(y, -width), width)
        if math.hypot(px, py) < foot:
            px, py = foot * ca, foot * sa
    else:
        plan_r = min(max(r, foot), width)
        px, py = plan_r * ca, plan_r * sa
    d = _distance(x, y, z, px, py, 0.0)
    if d < best:
        best, best_x, best_y, best_z = d, px, py, 0.0
        nr, nz = 0.0, 1.0
    # the normal in the meridian plane of the closest point (the query point's, unless the
    # flange clamp moved it, where the normal is +z anyway)
    na, nb = _azimuth(best_x, best_y)
    norm = math.hypot(nr, nz)
    return best_x, best_y, best_z, nr * na / norm, nr * nb / norm, nz / norm, best


@_jit
def _cone(params: FloatArray, x: float, y: float, z: float):
    """Base radius, height, top radius, lateral normal (r, z). The nearer of the lateral
    segment and the top disc (the lateral on a tie); +z at the apex."""
    base, height, top = params[0], params[1], params[2]
    r = math.hypot(x, y)
    ca, sa = _azimuth(x, y)
    lr, lz = _on_segment(r, z, base, 0.0, top, height)
    best_x, best_y, best_z = lr * ca, lr * sa, lz
    best = _distance(x, y, z, best_x, best_y, best_z)
    on_top = False
    tr, tz = _on_segment(r, z, 0.0, height, top, height)
    d = _distance(x, y, z, tr * ca, tr * sa, tz)
    if d < best:
        best, best_x, best_y, best_z = d, tr * ca, tr * sa, tz
        on_top = True
    if on_top or math.hypot(best_x, best_y) == 0.0:
        return best_x, best_y, best_z, 0.0, 0.0, 1.0, best
    na, nb = _azimuth(best_x, best_y)
    return best_x, best_y, best_z, params[3] * na, params[3] * nb, params[4], best


@_jit
def _ellipsoid_foot(y0: float, y1: float, y2: float, a0: float, a1: float, a2: float, three: bool):
    """The closest point on the ellipsoid Σ (q_i / a_i)² = 1 to (y0, y1, y2) ≥ 0 componentwise
    (one orthant; the caller restores signs); with ``three`` false, the ellipse of the first
    two components (y2, a2 unused, the third foot component 0).

    The foot is q_i = a_i² y_i / (a_i² + t) with t the largest root of
    Σ (a_i y_i / (a_i² + t))² = 1. Scaling t = s·a_min² gives
    G(s) = Σ (r_i z_i / (s + r_i))² − 1 with r_i = (a_i / a_min)² ≥ 1 and z_i = y_i / a_i; G is
    strictly decreasing on s > −1 and brackets its root in [max z_min-axes − 1, |r ∘ z| − 1],
    so bisection always converges. When the point lies on the plane orthogonal to the shortest
    axis deep inside, G(−1) < 0 and there is no root: the foot then leaves that plane, and the
    shortest-axis coordinate follows from the ellipsoid equation instead."""
    if not three:
        y2, a2 = 0.0, 1.0
    a_min = min(a0, a1, a2) if three else min(a0, a1)
    r0, r1, r2 = (a0 / a_min) ** 2, (a1 / a_min) ** 2, (a2 / a_min) ** 2
    z0, z1, z2 = y0 / a0, y1 / a1, y2 / a2
    s0, s1, s2 = a0 == a_min, a1 == a_min, three and a2 == a_min
    rz0, rz1, rz2 = r0 * z0, r1 * z1, r2 * z2
    lower = -np.inf
    if s0:
        lower = max(lower, z0)
    if s1:
        lower = max(lower, z1)
    if s2:
        lower = max(lower, z2)
    lower -= 1.0
    upper = max(math.sqrt(rz0 * rz0 + rz1 * rz1 + rz2 * rz2) - 1.0, lower)
    for _ in range(200):
        mid = 0.5 * (lower + upper)
        g = -1.0
        if rz0 != 0.0:
            g += (rz0 / (mid + r0)) ** 2
        if rz1 != 0.0:
            g += (rz1 / (mid + r1)) ** 2
        if rz2 != 0.0:
            g += (rz2 / (mid + r2)) ** 2
        if g > 0.0:
            lower = mid
        else:
            upper = mid
        if upper - lower <= 4.0 * _EPS * max(1.0, abs(upper)):
            break
    s = upper
    f0 = 0.0 if y0 == 0.0 else r0 * y0 / (s + r0)
    f1 = 0.0 if y1 == 0.0 else r1 * y1 / (s + r1)
    f2 = 0.0 if y2 == 0.0 else r2 * y2 / (s + r2)
    # Near s = −1 (the point near the plane orthogonal to the shortest axis, deep inside) the
    # shortest-axis coordinates y_k / (s + 1) are 0/0-like. They then follow better from the
    # ellipsoid equation, shared among tied shortest axes in proportion to y_k: that is better
    # conditioned whenever the share left for them, 1 − Σ_others (q_i/a_i)², exceeds s + 1.
    # With no root at all (all y_k = 0, G(−1) < 0) this is the exact answer: the foot leaves
    # the plane along the last shortest axis (z for a dome).
    taken = 0.0
    if not s0:
        taken += (f0 / a0) ** 2
    if not s1:
        taken += (f1 / a1) ** 2
    if not s2:
        taken += (f2 / a2) ** 2
    remainder = max(1.0 - taken, 0.0)
    if remainder > s + 1.0:
        w0 = y0 if s0 else 0.0
        w1 = y1 if s1 else 0.0
        w2 = y2 if s2 else 0.0
        if max(abs(w0), abs(w1), abs(w2)) > 0.0:
            w0, w1, w2 = _unit_scaled(w0, w1, w2)  # a unit vector where squares are subnormal
        elif s2:
            w2 = 1.0
        elif s1:
            w1 = 1.0
        else:
            w0 = 1.0
        height = a_min * math.sqrt(remainder)
        if s0:
            f0 = height * w0
        if s1:
            f1 = height * w1
        if s2:
            f2 = height * w2
    # Remove the residual of the root solve (tiny, but amplified where s + 1 is tiny) by a
    # radial rescale onto the ellipsoid; the foot moves by a second-order amount in distance.
    scale = math.sqrt((f0 / a0) ** 2 + (f1 / a1) ** 2 + (f2 / a2) ** 2)
    return f0 / scale, f1 / scale, f2 / scale


@_jit
def _ellipsoid_dome(params: FloatArray, x: float, y: float, z: float):
    """Semi-axes a, b, c. Exact for z ≥ 0 (the nearest point of the whole ellipsoid then lies
    in the upper half); below the base plane the nearer of the mirrored point's foot and the
    base-rim foot (the mirrored one on a tie)."""
    a, b, c = params[0], params[1], params[2]
    gx = -1.0 if x < 0.0 else 1.0
    gy = -1.0 if y < 0.0 else 1.0
    fx, fy, fz = _ellipsoid_foot(abs(x), abs(y), abs(z), a, b, c, True)
    # below the base plane this is the foot of the point mirrored in it
    qx, qy, qz = fx * gx, fy * gy, fz
    best = _distance(x, y, z, qx, qy, qz)
    if z < 0.0:
        rx, ry, _ = _ellipsoid_foot(abs(x), abs(y), 0.0, a, b, 1.0, False)
        d = _distance(x, y, z, rx * gx, ry * gy, 0.0)
        if d < best:
            best, qx, qy, qz = d, rx * gx, ry * gy, 0.0
    nx, ny, nz = qx / (a * a), qy / (b * b), qz / (c * c)
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    return qx, qy, qz, nx / norm, ny / norm, nz / norm, best


@_jit
def _paraboloid_dome(params: FloatArray, x: float, y: float, z: float):
    """Base radius R, height h, k = h/R². The meridian root of
    2k² r³ + (1 − 2k(h − z_p)) r − r_p = 0 by Newton from the right (the cubic is convex for
    r ≥ 0 and starts at −r_p ≤ 0), clamped to [0, R]."""
    radius, height, k = params[0], params[1], params[2]
    r_p = math.hypot(x, y)
    ca, sa = _azimuth(x, y)
    cubic = 2.0 * k * k
    linear = 1.0 - 2.0 * k * (height - z)
    # Start right of the root: at √(max(−linear, 0)/cubic) the cubic part vanishes and adding
    # ∛(r_p/cubic) makes the cubic ≥ 0.
    r = math.sqrt(max(-linear, 0.0) / cubic) + np.cbrt(r_p / cubic)
    for _ in range(100):
        f = cubic * r**3 + linear * r - r_p
        slope = 3.0 * cubic * r * r + linear
        step = f / slope if slope > 0.0 else 0.0
        r = max(r - step, 0.0)
        if abs(step) <= 4.0 * _EPS * max(r, radius):
            break
    r = min(max(r, 0.0), radius)
    qx, qy, qz = r * ca, r * sa, height - k * r * r
    na, nb = _azimuth(qx, qy)
    nr = 2.0 * k * math.hypot(qx, qy)
    norm = math.hypot(nr, 1.0)
    return qx, qy, qz, nr * na / norm, nr * nb / norm, 1.0 / norm, _distance(x, y, z, qx, qy, qz)


# --------------------------------------------------------------------------------------------
# Any kind


@_jit
def _other_kinds(kind: int, params: FloatArray, x: float, y: float, z: float):
    if kind == PLANE:
        return _plane(params, x, y, z)
    if kind == CYLINDER:
        return _cylinder(params, x, y, z)
    if kind == FLANGED_HEMISPHERE:
        return _flanged_hemisphere(params, x, y, z)
    if kind == CONE:
        return _cone(params, x, y, z)
    if kind == ELLIPSOID_DOME:
        return _ellipsoid_dome(params, x, y, z)
    if kind == PARABOLOID_DOME:
        return _paraboloid_dome(params, x, y, z)
    # not a kind of preform.drape.engine.compiled_surface (checked_kind refuses those before)
    return np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan


@_jit
def query(kind: int, params: FloatArray, x: float, y: float, z: float):
    """The closest point of the tool of ``kind`` to (x, y, z) [m], the unit outward normal
    there and the distance [m] (the tool's ``closest_point`` and ``normal`` at once).

    ``params`` as ``kernel_parameters`` gives them: its rank picks the queries when the caller
    is compiled (numba prunes the other branch), so the sphere's fill is compiled with the
    sphere's query alone and carries no dispatch on the other tools (measured: a run-time
    dispatch made the closed-form sphere fill 1.6x slower)."""
    if params.ndim == 1:
        return _sphere(kind, params, x, y, z)
    else:
        return _other_kinds(kind, params[0], x, y, z)


@_jit
def query_points(kind: int, params: FloatArray, points: FloatArray):
    """Closest tool points (m, 3) [m], unit normals there (m, 3) and distances (m,) [m], for
    the vectorised callers (the tools' own methods, generator marching)."""
    m = points.shape[0]
    foot = np.empty((m, 3))
    normal = np.empty((m, 3))
    dist = np.empty(m)
    for i in range(m):
        (
            foot[i, 0],
            foot[i, 1],
            foot[i, 2],
            normal[i, 0],
            normal[i, 1],
            normal[i, 2],
            dist[i],
        ) = query(kind, params, points[i, 0], points[i, 1], points[i, 2])
    return foot, normal, dist
