"""Compiled kernels of the pin-jointed net: node placement and the wavefront fill.

Each kernel exists once, here, compiled with numba (``cache=True``: compiled once per
install). ``preform.drape.net`` imports this module only when it drapes, so commands that do not
drape never import numba.

The per-node steps are plain scalar functions:

- :func:`_sphere_node`: the closed-form node on a sphere (PHYSICS §6); the plate's is
  ``preform.drape.surface_kernels.plane_node``, and every tool's closest point and normal
  ``preform.drape.surface_kernels.query``;
- :func:`_circle_frame` and :func:`_newton_update`: the general placement on the circle where
  the two distance spheres meet (``preform.drape.net``'s module doc), one damped Newton step
  in the circle angle φ at a time, given the surface's closest point and normal;
- :func:`_front_members`: which nodes front k holds and which are ready;
- :func:`_finish_node`: the checks every new node goes through (past the tool's bounds, folded
  cell, residual) and its write into the net.

Two drivers use them. For a surface with compiled queries
(:class:`~preform.drape.compiled_surface.CompiledQueries`), :func:`fill_fronts` fills the whole
net in one compiled loop (row by row within each quadrant). For any other surface (a mesh, a plugin's tool) the front loop
stays in Python and calls the vectorised wrappers below once per front, with the surface's own
vectorised ``closest_point``/``normal`` in between; the per-node arithmetic is the same code.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from preform.drape.compiled_surface import TRIMMED_SPHERE
from preform.drape.result import NodeStatus
from preform.drape.surface_kernels import plane_node
from preform.drape.surface_kernels import query as _query

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
StatusArray = NDArray[np.int8]

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


# --------------------------------------------------------------------------------------------
# The closed-form node on a sphere


# Inlined into ``_closed_form_node`` (numba IR), which the fill calls: one call level, as
# before the plate had its closed form (one level more made the sphere fill ~25 % slower).
@numba.njit(cache=True, error_model="numpy", fastmath=False, inline="always")
def _sphere_node(
    kind: int,
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
    """Node at chord ``spacing`` from A and B on the sphere, away from C; and its status.

    Relative to the centre, P·A = P·B = R² − d²/2 and |P| = R: P lies in the plane spanned by
    A + B and n = A × B, and of the two roots the one on the far side of the plane (0, A, B)
    from C is the node."""
    ox, oy, oz, r = params[0], params[1], params[2], params[3]
    pax, pay, paz = ax - ox, ay - oy, az - oz
    pbx, pby, pbz = bx - ox, by - oy, bz - oz
    pcx, pcy, pcz = cx - ox, cy - oy, cz - oz
    sx, sy, sz = pax + pbx, pay + pby, paz + pbz
    along = math.sqrt(sx * sx + sy * sy + sz * sz)
    nx = pay * pbz - paz * pby
    ny = paz * pbx - pax * pbz
    nz = pax * pby - pay * pbx
    n_len = math.sqrt(nx * nx + ny * ny + nz * nz)
    height = (2.0 * r * r - spacing * spacing) / along
    off2 = r * r - height * height
    if not (off2 >= 0.0 and n_len > 1e-12 * r * spacing):
        return np.nan, np.nan, np.nan, _NO_INTERSECTION
    away = -1.0 if pcx * nx + pcy * ny + pcz * nz > 0.0 else 1.0
    h = height / along
    k = away * math.sqrt(off2) / n_len
    px = h * sx + k * nx + ox
    py = h * sy + k * ny + oy
    pz = h * sz + k * nz + oz
    if kind == TRIMMED_SPHERE:
        if not pz >= params[4] - _EDGE_TOLERANCE * spacing:
            return np.nan, np.nan, np.nan, _OFF_TOOL
    elif not math.isfinite(px):
        return np.nan, np.nan, np.nan, _OFF_TOOL
    return px, py, pz, _PLACED


@_jit
def _closed_form_node(
    kind: int,
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
    """The closed-form node of a tool that has one (``CLOSED_FORM_KINDS``): the sphere's for
    a sphere's parameters (1-D), else the plate's (``surface_kernels.plane_node``), picked when
    compiled by the rank of ``params`` (as ``surface_kernels.query``)."""
    if params.ndim == 1:
        return _sphere_node(kind, params, ax, ay, az, bx, by, bz, cx, cy, cz, spacing)
    else:
        return plane_node(params[0], ax, ay, az, bx, by, bz, cx, cy, cz, spacing)


@_jit
def closed_form_nodes(
    kind: int, params: FloatArray, a: FloatArray, b: FloatArray, c: FloatArray, spacing: float
):
    """The tools' ``place_nodes`` (sphere, plate) over m nodes: points (m, 3) [m] (NaN unless
    placed) and NodeStatus codes (m,)."""
    m = a.shape[0]
    points = np.empty((m, 3))
    status = np.empty(m, dtype=np.int8)
    for i in range(m):
        px, py, pz, st = _closed_form_node(
            kind,
            params,
            a[i, 0],
            a[i, 1],
            a[i, 2],
            b[i, 0],
            b[i, 1],
            b[i, 2],
            c[i, 0],
            c[i, 1],
            c[i, 2],
            spacing,
        )
        points[i, 0], points[i, 1], points[i, 2] = px, py, pz
        status[i] = st
    return points, status


# --------------------------------------------------------------------------------------------
# The general node: Newton on the constraint circle

#: Frame of one node's circle: mid (3), a1 (3), a2 (3), radius; see ``_circle_frame``.
FRAME = 10


@_jit
def _circle_frame(
    a: FloatArray,
    b: FloatArray,
    c: FloatArray,
    guess: FloatArray,
    n0: FloatArray,
    spacing: float,
    frame: FloatArray,
) -> float:
    """Fill ``frame`` for the node at chord ``spacing`` from a and b, away from c: the circle
    P(φ) = M + r(cos φ·a1 + sin φ·a2), a1 the surface normal ``n0`` (at ``guess``, the closest
    point to a + b − c) seen from the chord, a2 pointing away from c. Returns the starting
    angle φ of ``guess``, or NaN when there is no circle (|AB| ≥ 2d or a degenerate frame)."""
    mx, my, mz = 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])
    ex, ey, ez = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    half2 = 0.25 * (ex * ex + ey * ey + ez * ez)
    radius2 = spacing * spacing - half2
    e_len = math.sqrt(4.0 * half2)
    ex, ey, ez = ex / e_len, ey / e_len, ez / e_len
    along = n0[0] * ex + n0[1] * ey + n0[2] * ez
    a1x, a1y, a1z = n0[0] - along * ex, n0[1] - along * ey, n0[2] - along * ez
    a1_len = math.sqrt(a1x * a1x + a1y * a1y + a1z * a1z)
    a1x, a1y, a1z = a1x / a1_len, a1y / a1_len, a1z / a1_len
    a2x = ey * a1z - ez * a1y
    a2y = ez * a1x - ex * a1z
    a2z = ex * a1y - ey * a1x
    if (c[0] - mx) * a2x + (c[1] - my) * a2y + (c[2] - mz) * a2z > 0.0:
        a2x, a2y, a2z = -a2x, -a2y, -a2z
    radius = math.sqrt(max(radius2, 0.0))
    frame[0], frame[1], frame[2] = mx, my, mz
    frame[3], frame[4], frame[5] = a1x, a1y, a1z
    frame[6], frame[7], frame[8] = a2x, a2y, a2z
    frame[9] = radius
    rx, ry, rz = guess[0] - mx, guess[1] - my, guess[2] - mz
    phi = math.atan2(rx * a2x + ry * a2y + rz * a2z, rx * a1x + ry * a1y + rz * a1z)
    phi = min(max(phi, 0.0), math.pi)
    if not (radius2 > 0.0 and math.isfinite(a1x) and math.isfinite(phi)):
        return np.nan
    return phi


@_jit
def _on_circle(frame: FloatArray, phi: float):
    cos_p, sin_p, r = math.cos(phi), math.sin(phi), frame[9]
    return (
        frame[0] + r * (cos_p * frame[3] + sin_p * frame[6]),
        frame[1] + r * (cos_p * frame[4] + sin_p * frame[7]),
        frame[2] + r * (cos_p * frame[5] + sin_p * frame[8]),
    )


#: Outcomes of one Newton update.
_GOING, _DONE, _FAILED_OFF_TOOL, _FAILED = 0, 1, 2, 3


@_jit
def _newton_update(
    frame: FloatArray,
    phi: float,
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
    """One damped Newton step in φ on the signed distance g(φ) = (P(φ) − foot)·n from the
    surface, given the closest point ``foot`` of P(φ) = (x, y, z), its normal and distance.
    Returns (new φ, outcome)."""
    if dist <= tolerance_m:
        return phi, _DONE
    ox, oy, oz = x - fx, y - fy, z - fz
    g = ox * nx + oy * ny + oz * nz
    cos_p, sin_p, r = math.cos(phi), math.sin(phi), frame[9]
    n_a1 = nx * frame[3] + ny * frame[4] + nz * frame[5]
    n_a2 = nx * frame[6] + ny * frame[7] + nz * frame[8]
    slope = r * (-sin_p * n_a1 + cos_p * n_a2)
    step = -g / slope
    if math.isnan(step):
        step = 0.0
    step = min(max(step, -0.5), 0.5)
    new_phi = min(max(phi + step, 0.0), math.pi)
    stuck = abs(new_phi - phi) <= 1e-15 * math.pi
    if not (stuck or last_try):
        return new_phi, _GOING
    # A point whose closest point is an edge of the tool has an offset with a tangential
    # part; an interior closest point has a purely normal one.
    tx, ty, tz = ox - g * nx, oy - g * ny, oz - g * nz
    if math.sqrt(tx * tx + ty * ty + tz * tz) > 0.5 * dist:
        return new_phi, _FAILED_OFF_TOOL
    return new_phi, _FAILED


@_jit
def circle_frames(
    a: FloatArray, b: FloatArray, c: FloatArray, guess: FloatArray, n0: FloatArray, spacing: float
):
    """Frames (m, FRAME) and starting angles φ (m,) [rad] of m nodes (NaN: no circle)."""
    m = a.shape[0]
    frames = np.empty((m, FRAME))
    phi = np.empty(m)
    for i in range(m):
        phi[i] = _circle_frame(a[i], b[i], c[i], guess[i], n0[i], spacing, frames[i])
    return frames, phi


@_jit
def circle_points(frames: FloatArray, phi: FloatArray, rows: IntArray) -> FloatArray:
    """P(φ) (len(rows), 3) [m] of the nodes ``rows``."""
    out = np.empty((rows.shape[0], 3))
    for k in range(rows.shape[0]):
        i = rows[k]
        out[k, 0], out[k, 1], out[k, 2] = _on_circle(frames[i], phi[i])
    return out


@_jit
def newton_updates(
    rows: IntArray,
    x: FloatArray,
    foot: FloatArray,
    normal: FloatArray,
    dist: FloatArray,
    frames: FloatArray,
    phi: FloatArray,
    points: FloatArray,
    status: StatusArray,
    tolerance_m: float,
    last_try: bool,
) -> IntArray:
    """One Newton update of the nodes ``rows`` (their P(φ) ``x``, closest points, normals and
    distances given); writes placed ``points`` and ``status`` and returns the rows still going."""
    going = np.empty(rows.shape[0], dtype=np.int64)
    count = 0
    for k in range(rows.shape[0]):
        i = rows[k]
        new_phi, outcome = _newton_update(
            frames[i],
            phi[i],
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
        phi[i] = new_phi
        if outcome == _DONE:
            points[i, 0], points[i, 1], points[i, 2] = x[k, 0], x[k, 1], x[k, 2]
            status[i] = _PLACED
        elif outcome == _FAILED_OFF_TOOL:
            status[i] = _OFF_TOOL
        elif outcome == _GOING:
            going[count] = i
            count += 1
    return going[:count]


@_jit
def _newton_node(
    kind: int,
    params: FloatArray,
    a: FloatArray,
    b: FloatArray,
    c: FloatArray,
    spacing: float,
    tolerance_m: float,
    max_iterations: int,
    frame: FloatArray,
    work: FloatArray,
):
    """The general node for a surface with compiled queries: (x, y, z, status, iterations)."""
    gx, gy, gz, n0x, n0y, n0z, _ = _query(
        kind, params, a[0] + b[0] - c[0], a[1] + b[1] - c[1], a[2] + b[2] - c[2]
    )
    work[0], work[1], work[2], work[3], work[4], work[5] = gx, gy, gz, n0x, n0y, n0z
    phi = _circle_frame(a, b, c, work[0:3], work[3:6], spacing, frame)
    if math.isnan(phi):
        return np.nan, np.nan, np.nan, _NO_INTERSECTION, 0
    for used in range(1, max_iterations + 1):
        x, y, z = _on_circle(frame, phi)
        fx, fy, fz, nx, ny, nz, dist = _query(kind, params, x, y, z)
        phi, outcome = _newton_update(
            frame, phi, x, y, z, fx, fy, fz, nx, ny, nz, dist, tolerance_m, used == max_iterations
        )
        if outcome == _DONE:
            return x, y, z, _PLACED, used
        if outcome == _FAILED_OFF_TOOL:
            return np.nan, np.nan, np.nan, _OFF_TOOL, used
        if outcome == _FAILED:
            return np.nan, np.nan, np.nan, _NO_INTERSECTION, used
    return np.nan, np.nan, np.nan, _NO_INTERSECTION, max_iterations


# --------------------------------------------------------------------------------------------
# The fronts


@_jit
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
            if (
                status[node] == _NOT_REACHED
                and status[ia] == _PLACED
                and status[ib] == _PLACED
                and status[ic] == _PLACED
            ):
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


@_jit
def _finish_node(
    pos: FloatArray,
    status: StatusArray,
    residual: FloatArray,
    member: IntArray,
    px: float,
    py: float,
    pz: float,
    st: np.int8,
    nx: float,
    ny: float,
    nz: float,
    dist: float,
    spacing: float,
    lo: FloatArray,
    hi: FloatArray,
) -> None:
    """Check a new node and write it: OFF_TOOL past the tool's bounds, FOLDED where the cell it
    completes faces against the surface normal (nx, ny, nz) at it, else PLACED with its
    residual max(|PA| − d, |PB| − d, distance ``dist`` to the tool)."""
    node, ia, ib, ic, orient = member[0], member[1], member[2], member[3], member[4]
    if st == _PLACED:
        past = px < lo[0] or py < lo[1] or pz < lo[2] or px > hi[0] or py > hi[1] or pz > hi[2]
        ux, uy, uz = px - pos[ic, 0], py - pos[ic, 1], pz - pos[ic, 2]
        vx, vy, vz = pos[ia, 0] - pos[ib, 0], pos[ia, 1] - pos[ib, 1], pos[ia, 2] - pos[ib, 2]
        cx = uy * vz - uz * vy
        cy = uz * vx - ux * vz
        cz = ux * vy - uy * vx
        if past:
            st = _OFF_TOOL
        elif orient * (cx * nx + cy * ny + cz * nz) <= 0.0:
            st = _FOLDED
    if st == _PLACED:
        to_a = math.sqrt((px - pos[ia, 0]) ** 2 + (py - pos[ia, 1]) ** 2 + (pz - pos[ia, 2]) ** 2)
        to_b = math.sqrt((px - pos[ib, 0]) ** 2 + (py - pos[ib, 1]) ** 2 + (pz - pos[ib, 2]) ** 2)
        pos[node, 0], pos[node, 1], pos[node, 2] = px, py, pz
        residual[node] = max(abs(to_a - spacing), abs(to_b - spacing), dist)
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
    """:func:`_finish_node` over one front placed by the Python loop (normals and distances of
    the placed points given; anything where the status is not PLACED)."""
    for i in range(members.shape[0]):
        _finish_node(
            pos,
            status,
            residual,
            members[i],
            points[i, 0],
            points[i, 1],
            points[i, 2],
            point_status[i],
            normals[i, 0],
            normals[i, 1],
            normals[i, 2],
            dist[i],
            spacing,
            lo,
            hi,
        )


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
    member = np.empty(5, dtype=np.int64)
    frame = np.empty(FRAME)
    work = np.empty(6)
    most_used = 0
    for q in range(q_sa.shape[0]):
        da, db = q_sa[q] * nj, q_sb[q]
        member[4] = q_sa[q] * q_sb[q]  # the cell is oriented +u × +v whatever the quadrant
        na, nb = q_na[q], q_nb[q]
        for a_off in range(1, na + 1):
            row = start_flat + a_off * da
            for b_off in range(1, nb + 1):
                node = row + b_off * db
                ia, ib = node - da, node - db
                ic = ia - db
                if not (
                    status[node] == _NOT_REACHED
                    and status[ia] == _PLACED
                    and status[ib] == _PLACED
                    and status[ic] == _PLACED
                ):
                    continue
                ready_on_front[a_off + b_off] = True
                member[0], member[1], member[2], member[3] = node, ia, ib, ic
                if closed_form:
                    px, py, pz, st = _closed_form_node(
                        kind,
                        params,
                        pos[ia, 0],
                        pos[ia, 1],
                        pos[ia, 2],
                        pos[ib, 0],
                        pos[ib, 1],
                        pos[ib, 2],
                        pos[ic, 0],
                        pos[ic, 1],
                        pos[ic, 2],
                        spacing,
                    )
                else:
                    px, py, pz, st, used = _newton_node(
                        kind,
                        params,
                        pos[ia],
                        pos[ib],
                        pos[ic],
                        spacing,
                        tolerance_m,
                        max_iterations,
                        frame,
                        work,
                    )
                    most_used = max(most_used, used)
                nx = ny = nz = dist = np.nan
                if st == _PLACED:
                    _, _, _, nx, ny, nz, dist = _query(kind, params, px, py, pz)
                _finish_node(
                    pos,
                    status,
                    residual,
                    member,
                    px,
                    py,
                    pz,
                    st,
                    nx,
                    ny,
                    nz,
                    dist,
                    spacing,
                    lo,
                    hi,
                )
    # Fronts as the front-by-front loop counts them: it stops at the first front past the
    # second with no ready node (no later front can have one).
    fronts = 0
    for k in range(2, last_front + 1):
        if not ready_on_front[k]:
            if k > 2:
                break
            continue
        fronts += 1
    # the vectorised loop makes one more pass over a front to find no node left, unless capped
    newton_max = 0 if closed_form or fronts == 0 else min(most_used + 1, max_iterations)
    return fronts, newton_max
