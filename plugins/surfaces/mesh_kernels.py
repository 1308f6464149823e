"""Compiled walking kernels on a triangle mesh: exact net placement and exact geodesics.

Imported lazily (numba is not loaded by ``import preform``); ``@njit(cache=True)`` compiles once
per install. Both kernels walk from triangle to triangle over a :class:`MeshTopology`, so a
query costs a few triangles, not a search of the mesh. Lengths in metres.

Net placement. Node P is at chord d from its parents A and B, so it lies on the circle
P(φ) = M + r(cos φ·a1 + sin φ·a2), M = (A + B)/2, r² = d² − |AB|²/4, a1 the mean outward normal
of the parents' triangles made normal to the chord, a2 = ê × a1 turned away from the opposite
node C (C itself lies on the circle at some φ in (−π, 0)). The surface is piecewise flat, so
each triangle's plane meets the circle in at most two points, in closed form:
n·(M − p0) + r cos φ (n·a1) + r sin φ (n·a2) = 0. The circle lies in the ball of radius d about M,
so the candidates are the triangles meeting that ball, found by a breadth-first walk from the
parents' triangles. Of the roots inside their triangle with 0 < φ < π (the far half from C),
the node is the one with the smallest φ: turning from the outward side, the first point where
the circle meets the tool, which is where the fabric, lying on the tool and never inside it,
touches it. At a crease this picks the wall beyond a convex edge and the wall rising from a
concave foot, with no iteration to stall. No root: OFF_TOOL if the ball reaches the mesh's
boundary, else NO_INTERSECTION. Parents that coincide (a cell closed up completely, as behind a
sharp convex vertex when the fibre angle falls to 0) or lie on facets facing opposite ways
(the net folded flat over a knife edge): FOLDED.

What a node costs (issue 30): the walk visits 4-12 triangles a node on the benchmark's
hemispheres (``benchmarks/bench_mesh.py``). Only a triangle whose bounding ball meets the
circle's far half can hold a root: the others are walked through, not solved (the slack is
how far the inside test's tolerance reaches past the triangle's sharpest corner,
``MeshTopology.corner_reach``, so no root the full solve would accept is skipped). The roots
come as (cos φ, sin φ) by algebra, not trigonometric calls, and are ranked by a pseudo-angle
monotone in φ. :func:`fill_fronts_kernel` fills a whole net in one compiled loop, as
``preform.drape.kernels.net_kernels.fill_fronts`` does for the analytic tools, with the same node
checks.

Geodesics. The straightest path on a piecewise-flat surface is straight inside each triangle
and crosses an edge by unfolding: the component of the direction along the edge is kept and the
component across it turns into the next triangle's plane (Polthier & Schmies' straightest
geodesics, which coincide with shortest ones away from vertices). Nodes are put where the
chord from the previous node reaches d, solved in closed form on each straight piece.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from preform.base.kernel_cache import cache_by_content
from preform.drape.engine.result import NodeStatus
from preform.drape.kernels.net_kernels import _check_node, _fronts_placed, _ready

#: The preform modules compiled into these kernels (inlined functions, frozen constants):
#: their sources are part of the key these kernels are cached under
#: (``preform.base.kernel_cache``).
COMPILED_IN = ("preform.drape.engine.result", "preform.drape.kernels.net_kernels")
cache_by_content(__name__)

_PLACED = int(NodeStatus.PLACED)
_OFF_TOOL = int(NodeStatus.OFF_TOOL)
_NO_INTERSECTION = int(NodeStatus.NO_INTERSECTION)
_FOLDED = int(NodeStatus.FOLDED)


#: The per-node steps are inlined into the loops that call them, as in
#: ``preform.drape.kernels.net_kernels``: an array handed to a function that is not inlined is
#: reference counted at every call, and these are called once per node and triangle.
_per_node = numba.njit(cache=True, inline="always")


@_per_node
def _dot3(u0, u1, u2, v0, v1, v2):
    return u0 * v0 + u1 * v1 + u2 * v2


@_per_node
def _segment_distance(p0, p1, p2, corners, t, k):
    """Distance [m] from point (p0, p1, p2) to edge k of triangle t (corner k to k + 1)."""
    k1 = (k + 1) % 3
    q0, q1, q2 = corners[t, k, 0], corners[t, k, 1], corners[t, k, 2]
    e0, e1, e2 = corners[t, k1, 0] - q0, corners[t, k1, 1] - q1, corners[t, k1, 2] - q2
    w0, w1, w2 = p0 - q0, p1 - q1, p2 - q2
    ll = e0 * e0 + e1 * e1 + e2 * e2
    s = 0.0
    if ll > 0.0:
        s = min(max((w0 * e0 + w1 * e1 + w2 * e2) / ll, 0.0), 1.0)
    d0, d1, d2 = w0 - s * e0, w1 - s * e1, w2 - s * e2
    return math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)


@_per_node
def _turns(f, t, normals, feature_cos):
    """Whether the surface turns by more than the feature angle from triangle f to t: the
    only case in which :func:`_unfolded` moves a point."""
    return (
        f != t
        and _dot3(
            normals[f, 0], normals[f, 1], normals[f, 2], normals[t, 0], normals[t, 1], normals[t, 2]
        )
        < feature_cos
    )


@_per_node
def _unfolded(q0, q1, q2, f, t, normals, corners, centroids, feature_cos, spacing):
    """Point q on triangle f as seen from triangle t: q itself (the chord model) unless the
    surface turns between them by more than the feature angle (cos of f's and t's normals below
    ``feature_cos``); then q rotated about the crease into t's plane, beyond the crease from t,
    so that its straight distance to a point of t is the length along the surface, over the
    crease. The crease is the line where f's and t's planes meet: for one sharp edge between
    them that is the edge itself."""
    nf0, nf1, nf2 = normals[f, 0], normals[f, 1], normals[f, 2]
    nt0, nt1, nt2 = normals[t, 0], normals[t, 1], normals[t, 2]
    if f == t or _dot3(nf0, nf1, nf2, nt0, nt1, nt2) >= feature_cos:
        return q0, q1, q2, False
    # u along the crease; its length² is sin² of the turn.
    u0, u1, u2 = nf1 * nt2 - nf2 * nt1, nf2 * nt0 - nf0 * nt2, nf0 * nt1 - nf1 * nt0
    uu = u0 * u0 + u1 * u1 + u2 * u2
    if uu < 1e-24:
        # Facets facing opposite ways (a knife edge): no crease line to unfold about.
        return q0, q1, q2, False
    hf = _dot3(nf0, nf1, nf2, corners[f, 0, 0], corners[f, 0, 1], corners[f, 0, 2])
    ht = _dot3(nt0, nt1, nt2, corners[t, 0, 0], corners[t, 0, 1], corners[t, 0, 2])
    # The point of the crease nearest the origin: (hf·(nt × u) + ht·(u × nf)) / |u|².
    x0 = (hf * (nt1 * u2 - nt2 * u1) + ht * (u1 * nf2 - u2 * nf1)) / uu
    x1 = (hf * (nt2 * u0 - nt0 * u2) + ht * (u2 * nf0 - u0 * nf2)) / uu
    x2 = (hf * (nt0 * u1 - nt1 * u0) + ht * (u0 * nf1 - u1 * nf0)) / uu
    ul = math.sqrt(uu)
    u0, u1, u2 = u0 / ul, u1 / ul, u2 / ul
    w0, w1, w2 = q0 - x0, q1 - x1, q2 - x2
    s = _dot3(w0, w1, w2, u0, u1, u2)
    h0, h1, h2 = w0 - s * u0, w1 - s * u1, w2 - s * u2
    h = math.sqrt(h0 * h0 + h1 * h1 + h2 * h2)
    if h > spacing:
        # The planes meet farther than one spacing from q: no single crease lies between q and
        # a node of t (two features within one spacing, or a smooth turn): the chord.
        return q0, q1, q2, False
    # In t's plane, across the crease: v ⟂ u, pointing away from t's side.
    v0, v1, v2 = nt1 * u2 - nt2 * u1, nt2 * u0 - nt0 * u2, nt0 * u1 - nt1 * u0
    if _dot3(v0, v1, v2, centroids[t, 0] - x0, centroids[t, 1] - x1, centroids[t, 2] - x2) > 0.0:
        v0, v1, v2 = -v0, -v1, -v2
    return x0 + s * u0 + h * v0, x1 + s * u1 + h * v1, x2 + s * u2 + h * v2, True


@numba.njit(cache=True)
def spacing_kernel(
    corners, normals, centroids, a, b, face_a, face_b, feature_cos, spacing, out_length
):
    """The spacing [m] from a[i] on triangle face_a[i] to b[i] on face_b[i] under the placement's
    rule: the distance from b to a unfolded into b's plane over a feature, else the chord."""
    for i in range(a.shape[0]):
        u0, u1, u2, _ = _unfolded(
            a[i, 0],
            a[i, 1],
            a[i, 2],
            face_a[i],
            face_b[i],
            normals,
            corners,
            centroids,
            feature_cos,
            spacing,
        )
        out_length[i] = math.sqrt((b[i, 0] - u0) ** 2 + (b[i, 1] - u1) ** 2 + (b[i, 2] - u2) ** 2)


