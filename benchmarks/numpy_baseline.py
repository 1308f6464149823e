"""The numpy drape path as it was before the compiled kernels (issue 15): the baseline of the
speed ratios in ``bench_kernels.py``, measured in the same process.

A frozen copy, reachable only from the benchmarks (never imported by preform or its tests): the
wavefront fill with the sphere's vectorised closed form and the vectorised Newton placement,
the cell fields and cell status, the node shear, the shear extremes and the summary, the
cut-cell share, the surrogate's Hermite evaluation and the coverage with its dependency
shadows, each as numpy code vectorised over a front or over the net. :func:`numpy_path` swaps
them into the drape step for the duration of a ``with`` block.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from preform.drape import steps as steps_module
from preform.drape.engine import fields as fields_module
from preform.drape.engine.generators import (
    ClosedFormGeodesics,
    GeneratorNodes,
    _across_crease,
    _chord_on_bent_path,
    _finish,
    _residual,
    plan_generators,
)
from preform.drape.engine.net import (
    ClosedFormPlacement,
    DrapeError,
    PlanPolylines,
    _lift_to_tangent,
    _split_polyline,
)
from preform.drape.engine.part import Part
from preform.drape.engine.ply import PlyOutline
from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField, NodeStatus
from preform.drape.engine.surface import Surface
from preform.drape.judging import verdict as verdict_module
from preform.drape.judging.verdict import (
    Coverage,
    _fold_zones,
    flat_plan_positions,
    generator_stops_on_tool,
)
from preform.plugins.surfaces.basic import Hemisphere, Sphere
from preform.shear import surrogate as surrogate_module
from preform.shear.law import ShearLaw

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
StatusArray = NDArray[np.int8]
CentroidPredicate = Callable[[FloatArray], BoolArray]
_PLACED = np.int8(NodeStatus.PLACED)
_NOT_REACHED = np.int8(NodeStatus.NOT_REACHED)


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("ij,ij->i", a, b)


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def _norm(a: FloatArray) -> FloatArray:
    return np.sqrt(_dot(a, a))


def _unit(a: FloatArray) -> FloatArray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / _norm(a)[:, None]


def _solve_on_circle(
    surface: Surface,
    a: FloatArray,
    b: FloatArray,
    c: FloatArray,
    spacing: float,
    tolerance_m: float,
    max_iterations: int,
) -> tuple[FloatArray, StatusArray, int]:
    """Nodes at chord ``spacing`` from a and b on the surface, away from c (see module doc).

    Returns points (m, 3) (NaN where not placed), NodeStatus codes and the iterations used.
    """
    m = len(a)
    points = np.full((m, 3), np.nan)
    status = np.full(m, NodeStatus.NO_INTERSECTION, dtype=np.int8)
    mid = 0.5 * (a + b)
    chord = b - a
    radius2 = spacing * spacing - 0.25 * _dot(chord, chord)
    e = _unit(chord)
    guess, _ = surface.closest_point(a + b - c)
    n0 = surface.normal(guess)
    a1 = _unit(n0 - _dot(n0, e)[:, None] * e)
    a2 = _cross(e, a1)
    a2 *= np.where(_dot(c - mid, a2) > 0, -1.0, 1.0)[:, None]
    radius = np.sqrt(np.maximum(radius2, 0.0))
    rel = guess - mid
    phi = np.clip(np.arctan2(_dot(rel, a2), _dot(rel, a1)), 0.0, np.pi)
    active = np.flatnonzero((radius2 > 0) & np.isfinite(a1[:, 0]) & np.isfinite(phi))
    used = 0
    for used in range(1, max_iterations + 1):  # the last value is reported
        if active.size == 0:
            break
        p_act, r_act = phi[active], radius[active]
        cos_p, sin_p = np.cos(p_act), np.sin(p_act)
        x = mid[active] + r_act[:, None] * (
            cos_p[:, None] * a1[active] + sin_p[:, None] * a2[active]
        )
        foot, dist = surface.closest_point(x)
        n = surface.normal(foot)
        offset = x - foot
        g = _dot(offset, n)
        done = dist <= tolerance_m
        points[active[done]] = x[done]
        status[active[done]] = NodeStatus.PLACED
        slope = r_act * (-sin_p * _dot(n, a1[active]) + cos_p * _dot(n, a2[active]))
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.clip(-g / slope, -0.5, 0.5)
        step = np.where(np.isfinite(step), step, 0.0)
        new_phi = np.clip(p_act + step, 0.0, np.pi)
        # A point whose closest point is an edge of the tool has an offset with a tangential
        # part; an interior closest point has a purely normal one.
        tangential = _norm(offset - g[:, None] * n) > 0.5 * dist
        stuck = ~done & (np.abs(new_phi - p_act) <= 1e-15 * np.pi)
        last_try = used == max_iterations
        fail = ~done & (stuck | last_try)
        status[active[fail & tangential]] = NodeStatus.OFF_TOOL
        phi[active] = new_phi
        active = active[~done & ~fail]
    return points, status, used


# --------------------------------------------------------------------------------------------
# The start and the generators


def drape(
    surface: Surface,
    *,
    node_spacing_m: float,
    ply: PlyOutline,
    start_xy_m: ArrayLike | None = None,
    start_point: ArrayLike | None = None,
    orientation_rad: float | None = 0.0,
    generator_angle_rad: float | None = 0.5 * np.pi,
    generators: str | PlanPolylines | object = "geodesic",
    trim: Callable[[FloatArray], BoolArray] | None = None,
    tolerance: float = 1e-9,
    max_iterations: int = 30,
    substeps: int = 16,
    use_closed_form: bool = True,
) -> DrapeResult:
    """Drape a ply over ``surface`` as a pin-jointed net.

    Parameters
    ----------
    surface: the tool (any :class:`~preform.drape.engine.surface.Surface`).
    node_spacing_m: node spacing d [m], the chord between neighbouring crossovers.
    ply: the ply outline in the flat; its origin is the start point, its axes the fibres.
    start_xy_m: plan position (x, y) [m] of the start point, put on the tool's top with
        ``point_at_plan``. Or ``start_point``: a 3-D point [m] already on the tool.
    orientation_rad: plan direction [rad from the tool's x axis] of the first generator (+u)
        at the start.
    generator_angle_rad: angle α [rad] from +u to +v at the start, counter-clockwise seen from
        the outward normal, in the tangent plane; 0 < α < π.
    generators: "geodesic", "plan" (tool surface above straight plan lines), or
        :class:`PlanPolylines` (then orientation and α follow from the polylines; pass None),
        or paths with a ``nodes`` method (:class:`preform.optimise.curved.CurvedGenerators`).
    trim: predicate on cell centroids (n, 3) [m] giving the part (default: every valid cell).
    tolerance: relative tolerance; every solve stops at ``tolerance``·d [m].
    max_iterations: cap on Newton steps per front on surfaces without a closed form.
    substeps: sub-steps per node spacing when marching generators.
    use_closed_form: use the surface's closed forms when it has them.

    Raises :class:`DrapeError` for a set-up that cannot give a net at all (start off the tool,
    start outside the ply, α outside (0, π), d ≤ 0). Everything else, including a net that
    runs off the tool, comes back as node statuses.
    """
    clock = time.perf_counter()
    surface = as_numpy_tool(surface)
    d = float(node_spacing_m)
    if not (np.isfinite(d) and d > 0):
        raise DrapeError(f"node spacing must be a positive length, got {node_spacing_m!r} m")
    if not 0 < tolerance < 1e-2:
        raise DrapeError(f"tolerance is relative to the node spacing; got {tolerance!r}")
    tol_m = tolerance * d

    # The start point.
    if (start_xy_m is None) == (start_point is None):
        raise DrapeError("give exactly one of start_xy_m (plan) and start_point (3-D)")
    if start_xy_m is not None:
        start_xy = np.asarray(start_xy_m, dtype=float).reshape(2)
        pts, mask = surface.point_at_plan(start_xy[None, :])
        if not bool(mask[0]) or not np.all(np.isfinite(pts[0])):
            raise DrapeError(
                f"the start point (x, y) = ({start_xy[0]:.6g}, {start_xy[1]:.6g}) m is not over "
                f"the tool (bounds {surface.bounds} m)"
            )
        start = pts[0]
    else:
        point = np.asarray(start_point, dtype=float).reshape(1, 3)
        foot, dist = surface.closest_point(point)
        if not dist[0] <= max(1e-6 * surface.size, tol_m):
            raise DrapeError(f"the start point is {dist[0]:.3g} m from the tool surface")
        start = foot[0]
        start_xy = start[:2].copy()
    normal = surface.normal(start[None, :])[0]

    # The generator directions at the start.
    polyline_halves: list[FloatArray] | None = None
    if isinstance(generators, PlanPolylines):
        if orientation_rad is not None and generator_angle_rad is not None:
            if (orientation_rad, generator_angle_rad) != (0.0, 0.5 * np.pi):
                raise DrapeError("with PlanPolylines the polylines set orientation and angle")
        fu, bu = _split_polyline(generators.first_xy_m, start_xy, 1e-6 * d)
        fv, bv = _split_polyline(generators.second_xy_m, start_xy, 1e-6 * d)
        polyline_halves = [fu, bu, fv, bv]
        lifted_u = _lift_to_tangent(fu[1] - fu[0], normal)
        lifted_v = _lift_to_tangent(fv[1] - fv[0], normal)
        if lifted_u is None or lifted_v is None:
            raise DrapeError("a generator polyline crosses a vertical wall at the start point")
        t_u, t_v = lifted_u, lifted_v
        alpha = float(np.arctan2(_cross(t_u[None], t_v[None])[0] @ normal, t_u @ t_v))
        theta = float(np.arctan2(fu[1, 1] - fu[0, 1], fu[1, 0] - fu[0, 0]))
        if not 0 < alpha < np.pi:
            raise DrapeError(
                f"the second generator polyline is {np.degrees(alpha):.3g}° from the first; it "
                "must be counter-clockwise from it (seen from the outward normal), 0 < α < 180°"
            )
    elif hasattr(generators, "nodes") or generators in ("geodesic", "plan"):
        if orientation_rad is None or generator_angle_rad is None:
            raise DrapeError("orientation_rad and generator_angle_rad are required")
        theta, alpha = float(orientation_rad), float(generator_angle_rad)
        if not 0 < alpha < np.pi:
            raise DrapeError(f"generator angle must lie in (0, π) rad, got {alpha!r}")
        lifted = _lift_to_tangent(np.array([np.cos(theta), np.sin(theta)]), normal)
        if lifted is None:
            raise DrapeError(
                "the tool is vertical at the start point and the orientation is not tangential "
                "to it"
            )
        t_u = lifted
        t_v = np.cos(alpha) * t_u + np.sin(alpha) * _cross(normal[None], t_u[None])[0]
    else:
        raise DrapeError(
            f"generators must be 'geodesic', 'plan' or PlanPolylines, got {generators!r}"
        )

    # The grid and the ply.
    try:
        grid = ply.node_grid(d)
    except ValueError as exc:
        raise DrapeError(str(exc)) from exc
    ni, nj = grid.shape
    i0, j0 = grid.start_index
    n_nodes = ni * nj
    pos = np.full((n_nodes, 3), np.nan)
    status = np.full(n_nodes, NodeStatus.NOT_REACHED, dtype=np.int8)
    status[~grid.inside.ravel()] = NodeStatus.OUTSIDE_PLY
    residual = np.zeros(n_nodes)
    start_flat = i0 * nj + j0
    pos[start_flat] = start
    status[start_flat] = NodeStatus.PLACED
    residual[start_flat] = float(surface.closest_point(start[None, :])[1][0])

    # Generators: +u, −u, +v, −v.
    counts = (ni - 1 - i0, i0, nj - 1 - j0, j0)
    gen = _old_generators(
        surface,
        start,
        start_xy,
        t_u,
        t_v,
        generators,
        d,
        counts,
        substeps,
        tolerance,
        use_closed_form,
        polyline_halves,
    )
    steps = ((nj, 0), (-nj, 0), (1, 1), (-1, 1))
    for row, (count, (stride, _)) in enumerate(zip(counts, steps, strict=True)):
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

    # The wavefronts.
    fill_clock = time.perf_counter()
    fill_cpu = time.process_time()
    closed_form = use_closed_form and isinstance(surface, ClosedFormPlacement)
    assert not closed_form or isinstance(surface, Sphere), (
        "the baseline's closed form is the sphere's"
    )
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
    newton_iterations = 0
    fronts = 0
    # Node (i0 + sa·a, j0 + sb·b) with a + b = k has flat index
    # i0·nj + j0 + sb·k + a·(sa·nj − sb): each quadrant's part of a front is an arithmetic run.
    q_sa = np.array([q[0] for q in quadrants], dtype=np.int64)
    q_sb = np.array([q[1] for q in quadrants], dtype=np.int64)
    q_na = np.array([q[2] for q in quadrants], dtype=np.int64)
    q_nb = np.array([q[3] for q in quadrants], dtype=np.int64)
    q_step = q_sa * nj - q_sb
    for k in range(2, last_front + 1):
        a_lo = np.maximum(1, k - q_nb)
        lens = np.maximum(np.minimum(q_na, k - 1) - a_lo + 1, 0)
        total = int(lens.sum())
        first = np.cumsum(lens) - lens
        a_off = np.arange(total) + np.repeat(a_lo - first, lens)
        node = np.repeat(start_flat + q_sb * k, lens) + a_off * np.repeat(q_step, lens)
        da, db = np.repeat(q_sa * nj, lens), np.repeat(q_sb, lens)
        ia, ib = node - da, node - db
        ic = ia - db
        ready = (
            (status[node] == _NOT_REACHED)
            & (status[ia] == _PLACED)
            & (status[ib] == _PLACED)
            & (status[ic] == _PLACED)
        )
        if not ready.any():
            if k > 2:
                # Every node of front k has a parent in front k − 1 off the generators.
                break
            continue
        fronts += 1
        node, ia, ib, ic = node[ready], ia[ready], ib[ready], ic[ready]
        orient = np.sign(da[ready]) * db[ready]
        a, b, c = pos[ia], pos[ib], pos[ic]
        if closed_form:
            # closed_form: the surface has its own exact placement (the sphere)
            p, st = sphere_place_nodes(surface, a, b, c, d)
            st = np.asarray(st, dtype=np.int8).copy()
        else:
            p, st, used = _solve_on_circle(surface, a, b, c, d, tol_m, max_iterations)
            newton_iterations = max(newton_iterations, used)
        ok = st == _PLACED
        if ok.any():
            p_ok = p[ok]
            past = np.any((p_ok < lo_bound) | (p_ok > hi_bound), axis=1)
            # The cell this node completes, oriented +u × +v whatever the quadrant.
            cell_normal = orient[ok][:, None] * _cross(p_ok - c[ok], a[ok] - b[ok])
            folded = _dot(cell_normal, surface.normal(p_ok)) <= 0
            sub = st[ok]
            sub[folded] = NodeStatus.FOLDED
            sub[past] = NodeStatus.OFF_TOOL
            st[ok] = sub
            ok = st == _PLACED
            p_ok = p[ok]
            dist = surface.closest_point(p_ok)[1]
            res = np.maximum.reduce(
                [
                    np.abs(_norm(p_ok - a[ok]) - d),
                    np.abs(_norm(p_ok - b[ok]) - d),
                    dist,
                ]
            )
            pos[node[ok]] = p_ok
            residual[node[ok]] = res
        status[node] = st

    fill_seconds = time.perf_counter() - fill_clock
    fill_cpu_seconds = time.process_time() - fill_cpu
    nodes = pos.reshape(ni, nj, 3)
    node_status = status.reshape(ni, nj)
    fields = cell_fields(nodes, node_status, trim=trim)
    placed = status == _PLACED
    info: dict[str, object] = {
        "placement": "closed form" if closed_form else "newton on the constraint circle",
        "generators": generators if isinstance(generators, str) else "plan polylines",
        "tolerance_m": tol_m,
        "max_residual_m": float(residual[placed].max()) if placed.any() else 0.0,
        "newton_iterations_max": newton_iterations,
        "fronts": fronts,
        "seconds": time.perf_counter() - clock,
        "fill_seconds": fill_seconds,
        "fill_cpu_seconds": fill_cpu_seconds,
    }
    return DrapeResult(
        nodes=nodes,
        status=node_status,
        residual=residual.reshape(ni, nj),
        start_index=(i0, j0),
        node_spacing=d,
        generator_angle=alpha,
        orientation=theta,
        info=info,
        **fields,
    )


# Vectors as (x, y, z) triples of contiguous 2-D arrays: a million cells' worth of cross
# products is several times faster this way than on strided (…, 3) views.
Vec = tuple[FloatArray, FloatArray, FloatArray]


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _vdot(a: Vec, b: Vec) -> FloatArray:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross_norm(a: Vec, b: Vec) -> FloatArray:
    cx = a[1] * b[2] - a[2] * b[1]
    cy = a[2] * b[0] - a[0] * b[2]
    cz = a[0] * b[1] - a[1] * b[0]
    return np.sqrt(cx * cx + cy * cy + cz * cz)


def _angle(a: Vec, b: Vec) -> FloatArray:
    """Angle [rad, 0..π] between vectors; atan2 keeps it accurate near 0 and π too."""
    return np.arctan2(_cross_norm(a, b), _vdot(a, b))


def _stack_unit(a: Vec, valid: BoolArray) -> FloatArray:
    length = np.sqrt(_vdot(a, a))
    out = np.zeros((*length.shape, 3))
    for k in range(3):
        np.divide(a[k], length, out=out[..., k], where=valid)
    return out


def cell_status(status: NDArray[np.int8]) -> NDArray[np.int8]:
    """CellStatus per cell from its corners' NodeStatus (numpy, as before the kernels)."""
    corners = [status[:-1, :-1], status[1:, :-1], status[:-1, 1:], status[1:, 1:]]
    out = np.full(corners[0].shape, CellStatus.VALID, dtype=np.int8)
    missing = np.zeros(out.shape, dtype=bool)
    folded = np.zeros(out.shape, dtype=bool)
    outside = np.zeros(out.shape, dtype=bool)
    for corner in corners:
        missing |= corner != NodeStatus.PLACED
        folded |= corner == NodeStatus.FOLDED
        outside |= corner == NodeStatus.OUTSIDE_PLY
    out[missing] = CellStatus.INCOMPLETE
    out[folded] = CellStatus.FOLDED
    out[outside] = CellStatus.OUTSIDE_PLY
    return out


def cell_fields(
    nodes: FloatArray,
    status: NDArray[np.int8],
    *,
    trim: Part | CentroidPredicate | None = None,
) -> dict[str, Any]:
    """The cell arrays of a :class:`DrapeResult` from node positions (ni, nj, 3) [m] and
    statuses (ni, nj): ``cell_status``, ``shear`` [rad], ``centroid`` [m], ``area`` [m²],
    ``fibre_u``, ``fibre_v`` (unit), ``in_part`` and ``part_share``. ``trim`` is a
    :class:`~preform.drape.engine.part.Part` (cells cut by its edge count by their undeformed area
    inside it: ``part_share``; ``in_part`` is every valid cell with some area inside) or a
    predicate on centroids (a cell is in or out whole). Without it every valid cell counts
    whole. Zero (NaN for centroids) where not VALID."""
    c_status = cell_status(status)
    valid = c_status == CellStatus.VALID
    shape = valid.shape
    shear = np.zeros(shape)
    area = np.zeros(shape)
    centroid = np.full((*shape, 3), np.nan)
    fibre_u = np.zeros((*shape, 3))
    fibre_v = np.zeros((*shape, 3))
    comp = [nodes[..., k] for k in range(3)]
    # Row blocks of ~16k cells keep every temporary in cache; whole-net temporaries of a
    # million cells cost more in page faults than in arithmetic.
    rows = max(1, 16384 // max(shape[1], 1))
    for r0 in range(0, shape[0], rows):
        r1 = min(r0 + rows, shape[0])
        x00: Vec = (comp[0][r0:r1, :-1], comp[1][r0:r1, :-1], comp[2][r0:r1, :-1])
        x10: Vec = (
            comp[0][r0 + 1 : r1 + 1, :-1],
            comp[1][r0 + 1 : r1 + 1, :-1],
            comp[2][r0 + 1 : r1 + 1, :-1],
        )
        x01: Vec = (comp[0][r0:r1, 1:], comp[1][r0:r1, 1:], comp[2][r0:r1, 1:])
        x11: Vec = (
            comp[0][r0 + 1 : r1 + 1, 1:],
            comp[1][r0 + 1 : r1 + 1, 1:],
            comp[2][r0 + 1 : r1 + 1, 1:],
        )
        ok = valid[r0:r1]
        with np.errstate(invalid="ignore", divide="ignore"):
            u_low, u_high = _sub(x10, x00), _sub(x11, x01)
            v_left, v_right = _sub(x01, x00), _sub(x11, x10)
            omega = 0.25 * (
                _angle(u_low, v_left)
                + _angle(u_low, v_right)
                + _angle(u_high, v_left)
                + _angle(u_high, v_right)
            )
            shear[r0:r1] = np.where(ok, omega - 0.5 * np.pi, 0.0)
            for k in range(3):
                mean = 0.25 * (x00[k] + x10[k] + x01[k] + x11[k])
                centroid[r0:r1, :, k] = np.where(ok, mean, np.nan)
            diag, anti = _sub(x11, x00), _sub(x01, x10)
            # Split along (i, j)-(i+1, j+1), then along (i+1, j)-(i, j+1); average.
            split_a = _cross_norm(u_low, diag) + _cross_norm(diag, v_left)
            split_b = _cross_norm(u_low, anti) + _cross_norm(anti, v_right)
            area[r0:r1] = np.where(ok, 0.25 * (split_a + split_b), 0.0)
            fibre_u[r0:r1] = _stack_unit(_add(u_low, u_high), ok)
            fibre_v[r0:r1] = _stack_unit(_add(v_left, v_right), ok)
    in_part = valid.copy()
    share = valid.astype(float)
    if isinstance(trim, Part):
        # Cut cells count by their undeformed area inside the part (preform.drape.engine.part).
        with np.errstate(invalid="ignore"):
            phi = np.asarray(trim.level(nodes), dtype=float)
            cut = cell_part_share(phi[:-1, :-1], phi[1:, :-1], phi[:-1, 1:], phi[1:, 1:])
        share = np.where(valid, np.nan_to_num(cut, nan=0.0), 0.0)
        in_part &= share > 0.0
    elif trim is not None and valid.any():
        in_part[valid] &= np.asarray(trim(centroid[valid]), dtype=bool)
        share = in_part.astype(float)
    return {
        "part_share": share,
        "cell_status": c_status,
        "shear": shear,
        "centroid": centroid,
        "area": area,
        "fibre_u": fibre_u,
        "fibre_v": fibre_v,
        "in_part": in_part,
    }


def node_shear(result: DrapeResult) -> FloatArray:
    """Signed shear γ at every node (ni, nj) [rad], NaN where it cannot be formed.

    At node (i, j) the fibre edges to (i±1, j) and (i, j±1) form up to four corners (the +u
    or −u edge with the +v or −v edge, each taken in its + sense); γ is the mean of their
    angles ω minus 90°, as for a cell (so it is centred on the node: second-order accurate
    where all four exist). Unlike the cell value, which is the shear at a cell centre, the
    node value reaches the part's edge itself: nodes are where the extremes are read."""
    p = np.asarray(result.nodes, dtype=float)
    placed = result.status == NodeStatus.PLACED
    ni, nj = placed.shape
    nan = np.full((ni, nj, 3), np.nan)
    u_fwd, u_bwd, v_fwd, v_bwd = nan.copy(), nan.copy(), nan.copy(), nan.copy()
    u_fwd[:-1] = p[1:] - p[:-1]
    u_bwd[1:] = p[1:] - p[:-1]
    v_fwd[:, :-1] = p[:, 1:] - p[:, :-1]
    v_bwd[:, 1:] = p[:, 1:] - p[:, :-1]
    total = np.zeros((ni, nj))
    count = np.zeros((ni, nj))
    with np.errstate(invalid="ignore"):
        for u in (u_fwd, u_bwd):
            for v in (v_fwd, v_bwd):
                uu: Vec = (u[..., 0], u[..., 1], u[..., 2])
                vv: Vec = (v[..., 0], v[..., 1], v[..., 2])
                omega = _angle(uu, vv)
                ok = np.isfinite(omega)
                total += np.where(ok, omega, 0.0)
                count += ok
        gamma = np.where(placed & (count > 0), total / np.maximum(count, 1) - 0.5 * np.pi, np.nan)
    return np.asarray(gamma)


def _triangle_inside_share(f0: FloatArray, f1: FloatArray, f2: FloatArray) -> FloatArray:
    """Share (0..1) of a triangle where the linear function with corner values f0, f1, f2 is
    ≥ 0. Vectorised. With the corners sorted a ≤ b ≤ c the zero set cuts off a corner
    triangle, whose share is a product of the two edge fractions."""
    s = np.sort(np.stack([f0, f1, f2]), axis=0)
    a, b, c = s[0], s[1], s[2]
    out = np.zeros_like(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        # One corner inside (a ≤ b < 0 ≤ c): the inside is the triangle at c.
        one = (b < 0) & (c >= 0)
        share_one = (c / (c - a)) * (c / (c - b))
        # Two corners inside (a < 0 ≤ b): the outside is the triangle at a.
        two = (a < 0) & (b >= 0)
        share_two = 1.0 - (a / (a - b)) * (a / (a - c))
    out = np.where(a >= 0, 1.0, out)
    out = np.where(one, np.nan_to_num(share_one), out)
    out = np.where(two, np.nan_to_num(share_two, nan=1.0), out)
    return np.clip(out, 0.0, 1.0)


def cell_part_share(
    phi00: ArrayLike, phi10: ArrayLike, phi01: ArrayLike, phi11: ArrayLike
) -> FloatArray:
    """Share (0..1) of each cell's undeformed square inside the part, from φ at its corners
    (i, j), (i+1, j), (i, j+1), (i+1, j+1) (module docstring: exact for an affine φ)."""
    f00, f10, f01, f11 = (np.asarray(f, dtype=float) for f in (phi00, phi10, phi01, phi11))
    # Split along (i, j)-(i+1, j+1), then along (i+1, j)-(i, j+1); average.
    split_a = 0.5 * (_triangle_inside_share(f00, f10, f11) + _triangle_inside_share(f00, f11, f01))
    split_b = 0.5 * (_triangle_inside_share(f00, f10, f01) + _triangle_inside_share(f10, f11, f01))
    return np.asarray(0.5 * (split_a + split_b))


def sphere_place_nodes(
    self: Sphere, a: FloatArray, b: FloatArray, opposite: FloatArray, spacing: float
) -> tuple[FloatArray, StatusArray]:
    """Net nodes (m, 3) [m] at chord ``spacing`` [m] from ``a`` and ``b`` (m, 3) on the side
    away from ``opposite``, with NodeStatus codes (m,).

    Closed form (PHYSICS §6): relative to the centre, P·A = P·B = R² − d²/2 and |P| = R. P
    lies in the plane spanned by A + B and n = A × B; the root on the far side of the
    plane (0, A, B) from the opposite node is the new node.
    """
    r = self.radius
    pa, pb, pc = a - self.centre, b - self.centre, opposite - self.centre
    along = pa + pb
    along_len = np.sqrt(_dot(along, along))
    n = _cross(pa, pb)
    n_len = np.sqrt(_dot(n, n))
    with np.errstate(divide="ignore", invalid="ignore"):
        height = (2.0 * r * r - spacing * spacing) / along_len
        off2 = r * r - height * height
        ok = (off2 >= 0) & (n_len > 1e-12 * r * spacing)
        away = np.where(_dot(pc, n) > 0, -1.0, 1.0)
        p = (height / along_len)[:, None] * along + (
            away * np.sqrt(np.where(ok, off2, 0.0)) / n_len
        )[:, None] * n
    p += self.centre
    status = np.where(ok, NodeStatus.PLACED, NodeStatus.NO_INTERSECTION).astype(np.int8)
    status[ok & ~self._on_tool(p, spacing)] = NodeStatus.OFF_TOOL
    p[status != NodeStatus.PLACED] = np.nan
    return p, status


def _sense_energy(self: Any, u: FloatArray) -> FloatArray:
    """W(u) [J/m²] by cubic Hermite interpolation."""
    k, t, h = self._locate(u)
    t2, t3 = t * t, t * t * t
    h00, h10 = 2 * t3 - 3 * t2 + 1, t3 - 2 * t2 + t
    h01, h11 = -2 * t3 + 3 * t2, t3 - t2
    w = (
        h00 * self.energy[k]
        + h10 * h * self.slope_left[k]
        + h01 * self.energy[k + 1]
        + h11 * h * self.slope_right[k]
    )
    # energy of a non-negative law never decreases: a cubic overshoot must not say so
    return np.maximum(w, np.minimum(self.energy[k], self.energy[k + 1]))


# ---------------------------------------------------------------------------------------------
# Generators and the hemisphere's queries, as they were


def _gdot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...i,...i->...", a, b)


def _gunit(a: FloatArray) -> FloatArray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / np.sqrt(_gdot(a, a))[..., None]


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


def _march_geodesics(
    surface: Surface,
    starts: FloatArray,
    directions: FloatArray,
    spacing: float,
    count: int,
    substeps: int,
    tolerance: float,
) -> GeneratorNodes:
    m = len(starts)
    h = spacing / max(int(substeps), 1)
    points = np.full((m, count, 3), np.nan)
    on_tool = np.zeros((m, count), dtype=bool)
    found = np.zeros(m, dtype=int)
    running = np.ones(m, dtype=bool)
    x = starts.copy()
    t = _gunit(np.asarray(directions, dtype=float))
    normal = surface.normal(starts)
    last = starts.copy()
    # A generator that keeps turning back (a closed geodesic shorter than d) must still stop.
    for _ in range(4 * count * max(int(substeps), 1) + 16):
        act = np.flatnonzero(running & (found < count))
        if act.size == 0:
            break
        xa, ta, na = x[act], t[act], normal[act]
        # Straight continuation, brought back to the tool along the normal at x_k (the
        # discrete geodesic equation): projecting along the normal at the new point instead
        # would leave an O(h³) sideways error per step, i.e. an O(h) drift overall.
        ahead = xa + h * ta
        foot, _ = surface.closest_point(ahead)
        n_foot = surface.normal(foot)
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = _gdot(foot - ahead, n_foot) / _gdot(na, n_foot)
        # A sharp crease (a mesh edge onto a vertical wall): the tangent plane turns by more
        # than 60° within one sub-step, and the correction along the old normal is undefined.
        crease = np.abs(_gdot(na, n_foot)) < 0.5
        lam = np.where(crease, 0.0, lam)
        x_new, dist = surface.closest_point(ahead + lam[:, None] * na)
        if crease.any():
            x_new[crease], dist[crease] = _across_crease(
                surface, ta[crease], na[crease], foot[crease], n_foot[crease], h
            )
        step = x_new - xa
        # across a crease the path bends, so progress is the step's length, not its projection
        progress = np.where(crease, np.linalg.norm(step, axis=-1), _gdot(step, ta))
        # Past the edge the closest point sticks to the boundary: no progress, or far away.
        off = ~np.isfinite(progress) | (progress < 0.5 * h) | (dist > 0.5 * h)
        running[act[off]] = False
        keep = ~off
        act, xa, x_new, step = act[keep], xa[keep], x_new[keep], step[keep]
        n_new, via, bent = n_foot[keep], foot[keep], crease[keep]
        w = xa - last[act]
        reach = _gdot(x_new - last[act], x_new - last[act]) >= spacing * spacing
        if reach.any():
            idx = act[reach]
            s, wr = step[reach], w[reach]
            ss, ws = _gdot(s, s), _gdot(wr, s)
            tau = (-ws + np.sqrt(np.maximum(ws * ws - ss * (_gdot(wr, wr) - spacing**2), 0))) / ss
            node = xa[reach] + tau[:, None] * s
            node = _slide_to_chord(surface, last[idx], node, spacing, tolerance)
            folded = bent[reach]
            if folded.any():
                # across a crease the straight chord cuts through the tool: find the node on
                # the two flat pieces of the path (start -> crease -> new point) instead
                node[folded] = _chord_on_bent_path(
                    last[idx][folded],
                    xa[reach][folded],
                    via[reach][folded],
                    x_new[reach][folded],
                    spacing,
                )
            points[idx, found[idx]] = node
            on_tool[idx, found[idx]] = True
            found[idx] += 1
            last[idx] = node
        x[act] = x_new
        t[act] = _gunit(step)
        # The foot of the first projection is O(h³) from x_{k+1}: its normal serves there.
        normal[act] = n_new
    return _finish(points, on_tool, _residual(surface, points, starts[0], spacing))


def _slide_to_chord(
    surface: Surface, anchor: FloatArray, guess: FloatArray, spacing: float, tolerance: float
) -> FloatArray:
    """Move surface points ``guess`` to chord ``spacing`` from ``anchor`` keeping their
    direction: alternate rescaling and projection (each round shrinks the error by ~(d/R)²)."""
    node = guess
    for _ in range(8):
        node = anchor + spacing * _gunit(node - anchor)
        node, _ = surface.closest_point(node)
        chord = np.sqrt(_gdot(node - anchor, node - anchor))
        if np.all(np.abs(chord - spacing) <= tolerance * spacing):
            break
    return node


def _old_generators(
    surface: Surface,
    start: FloatArray,
    start_xy: FloatArray,
    t_u: FloatArray,
    t_v: FloatArray,
    kind: str | PlanPolylines | object,
    spacing: float,
    counts: tuple[int, int, int, int],
    substeps: int,
    tolerance: float,
    use_closed_form: bool,
    polyline_halves: list[FloatArray] | None,
) -> GeneratorNodes:
    """Nodes on the four half-generators +u, −u, +v, −v."""
    count = max(counts)
    if kind == "geodesic":
        directions = np.stack([t_u, -t_u, t_v, -t_v])
        return geodesic_generators(
            surface,
            start,
            directions,
            spacing,
            count,
            substeps=substeps,
            tolerance=tolerance,
            use_closed_form=use_closed_form,
        )
    if kind == "plan":
        lines = []
        for t in (t_u, -t_u, t_v, -t_v):
            if np.hypot(t[0], t[1]) <= 1e-9:
                raise DrapeError(
                    "a generator is vertical at the start point, so it has no plan direction; "
                    "use geodesic generators"
                )
            lines.append(np.vstack([start_xy, start_xy + spacing * t[:2] / np.hypot(*t[:2])]))
        return plan_generators(
            surface, start, lines, spacing, count, substeps=substeps, tolerance=tolerance
        )
    if hasattr(kind, "nodes"):
        # Paths that build their own nodes, e.g. preform.optimise.curved.CurvedGenerators.
        return kind.nodes(
            surface, start, t_u, t_v, spacing, count, substeps=substeps, tolerance=tolerance
        )
    assert polyline_halves is not None
    return plan_generators(
        surface, start, polyline_halves, spacing, count, substeps=substeps, tolerance=tolerance
    )


class NumpyHemisphere(Hemisphere):
    """The hemisphere with its numpy closest point and normal of before the compiled queries."""

    def _radial(self, points: FloatArray) -> FloatArray:
        """Unit directions from the centre; +z for the centre itself (any choice is closest)."""
        rel = np.asarray(points, dtype=float) - self.centre
        length = np.sqrt(_gdot(rel, rel))
        at_centre = length == 0
        if at_centre.any():
            rel[at_centre] = (0.0, 0.0, 1.0)
            length[at_centre] = 1.0
        rel /= length[:, None]
        return rel

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at sphere points (n, 3) [m]."""
        return self._radial(points)

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest points on the tool [m] (on its lower edge for points below it) and
        distances."""
        p = np.asarray(points, dtype=float)
        radial = self._radial(p)
        floor = -self.run_off / self.radius
        below = radial[:, 2] < floor
        if np.any(below):
            flat = radial[below].copy()
            flat[:, 2] = 0.0
            length = np.sqrt(_gdot(flat, flat))
            flat = np.where(
                length[:, None] > 0,
                flat / np.where(length > 0, length, 1.0)[:, None],
                np.array([1.0, 0.0, 0.0]),
            )
            # The edge circle at height floor·R: radial = (cos·flat, sin) with sin = floor.
            radial[below] = np.sqrt(1.0 - floor * floor) * flat
            radial[below, 2] = floor
        q = self.centre + self.radius * radial
        return q, np.sqrt(_gdot(p - q, p - q))


def as_numpy_tool(surface: Any) -> Any:
    """The numpy hemisphere for a Hemisphere (same radius, centre and run-off), else itself."""
    if isinstance(surface, Hemisphere) and not isinstance(surface, NumpyHemisphere):
        run_off = surface.run_off or None
        return NumpyHemisphere(surface.radius, centre_m=surface.centre, run_off_m=run_off)
    return surface


def energy_field(
    result: DrapeResult,
    law: ShearLaw,
    *,
    region: BoolArray | CentroidPredicate | None = None,
) -> EnergyField:
    """Shear strain energy of a draped net under ``law``.

    W(γ) [J/m²] per cell from the signed shear (so an asymmetric law takes the branch the
    convention in ``preform.drape.engine.result`` says), thickness ratio t/t0 = 1/cos γ, cells past the
    locking angle (|γ| > locking) and past stitch failure (γ > failure, the parallel sense),
    and the total Σ W·s·d² [J] over the counted cells (d² the undeformed cell, s its share
    inside the part, ``result.part_weight``: 1 for a cell wholly inside).

    Counted cells: valid cells in the part (``result.in_part``), further restricted by
    ``region`` (a boolean mask (ni−1, nj−1) or a predicate on centroids (n, 3) [m]). The
    per-cell arrays are zero outside them (the thickness ratio is 1 there: no deformation counted).
    """
    counted = result.valid & result.in_part
    if region is not None:
        if callable(region):
            keep = np.zeros_like(counted)
            if counted.any():
                keep[counted] = np.asarray(region(result.centroid[counted]), dtype=bool)
        else:
            keep = np.asarray(region, dtype=bool)
            if keep.shape != counted.shape:
                raise ValueError(f"region mask shape {keep.shape} != cell shape {counted.shape}")
        counted = counted & keep
    gamma = np.where(counted, result.shear, 0.0)
    # the law is evaluated on the counted cells only (a mechanistic law is costly per angle)
    density = np.zeros(counted.shape, dtype=float)
    if counted.any():
        density[counted] = np.asarray(law.energy(gamma[counted]), dtype=float)
    thickness_ratio = np.where(counted, 1.0 / np.maximum(np.cos(gamma), 1e-12), 1.0)
    locking = law.locking_angle
    failure = law.failure_angle
    past_locking = (
        counted & (np.abs(gamma) > locking) if locking is not None else np.zeros_like(counted)
    )
    past_failure = counted & (gamma > failure) if failure is not None else np.zeros_like(counted)
    weight = np.where(counted, result.part_weight, 0.0)
    total = float((density * weight).sum() * result.node_spacing**2)
    return EnergyField(
        energy_density=density,
        thickness_ratio=thickness_ratio,
        past_locking=np.asarray(past_locking, dtype=bool),
        past_failure=np.asarray(past_failure, dtype=bool),
        total_energy=total,
    )


def surrogate_energy(self: Any, gamma: ArrayLike) -> FloatArray:
    g = np.asarray(gamma, dtype=float)
    u = np.abs(g)
    return np.where(g >= 0, _sense_energy(self._positive, u), _sense_energy(self._negative, u))


def dependency_shadow(mask: BoolArray, start: tuple[int, int]) -> BoolArray:
    """``preform.drape.judging.verdict.dependency_shadow`` as numpy accumulates (as before the kernels)."""
    i0, j0 = start
    out = np.zeros_like(mask, dtype=bool)
    rows = (slice(i0, None), slice(i0, None, -1))
    cols = (slice(j0, None), slice(j0, None, -1))
    for r in rows:
        for c in cols:
            part = np.logical_or.accumulate(np.logical_or.accumulate(mask[r, c], axis=0), axis=1)
            out[r, c] |= part
    return out


def extremes(result: DrapeResult, part: Part | None = None) -> dict[str, float]:
    """``preform.drape.engine.fields.extremes`` in numpy, on this module's node shear (as before the
    kernels)."""
    counted = result.valid & result.in_part
    cells = np.abs(result.shear[counted])
    gamma = node_shear(result)
    inside = np.isfinite(gamma)
    if part is not None:
        inside &= part.contains(np.where(np.isfinite(result.nodes), result.nodes, 0.0))
    nodes = np.abs(gamma[inside])
    return {
        "max_abs_shear_cells_deg": float(np.degrees(cells.max())) if cells.size else 0.0,
        "max_abs_shear_nodes_deg": float(np.degrees(nodes.max())) if nodes.size else 0.0,
    }


def coverage(result: DrapeResult, surface: Any, start_xy_m: tuple[float, float]) -> Coverage:
    """``preform.drape.judging.verdict.coverage`` as it was before the kernels: the plan positions of
    every node, the dependency shadows as numpy accumulates."""
    status = result.status
    placed = status == NodeStatus.PLACED
    in_ply = status != NodeStatus.OUTSIDE_PLY
    start = result.start_index
    stopped = generator_stops_on_tool(result, surface)
    edge = (status == NodeStatus.OFF_TOOL) & ~stopped
    past_edge = ~placed & in_ply & dependency_shadow(edge, start)
    failed = (status == NodeStatus.NO_INTERSECTION) | (status == NodeStatus.FOLDED) | stopped
    behind_failure = dependency_shadow(failed, start)
    behind_outline = dependency_shadow(~in_ply, start)
    lost = ~placed & in_ply & ~past_edge

    plan = flat_plan_positions(result, start_xy_m)
    over = np.zeros(status.shape, dtype=bool)
    if lost.any():
        _, mask = surface.point_at_plan(plan[lost])
        over[lost] = np.asarray(mask, dtype=bool)
    missing = lost & over
    not_reached = missing & (status == NodeStatus.NOT_REACHED)
    # The failed nodes themselves are counted wherever they lie (they say why the net stopped);
    # the nodes behind them only where they lie over the tool (they are the coverage lost).
    counts = {
        "stopped_on_tool": int(np.count_nonzero(lost & stopped)),
        "no_intersection": int(np.count_nonzero(lost & (status == NodeStatus.NO_INTERSECTION))),
        "folded": int(np.count_nonzero(lost & (status == NodeStatus.FOLDED))),
        "not_reached_behind_failure": int(np.count_nonzero(not_reached & behind_failure)),
        "not_reached_behind_outline": int(
            np.count_nonzero(not_reached & ~behind_failure & behind_outline)
        ),
    }
    # A node that is missing for none of these reasons would be an engine bug; say so rather
    # than let it pass as coverage.
    other = int(np.count_nonzero(not_reached & ~behind_failure & ~behind_outline))
    if other:
        counts["not_reached_unexplained"] = other

    # Cells: valid ones are covered; a non-valid cell inside the ply is asked for when one of
    # its corners is missing and none is past the edge (so complete ⇔ nothing missing).
    valid = result.cell_status == CellStatus.VALID
    cell_in_ply = result.cell_status != CellStatus.OUTSIDE_PLY
    edge_corner = past_edge[:-1, :-1] | past_edge[1:, :-1] | past_edge[:-1, 1:] | past_edge[1:, 1:]
    missing_corner = missing[:-1, :-1] | missing[1:, :-1] | missing[:-1, 1:] | missing[1:, 1:]
    asked = valid | (cell_in_ply & ~edge_corner & missing_corner)

    # Uncovered fabric area by cause: each missing cell (asked, not valid) is d² of undeformed
    # fabric, given to the first cause among its corners in this order.
    lost_cells = asked & ~valid
    causes = (
        ("folded", lost & (status == NodeStatus.FOLDED)),
        ("no_intersection", lost & (status == NodeStatus.NO_INTERSECTION)),
        ("stopped_on_tool", lost & stopped),
        ("behind_failure", missing & behind_failure),
        ("behind_outline", missing & behind_outline),
    )
    uncovered: dict[str, float] = {}
    left = lost_cells.copy()
    for name, node_mask in causes:
        corner = node_mask[:-1, :-1] | node_mask[1:, :-1] | node_mask[:-1, 1:] | node_mask[1:, 1:]
        mine = left & corner
        uncovered[name] = float(np.count_nonzero(mine)) * result.node_spacing**2
        left &= ~mine
    if left.any():
        uncovered["other"] = float(np.count_nonzero(left)) * result.node_spacing**2

    # The fold zone is all the fabric lost behind a fold, also where it would have hung past
    # the tool's plan (a vertex's shadow on a tool with vertical walls lies wholly there).
    fold_nodes = lost & dependency_shadow(status == NodeStatus.FOLDED, start)
    fold_corner = (
        fold_nodes[:-1, :-1] | fold_nodes[1:, :-1] | fold_nodes[:-1, 1:] | fold_nodes[1:, 1:]
    )
    zones = _fold_zones(
        cell_in_ply & ~valid & ~edge_corner & fold_corner, plan, result.node_spacing
    )

    first: tuple[float, float] | None = None
    if missing.any():
        i0, j0 = start
        ii, jj = np.nonzero(missing)
        k = int(np.argmin(np.abs(ii - i0) + np.abs(jj - j0)))
        first = (float(plan[ii[k], jj[k], 0]), float(plan[ii[k], jj[k], 1]))
    return Coverage(
        cells_asked=int(np.count_nonzero(asked)),
        cells_covered=int(np.count_nonzero(valid)),
        missing_nodes=counts,
        nodes_overhang=int(np.count_nonzero(past_edge | (lost & ~over))),
        nodes_missing=int(np.count_nonzero(missing)),
        first_missing_xy_m=first,
        node_spacing_m=result.node_spacing,
        uncovered_area_m2=uncovered,
        fold_zones=zones,
    )


def summary(
    result: DrapeResult, energy: EnergyField | None = None, part: Part | None = None
) -> dict[str, object]:
    """``preform.drape.engine.fields.summary`` as numpy masks and sums (as before the kernels), on
    this module's extremes."""
    valid = result.valid  # each a pass over the net: computed once here
    counted = valid & result.in_part
    shear = np.abs(result.shear[counted])
    part_weight = result.part_weight
    weight = part_weight[counted]
    peaks = extremes(result, part)
    out: dict[str, object] = {
        "nodes_total": result.nodes_total,
        "nodes_placed": result.nodes_placed,
        "complete": result.complete,
        "cells_valid": int(np.count_nonzero(valid)),
        "cells_in_part": int(np.count_nonzero(counted)),
        "cells_cut_by_part_edge": int(np.count_nonzero(counted & (part_weight < 1.0))),
        "part_fabric_area_m2": float(weight.sum() * result.node_spacing**2),
        "part_draped_area_m2": float((result.area[counted] * weight).sum()),
        "max_abs_shear_deg": peaks["max_abs_shear_cells_deg"],
        **peaks,
        "mean_abs_shear_deg": (
            float(np.degrees(np.average(shear, weights=weight)))
            if shear.size and weight.sum() > 0
            else 0.0
        ),
        "generator_angle_deg": float(np.degrees(result.generator_angle)),
        "orientation_deg": float(np.degrees(result.orientation)),
        "node_spacing_m": result.node_spacing,
    }
    for code in NodeStatus:
        out[f"nodes_{code.name.lower()}"] = int(np.count_nonzero(result.status == code))
    for cell_code in CellStatus:
        out[f"cells_{cell_code.name.lower()}"] = int(
            np.count_nonzero(result.cell_status == cell_code)
        )
    if energy is not None:
        out["total_energy_J"] = energy.total_energy
        out["cells_past_locking"] = int(np.count_nonzero(energy.past_locking))
        # Counted by the fabric area they put inside the part (undeformed, d² per whole cell).
        out["part_area_past_locking_m2"] = float(
            (part_weight * energy.past_locking).sum() * result.node_spacing**2
        )
        out["cells_past_failure"] = int(np.count_nonzero(energy.past_failure))
    return out


@contextlib.contextmanager
def numpy_path() -> Iterator[None]:
    """Run the drape step (``preform.drape.steps.run_drape``) on this module's numpy code."""
    saved = (
        steps_module.drape,
        steps_module.energy_field,
        fields_module.node_shear,
        fields_module.extremes,
        surrogate_module.TabulatedSurrogate.energy,
        verdict_module.dependency_shadow,
        steps_module.coverage,
        steps_module.summary,
    )
    steps_module.drape = drape  # type: ignore[assignment]
    steps_module.energy_field = energy_field
    fields_module.node_shear = node_shear
    fields_module.extremes = extremes
    surrogate_module.TabulatedSurrogate.energy = surrogate_energy  # type: ignore[method-assign]
    verdict_module.dependency_shadow = dependency_shadow
    steps_module.coverage = coverage
    steps_module.summary = summary
    try:
        yield
    finally:
        (
            steps_module.drape,
            steps_module.energy_field,
            fields_module.node_shear,
            fields_module.extremes,
            surrogate_module.TabulatedSurrogate.energy,
            verdict_module.dependency_shadow,
            steps_module.coverage,
            steps_module.summary,
        ) = saved  # type: ignore[assignment]