@_per_node
def _place_node(
    corners,
    normals,
    neighbours,
    edge_normals,
    centroids,
    radii,
    reach,
    a,
    b,
    c,
    spacing,
    feature_cos,
    fa,
    fb,
    fc,
    visited,
    queue,
):
    """The node at chord ``spacing`` from a and b (3-tuples) on the mesh, away from c (module
    doc), walking from the parents' triangles fa and fb (fc: the opposite node's, −1 if not
    known). ``visited`` (m,) bool all False and ``queue`` (m,) int64 are scratch (left all
    False). Returns (NodeStatus code, x, y, z, triangle, nx, ny, nz, residual): the node's
    triangle, its normal and its residual [m], the largest of its distance to that triangle's
    plane and the errors of its two spacings (chord, or surface length over a feature); NaN
    and triangle −1 where not placed."""
    nan = np.nan
    inside_tol = 1e-9 * spacing
    m0 = 0.5 * (a[0] + b[0])
    m1 = 0.5 * (a[1] + b[1])
    m2 = 0.5 * (a[2] + b[2])
    e0, e1, e2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    chord = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    r2 = spacing * spacing - 0.25 * chord * chord
    if chord <= 1e-9 * spacing:
        # The parents coincide: the cell has closed up completely (ω = 0, the collapse
        # behind a sharp convex vertex), the limit of a fold.
        return _FOLDED, nan, nan, nan, -1, nan, nan, nan, nan
    if not r2 > 0.0:
        return _NO_INTERSECTION, nan, nan, nan, -1, nan, nan, nan, nan
    r = math.sqrt(r2)
    e0, e1, e2 = e0 / chord, e1 / chord, e2 / chord
    if fc < 0:
        fc = fa  # (opposite node's triangle unknown: taken as a parent's)
    s0 = normals[fa, 0] + normals[fb, 0]
    s1 = normals[fa, 1] + normals[fb, 1]
    s2 = normals[fa, 2] + normals[fb, 2]
    along = _dot3(s0, s1, s2, e0, e1, e2)
    x0, x1, x2 = s0 - along * e0, s1 - along * e1, s2 - along * e2
    length = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    if length < 1e-12:
        # Parents' normals cancel or lie along the chord: the net is folded flat here.
        return _FOLDED, nan, nan, nan, -1, nan, nan, nan, nan
    x0, x1, x2 = x0 / length, x1 / length, x2 / length
    y0, y1, y2 = e1 * x2 - e2 * x1, e2 * x0 - e0 * x2, e0 * x1 - e1 * x0
    if _dot3(y0, y1, y2, c[0] - m0, c[1] - m1, c[2] - m2) > 0.0:
        y0, y1, y2 = -y0, -y1, -y2

    ball = spacing * (1.0 + 1e-9)
    head, tail = 0, 0
    for f in (fa, fb):
        if not visited[f]:
            visited[f] = True
            queue[tail] = f
            tail += 1
    best_rank = np.inf
    best_face = -1
    best_over_feature = False
    ba0, ba1, ba2, bb0, bb1, bb2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    bp0, bp1, bp2 = 0.0, 0.0, 0.0
    boundary = False
    while head < tail:
        t = queue[head]
        head += 1
        for k in range(3):
            nb = neighbours[t, k]
            if nb < 0:
                if not boundary:
                    if _segment_distance(m0, m1, m2, corners, t, k) <= ball:
                        boundary = True
                continue
            if visited[nb]:
                continue
            g0 = centroids[nb, 0] - m0
            g1 = centroids[nb, 1] - m1
            g2 = centroids[nb, 2] - m2
            if math.sqrt(g0 * g0 + g1 * g1 + g2 * g2) <= ball + radii[nb]:
                visited[nb] = True
                queue[tail] = nb
                tail += 1
        # The circle this triangle sees: the chord circle, or, where the surface turns by
        # more than the feature angle between a parent's triangle and t, the circle about
        # that parent unfolded into t's plane (surface length over the crease, module doc).
        over = False
        ta0, ta1, ta2 = a[0], a[1], a[2]
        tb0, tb1, tb2 = b[0], b[1], b[2]
        tc0, tc1, tc2 = c[0], c[1], c[2]
        if (
            _turns(fa, t, normals, feature_cos)
            or _turns(fb, t, normals, feature_cos)
            or _turns(fc, t, normals, feature_cos)
        ):
            ta0, ta1, ta2, ua = _unfolded(
                a[0], a[1], a[2], fa, t, normals, corners, centroids, feature_cos, spacing
            )
            tb0, tb1, tb2, ub = _unfolded(
                b[0], b[1], b[2], fb, t, normals, corners, centroids, feature_cos, spacing
            )
            tc0, tc1, tc2, uc = _unfolded(
                c[0],
                c[1],
                c[2],
                fc,
                t,
                normals,
                corners,
                centroids,
                feature_cos,
                2.0 * spacing,  # (a cell's diagonal is under 2 d)
            )
            over = ua or ub or uc
        if not over:
            # A triangle not over a feature can only meet the chord circle's far half
            # (0 < φ < π, where (p − M)·a2 > 0): most triangles in the ball are far from it,
            # and those whose bounding ball misses it by more than the slack of the inside
            # test below (``reach``) have no root to find.
            g0 = centroids[t, 0] - m0
            g1 = centroids[t, 1] - m1
            g2 = centroids[t, 2] - m2
            limit = radii[t] + (reach[t] + 1.0) * inside_tol
            if _dot3(g0, g1, g2, y0, y1, y2) < -limit:
                continue
            h = _dot3(g0, g1, g2, e0, e1, e2)
            rho = math.sqrt(max(g0 * g0 + g1 * g1 + g2 * g2 - h * h, 0.0))
            if h * h + (rho - r) * (rho - r) > limit * limit:
                continue
        cm0, cm1, cm2, cr = m0, m1, m2, r
        cx0, cx1, cx2, cy0, cy1, cy2 = x0, x1, x2, y0, y1, y2
        if over:
            cm0, cm1, cm2 = 0.5 * (ta0 + tb0), 0.5 * (ta1 + tb1), 0.5 * (ta2 + tb2)
            f0, f1, f2 = tb0 - ta0, tb1 - ta1, tb2 - ta2
            fl = math.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
            cr2 = spacing * spacing - 0.25 * fl * fl
            if not cr2 > 0.0 or fl <= 1e-9 * spacing:
                continue
            cr = math.sqrt(cr2)
            f0, f1, f2 = f0 / fl, f1 / fl, f2 / fl
            # The circle's own frame: from t's outward normal, turning away from the
            # opposite node as seen in t's plane (unfolded too if across a feature), so
            # the far half is 0 < φ < π as for the chord circle; past a fold sharper than
            # 90° the node can lie behind the parents' chord in space, so the chord
            # circle's half cannot say it.
            nt0, nt1, nt2 = normals[t, 0], normals[t, 1], normals[t, 2]
            fx = _dot3(nt0, nt1, nt2, f0, f1, f2)
            cx0, cx1, cx2 = nt0 - fx * f0, nt1 - fx * f1, nt2 - fx * f2
            cl = math.sqrt(cx0 * cx0 + cx1 * cx1 + cx2 * cx2)
            if cl < 1e-12:
                continue
            cx0, cx1, cx2 = cx0 / cl, cx1 / cl, cx2 / cl
            cy0, cy1, cy2 = f1 * cx2 - f2 * cx1, f2 * cx0 - f0 * cx2, f0 * cx1 - f1 * cx0
            if _dot3(cy0, cy1, cy2, tc0 - cm0, tc1 - cm1, tc2 - cm2) > 0.0:
                cy0, cy1, cy2 = -cy0, -cy1, -cy2
        n0, n1, n2 = normals[t, 0], normals[t, 1], normals[t, 2]
        al = _dot3(n0, n1, n2, cx0, cx1, cx2)
        be = _dot3(n0, n1, n2, cy0, cy1, cy2)
        ga = _dot3(
            n0, n1, n2, cm0 - corners[t, 0, 0], cm1 - corners[t, 0, 1], cm2 - corners[t, 0, 2]
        )
        rho = math.sqrt(al * al + be * be)
        if rho * cr < abs(ga) or rho == 0.0:
            continue
        # cos φ and sin φ of the two roots of al cos φ + be sin φ = −ga / cr, without a
        # trigonometric call: (cos, sin) = q (al, be)/ρ ± √(1 − q²) (−be, al)/ρ.
        q = min(max(-ga / (cr * rho), -1.0), 1.0)
        s = math.sqrt(1.0 - q * q)
        ua, ub = al / rho, be / rho
        for sign in (1.0, -1.0):
            cs = q * ua - sign * s * ub
            sn = q * ub + sign * s * ua
            if not sn > 0.0:
                continue  # not on the far half, 0 < φ < π
            p0 = cm0 + cr * cs * cx0 + cr * sn * cy0
            p1 = cm1 + cr * cs * cx1 + cr * sn * cy1
            p2 = cm2 + cr * cs * cx2 + cr * sn * cy2
            # Roots are ranked by φ through a pseudo-angle, monotone in φ over (0, 2π]:
            # 1 − cos φ on (0, π], 3 + cos φ on (π, 2π].
            rank = 1.0 - cs
            if over:
                # Ranked with the chord-circle roots by its angle about the parents' chord,
                # taken in (0, 2π]: all triangles compared on one scale.
                px = _dot3(p0 - m0, p1 - m1, p2 - m2, x0, x1, x2)
                py = _dot3(p0 - m0, p1 - m1, p2 - m2, y0, y1, y2)
                pl = math.sqrt(px * px + py * py)
                if pl == 0.0:
                    rank = 4.0  # (on the chord: φ = 2π, last)
                else:
                    rank = 1.0 - px / pl if py > 0.0 else 3.0 + px / pl
            if rank >= best_rank:
                continue
            inside = True
            for k in range(3):
                w = _dot3(
                    edge_normals[t, k, 0],
                    edge_normals[t, k, 1],
                    edge_normals[t, k, 2],
                    p0 - corners[t, k, 0],
                    p1 - corners[t, k, 1],
                    p2 - corners[t, k, 2],
                )
                if w > inside_tol:
                    inside = False
                    break
            if inside:
                best_rank, best_face = rank, t
                best_over_feature = over
                ba0, ba1, ba2, bb0, bb1, bb2 = ta0, ta1, ta2, tb0, tb1, tb2
                bp0, bp1, bp2 = p0, p1, p2
    for j in range(tail):
        visited[queue[j]] = False
    if best_face < 0:
        status = _OFF_TOOL if boundary else _NO_INTERSECTION
        return status, nan, nan, nan, -1, nan, nan, nan, nan
    o0, o1, o2 = normals[best_face, 0], normals[best_face, 1], normals[best_face, 2]
    if best_over_feature:
        # The cell wraps over the crease: past a 90° fold its chord-built normal faces
        # away from the node's facet though nothing folded, so the engine's fold test
        # compares it with the mean normal of its four corners' facets.
        w0 = normals[best_face, 0] + normals[fa, 0] + normals[fb, 0] + normals[fc, 0]
        w1 = normals[best_face, 1] + normals[fa, 1] + normals[fb, 1] + normals[fc, 1]
        w2 = normals[best_face, 2] + normals[fa, 2] + normals[fb, 2] + normals[fc, 2]
        wl = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        if wl > 1e-12:
            o0, o1, o2 = w0 / wl, w1 / wl, w2 / wl
    # The residual of the constraint placed by (the chord, or the length along the surface
    # over a feature: the distance to the unfolded parent) and of lying on the facet.
    plane = abs(
        _dot3(
            normals[best_face, 0],
            normals[best_face, 1],
            normals[best_face, 2],
            bp0 - corners[best_face, 0, 0],
            bp1 - corners[best_face, 0, 1],
            bp2 - corners[best_face, 0, 2],
        )
    )
    to_a = math.sqrt((bp0 - ba0) ** 2 + (bp1 - ba1) ** 2 + (bp2 - ba2) ** 2)
    to_b = math.sqrt((bp0 - bb0) ** 2 + (bp1 - bb1) ** 2 + (bp2 - bb2) ** 2)
    residual = max(plane, abs(to_a - spacing), abs(to_b - spacing))
    return _PLACED, bp0, bp1, bp2, best_face, o0, o1, o2, residual


@numba.njit(cache=True)
def place_nodes_kernel(
    corners,
    normals,
    neighbours,
    edge_normals,
    centroids,
    radii,
    reach,
    a,
    b,
    c,
    spacing,
    feature_cos,
    face_a,
    face_b,
    face_c,
    visited,
    queue,
    out_points,
    out_status,
    out_faces,
    out_normals,
    out_residual,
):
    """Nodes at chord ``spacing`` from a[i] and b[i] on the mesh, away from c[i] (module doc;
    :func:`_place_node` for each row). ``face_a``/``face_b``: the parents' triangles.
    ``visited`` (m,) bool all False and ``queue`` (m,) int64 are scratch (left all False).
    Writes points, NodeStatus codes, the node's triangle, its normal and its residual [m]."""
    for i in range(a.shape[0]):
        st, p0, p1, p2, f, n0, n1, n2, res = _place_node(
            corners, normals, neighbours, edge_normals, centroids, radii, reach,
            (a[i, 0], a[i, 1], a[i, 2]), (b[i, 0], b[i, 1], b[i, 2]),
            (c[i, 0], c[i, 1], c[i, 2]), spacing, feature_cos, face_a[i], face_b[i],
            face_c[i], visited, queue,
        )  # fmt: skip
        out_status[i] = st
        out_points[i, 0], out_points[i, 1], out_points[i, 2] = p0, p1, p2
        out_faces[i] = f
        out_normals[i, 0], out_normals[i, 1], out_normals[i, 2] = n0, n1, n2
        out_residual[i] = res


@numba.njit(cache=True)
def fill_fronts_kernel(
    corners,
    normals,
    neighbours,
    edge_normals,
    centroids,
    radii,
    reach,
    feature_cos,
    visited,
    queue,
    pos,
    status,
    residual,
    face,
    nj,
    start_flat,
    q_sa,
    q_sb,
    q_na,
    q_nb,
    last_front,
    spacing,
    lo,
    hi,
):
    """Every front of a net on the mesh, in place on ``pos``, ``status``, ``residual`` and
    ``face`` (flat, ni·nj; each placed node's triangle, the hint for its children), the
    generators already there: :func:`_place_node` for each node, then the checks every node
    of every tool goes through (``preform.drape.kernels.net_kernels._check_node``). Returns the
    number of fronts placed, as the front-by-front loop counts them.

    As ``preform.drape.kernels.net_kernels.fill_fronts``: a node needs only its three parents, so each
    quadrant is swept row by row instead of front by front, and the net is the same."""
    ready_on_front = np.zeros(last_front + 2, dtype=np.bool_)
    low, high = (lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2])
    for q in range(q_sa.shape[0]):
        da, db = q_sa[q] * nj, q_sb[q]
        orient = q_sa[q] * q_sb[q]  # the cell is oriented +u × +v whatever the quadrant
        for a_off in range(1, q_na[q] + 1):
            row = start_flat + a_off * da
            for b_off in range(1, q_nb[q] + 1):
                node = row + b_off * db
                ia, ib = node - da, node - db
                ic = ia - db
                if not _ready(status, node, ia, ib, ic):
                    continue
                ready_on_front[a_off + b_off] = True
                a = (pos[ia, 0], pos[ia, 1], pos[ia, 2])
                b = (pos[ib, 0], pos[ib, 1], pos[ib, 2])
                c = (pos[ic, 0], pos[ic, 1], pos[ic, 2])
                st, p0, p1, p2, f, n0, n1, n2, res = _place_node(
                    corners, normals, neighbours, edge_normals, centroids, radii, reach, a, b,
                    c, spacing, feature_cos, face[ia], face[ib], face[ic], visited, queue,
                )  # fmt: skip
                # The engine's checks (bounds, fold); the residual kept is the walk's own,
                # under its spacing rule (the length along the surface over a feature
                # crease, where the chord is shorter than d by design).
                st, _ = _check_node(
                    (p0, p1, p2), np.int8(st), a, b, c, orient, n0, n1, n2, res, spacing, low,
                    high,
                )  # fmt: skip
                if st == _PLACED:
                    pos[node, 0], pos[node, 1], pos[node, 2] = p0, p1, p2
                    residual[node] = res
                status[node] = st
                face[node] = f
    return _fronts_placed(ready_on_front, last_front)


@numba.njit(cache=True)
def geodesic_kernel(
    corners,
    normals,
    neighbours,
    edge_normals,
    centroids,
    start,
    start_face,
    direction,
    spacing,
    feature_cos,
    count,
    out_points,
    out_status,
    out_faces,
):
    """``count`` nodes along the straightest geodesic from start[g] on triangle start_face[g]
    in tangent direction[g], successive chords ``spacing`` [m] (module doc). Status PLACED,
    then OFF_TOOL from the node that would lie past the mesh's boundary on."""
    m = start.shape[0]
    max_crossings = 64 * neighbours.shape[0] + 1024
    for g in range(m):
        for j in range(count):
            out_status[g, j] = _OFF_TOOL
            out_faces[g, j] = -1
            for k in range(3):
                out_points[g, j, k] = np.nan
        f = start_face[g]
        x0, x1, x2 = start[g, 0], start[g, 1], start[g, 2]
        q0, q1, q2 = x0, x1, x2
        q_face = f
        n0, n1, n2 = normals[f, 0], normals[f, 1], normals[f, 2]
        t0, t1, t2 = direction[g, 0], direction[g, 1], direction[g, 2]
        tn = _dot3(t0, t1, t2, n0, n1, n2)
        t0, t1, t2 = t0 - tn * n0, t1 - tn * n1, t2 - tn * n2
        length = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        if length == 0.0:
            continue
        t0, t1, t2 = t0 / length, t1 / length, t2 / length
        entry = -1
        found = 0
        for _ in range(max_crossings):
            s_exit = np.inf
            k_exit = -1
            for k in range(3):
                if k == entry:
                    continue
                rate = _dot3(
                    edge_normals[f, k, 0], edge_normals[f, k, 1], edge_normals[f, k, 2], t0, t1, t2
                )
                if rate <= 1e-15:
                    continue
                gap = _dot3(
                    edge_normals[f, k, 0],
                    edge_normals[f, k, 1],
                    edge_normals[f, k, 2],
                    corners[f, k, 0] - x0,
                    corners[f, k, 1] - x1,
                    corners[f, k, 2] - x2,
                )
                s = max(gap, 0.0) / rate
                if s < s_exit:
                    s_exit, k_exit = s, k
            if k_exit < 0:
                break
            # Nodes on this straight piece: |x + s·t − q| = d, the root ahead, with q unfolded
            # into this triangle's plane if a feature lies between (surface length, module doc).
            while found < count:
                uq0, uq1, uq2, _ = _unfolded(
                    q0, q1, q2, q_face, f, normals, corners, centroids, feature_cos, spacing
                )
                w0, w1, w2 = x0 - uq0, x1 - uq1, x2 - uq2
                bb = _dot3(t0, t1, t2, w0, w1, w2)
                cc = w0 * w0 + w1 * w1 + w2 * w2 - spacing * spacing
                disc = bb * bb - cc
                if disc < 0.0:
                    break
                s_node = -bb + math.sqrt(disc)
                if -1e-9 * spacing < s_node < 0.0:
                    # The node fell on the edge just crossed, a rounding error behind.
                    s_node = 0.0
                if s_node < 0.0 or s_node > s_exit:
                    break
                x0, x1, x2 = x0 + s_node * t0, x1 + s_node * t1, x2 + s_node * t2
                s_exit -= s_node
                q0, q1, q2 = x0, x1, x2
                q_face = f
                out_points[g, found, 0], out_points[g, found, 1] = x0, x1
                out_points[g, found, 2] = x2
                out_status[g, found] = _PLACED
                out_faces[g, found] = f
                found += 1
            if found == count:
                break
            x0, x1, x2 = x0 + s_exit * t0, x1 + s_exit * t1, x2 + s_exit * t2
            nb = neighbours[f, k_exit]
            if nb < 0:
                break
            k1 = (k_exit + 1) % 3
            v0 = corners[f, k1, 0] - corners[f, k_exit, 0]
            v1 = corners[f, k1, 1] - corners[f, k_exit, 1]
            v2 = corners[f, k1, 2] - corners[f, k_exit, 2]
            vl = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
            v0, v1, v2 = v0 / vl, v1 / vl, v2 / vl
            along = _dot3(t0, t1, t2, v0, v1, v2)
            across = _dot3(
                t0,
                t1,
                t2,
                edge_normals[f, k_exit, 0],
                edge_normals[f, k_exit, 1],
                edge_normals[f, k_exit, 2],
            )
            entry = -1
            for k in range(3):
                if neighbours[nb, k] == f:
                    entry = k
                    break
            if entry < 0:
                break
            # Into the next triangle: against its own outward normal of the shared edge.
            u0 = along * v0 - across * edge_normals[nb, entry, 0]
            u1 = along * v1 - across * edge_normals[nb, entry, 1]
            u2 = along * v2 - across * edge_normals[nb, entry, 2]
            ul = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
            t0, t1, t2 = u0 / ul, u1 / ul, u2 / ul
            f = nb
