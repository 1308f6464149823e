"""Relaxing a draped net towards least shear energy: beyond the paper, kept apart from it.

**This is not the paper's method.** The paper (and :mod:`preform.optimise.search`,
:mod:`preform.optimise.curved`) only chooses among *kinematic* drapes: the generators fix the net.
Here every node of the net is free: starting from the best kinematic drape, the nodes move over
the tool to lower the total shear energy while the tows stay (nearly) inextensible. It answers
"how much energy is left on the table by insisting on a pin-jointed mapping from two
generators?", not "what does the paper predict?".

Problem, over the nodes x of the counted cells (the part's valid cells of the starting drape;
the start node stays pinned):

    minimise  Σ_cells W(γ_c)·s_c·d²   subject to  |x_a − x_b| = d on every edge,  x on the tool,

with γ_c the mean of the four edge-pair angles minus 90° exactly as
:func:`preform.drape.engine.fields.cell_fields` defines it and s_c the cell's share of area inside the
part (``DrapeResult.part_weight``, held at the kinematic drape's). The edges go into an augmented
Lagrangian on the strains r_e = |e|/d − 1, the tool into a penalty on the scaled (unsigned)
distance r_s = dist(x)/d, which also holds nodes back at a trimmed edge such as a dome's rim.
Each outer round minimises it with L-BFGS (written out here) using the analytic gradient
(dγ/dx from dθ/da = −(b̂ − cos θ·â)/(|a| sin θ), dW/dγ = the law's torque,
∂(dist²/2)/∂x = x − foot), then updates the multipliers and, when a round did not shrink the
violation enough, the penalty. At the end the nodes are put exactly on the tool and the edge
errors reported.

Cost: one energy-and-gradient evaluation is a few vectorised passes over the cells (~1 ms
per 1000 cells); the soft shear modes against stiff tows make the problem ill-conditioned, so
a relaxation takes thousands of evaluations (the initial penalty is deliberately soft,
:data:`PENALTY_PER_CELL`, with the multipliers doing the enforcing). Measured on the bundled
hemisphere with an asymmetric woven law (``benchmarks/bench_search.py --relax``): d = 10 mm,
622 cells, ~2000 evaluations, ~2 s; d = 5 mm, 2624 cells, ~5500 evaluations, ~20 s. Coarse
nets only: the scene's 145 × 145 net would take many minutes.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.result import DrapeResult, NodeStatus
from preform.drape.engine.surface import Surface
from preform.shear.law import ShearLaw
from preform.shear.surrogate import TabulatedSurrogate

#: Initial edge-strain penalty per counted cell, on energies normalised by the kinematic total.
PENALTY_PER_CELL = 0.01


@dataclass(frozen=True)
class RelaxResult:
    """A relaxed net and how it compares with the kinematic drape it started from."""

    #: Node positions (ni, nj, 3) [m]; NaN where the starting drape had no counted node.
    nodes: FloatArray
    #: Signed shear per cell (ni−1, nj−1) [rad]; 0 outside the counted cells.
    shear: FloatArray
    #: The cells relaxed and counted (ni−1, nj−1).
    counted: BoolArray
    #: Σ W·s·d² over the counted cells (s: share inside the part), relaxed and kinematic [J].
    energy_J: float
    kinematic_energy_J: float
    #: Largest |edge length − d| [m] and largest distance to the tool [m] after relaxing.
    max_edge_error_m: float
    max_surface_distance_m: float
    #: RMS and largest |γ_relaxed − γ_kinematic| over the counted cells [rad].
    rms_shear_change_rad: float
    max_shear_change_rad: float
    #: Largest node displacement [m].
    max_displacement_m: float
    #: Outer (multiplier) rounds, energy-and-gradient evaluations, wall time [s].
    rounds: int
    evaluations: int
    seconds: float
    #: Edge strains within tolerance at the end.
    converged: bool

    @property
    def relative_saving(self) -> float:
        """1 − E_relaxed / E_kinematic [-]."""
        return 1.0 - self.energy_J / self.kinematic_energy_J

    def summary(self) -> dict[str, float | int | bool]:
        """The relaxation's own numbers. Its objective (``relaxed_objective_J``) holds each
        cell's kinematic share of the part; the relaxed net's energy, summed as every drape is,
        is ``relaxed_energy_J`` (``preform.optimise.search_steps``)."""
        return {
            "relaxed_objective_J": self.energy_J,
            "relaxed_max_edge_error_m": self.max_edge_error_m,
            "relaxed_max_surface_distance_m": self.max_surface_distance_m,
            "relaxed_rms_shear_change_deg": math.degrees(self.rms_shear_change_rad),
            "relaxed_max_shear_change_deg": math.degrees(self.max_shear_change_rad),
            "relaxed_evaluations": self.evaluations,
            "relaxed_seconds": self.seconds,
            "relaxed_converged": self.converged,
        }


def _angle_and_gradient(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """θ = angle(a, b) [rad] for vectors (..., 3) and ∂θ/∂a, ∂θ/∂b."""
    la = np.sqrt(np.einsum("...i,...i->...", a, a))
    lb = np.sqrt(np.einsum("...i,...i->...", b, b))
    ua, ub = a / la[..., None], b / lb[..., None]
    cos = np.einsum("...i,...i->...", ua, ub)
    cross = np.cross(ua, ub)
    sin = np.sqrt(np.einsum("...i,...i->...", cross, cross))
    theta = np.arctan2(sin, cos)
    inv = 1.0 / np.maximum(sin, 1e-12)
    grad_a = -(ub - cos[..., None] * ua) * (inv / la)[..., None]
    grad_b = -(ua - cos[..., None] * ub) * (inv / lb)[..., None]
    return theta, grad_a, grad_b


def cell_shear_and_gradient(
    nodes: FloatArray,
) -> tuple[FloatArray, tuple[FloatArray, FloatArray, FloatArray, FloatArray]]:
    """γ per cell (ni−1, nj−1) [rad] of a net (ni, nj, 3) [m], as in ``cell_fields``, and
    ∂γ/∂x at its corners (00, 10, 01, 11), each (ni−1, nj−1, 3) [1/m]."""
    x00, x10 = nodes[:-1, :-1], nodes[1:, :-1]
    x01, x11 = nodes[:-1, 1:], nodes[1:, 1:]
    u_low, u_high = x10 - x00, x11 - x01
    v_left, v_right = x01 - x00, x11 - x10
    g00 = np.zeros_like(x00)
    g10 = np.zeros_like(x00)
    g01 = np.zeros_like(x00)
    g11 = np.zeros_like(x00)
    total = np.zeros(x00.shape[:-1])
    # (u edge, its tail, its head) x (v edge, its tail, its head): the four pairs cell_fields
    # averages.
    for u, (ut, uh) in ((u_low, (g00, g10)), (u_high, (g01, g11))):
        for v, (vt, vh) in ((v_left, (g00, g01)), (v_right, (g10, g11))):
            theta, da, db = _angle_and_gradient(u, v)
            total += theta
            uh += 0.25 * da
            ut -= 0.25 * da
            vh += 0.25 * db
            vt -= 0.25 * db
    return 0.25 * total - 0.5 * np.pi, (g00, g10, g01, g11)


def _lbfgs(
    fun: Callable[[FloatArray], tuple[float, FloatArray]],
    x0: FloatArray,
    *,
    first_step: float,
    max_iterations: int,
    memory: int = 10,
    ftol: float = 1e-13,
) -> tuple[FloatArray, bool]:
    """Minimise ``fun`` (value and gradient) by limited-memory BFGS with Armijo backtracking.

    Written out rather than taken from scipy: scipy's L-BFGS-B calls BLAS on every iteration,
    and on a shared machine OpenBLAS's threads made that cost milliseconds per iteration for a
    few hundred unknowns, far more than the energy itself. ``first_step`` bounds the largest
    coordinate change of the first (unscaled) step. Returns the minimiser and whether it
    stopped on ``ftol`` (rather than on the iteration cap or a failed line search).
    """
    x = x0.copy()
    f, g = fun(x)
    pairs: list[tuple[FloatArray, FloatArray, float]] = []
    for _ in range(max_iterations):
        # Two-loop recursion for −H·g.
        q = g.copy()
        alphas = []
        for s_k, y_k, rho in reversed(pairs):
            a_k = rho * float(s_k @ q)
            alphas.append(a_k)
            q -= a_k * y_k
        if pairs:
            s_k, y_k, _ = pairs[-1]
            q *= float(s_k @ y_k) / float(y_k @ y_k)
        else:
            q *= first_step / max(float(np.abs(q).max()), 1e-300)
        for (s_k, y_k, rho), a_k in zip(pairs, reversed(alphas), strict=True):
            q += (a_k - rho * float(y_k @ q)) * s_k
        direction = -q
        slope = float(g @ direction)
        if slope >= 0:  # not a descent direction: restart from steepest descent
            pairs.clear()
            direction = -g * (first_step / max(float(np.abs(g).max()), 1e-300))
            slope = float(g @ direction)
            if slope >= 0:
                return x, True
        step = 1.0
        for _ in range(40):
            x_new = x + step * direction
            f_new, g_new = fun(x_new)
            if f_new <= f + 1e-4 * step * slope:
                break
            step *= 0.5
        else:
            return x, False
        s_new, y_new = x_new - x, g_new - g
        sy = float(s_new @ y_new)
        if sy > 1e-12 * float(np.sqrt((s_new @ s_new) * (y_new @ y_new))):
            pairs.append((s_new, y_new, 1.0 / sy))
            if len(pairs) > memory:
                pairs.pop(0)
        done = abs(f - f_new) <= ftol * max(abs(f_new), 1.0)
        x, f, g = x_new, f_new, g_new
        if done:
            return x, True
    return x, False


def relax_net(
    result: DrapeResult,
    surface: Surface,
    law: ShearLaw,
    *,
    counted: BoolArray | None = None,
    edge_tolerance: float = 1e-4,
    max_rounds: int = 8,
    max_iterations: int = 1500,
    tabulate: bool = True,
) -> RelaxResult:
    """Relax the kinematic drape ``result`` on ``surface`` towards least shear energy under
    ``law`` keeping edges at d (see the module docstring; not the paper's method).

    ``counted``: the cells to relax and count (ni−1, nj−1) (default: valid cells in the part).
    ``edge_tolerance``: target |strain| = ||e|/d − 1| [-]; ``max_rounds`` outer rounds of at
    most ``max_iterations`` L-BFGS iterations each. ``tabulate``: evaluate W and C from a
    :class:`~preform.shear.surrogate.TabulatedSurrogate` (mechanistic laws are slow per angle).
    """
    clock = time.perf_counter()
    table = TabulatedSurrogate(law) if tabulate else law
    d = float(result.node_spacing)
    cells = np.asarray(result.valid & result.in_part if counted is None else counted, dtype=bool)
    if not cells.any():
        raise ValueError("no counted cells to relax")
    ni, nj = result.shape
    active = np.zeros((ni, nj), dtype=bool)
    active[:-1, :-1] |= cells
    active[1:, :-1] |= cells
    active[:-1, 1:] |= cells
    active[1:, 1:] |= cells
    if not np.all(result.status[active] == NodeStatus.PLACED):
        raise ValueError("every corner of a counted cell must be a placed node")
    free = active.copy()
    free[result.start_index] = False
    # Edges of counted cells: u edges (i, j)-(i+1, j), v edges (i, j)-(i, j+1).
    u_edges = np.zeros((ni - 1, nj), dtype=bool)
    u_edges[:, :-1] |= cells
    u_edges[:, 1:] |= cells
    v_edges = np.zeros((ni, nj - 1), dtype=bool)
    v_edges[:-1, :] |= cells
    v_edges[1:, :] |= cells

    start = np.where(active[..., None], result.nodes, 0.0)
    gamma0 = result.shear[cells]
    # Each cell counts by its share of area inside the part (issue 11), held at the kinematic
    # drape's: the relaxed nodes move by a fraction of d, which changes a cut cell's share by
    # as little, and a fixed weight keeps the objective smooth.
    weight_all = np.where(cells, result.part_weight, 0.0)
    weight = weight_all[cells]
    e_kin = float((np.asarray(law.energy(gamma0), dtype=float) * weight).sum() * d * d)
    scale = max(e_kin, 1e-300)
    n_free = int(np.count_nonzero(free))
    mu = PENALTY_PER_CELL * float(np.count_nonzero(cells))
    lam_u = np.zeros(int(np.count_nonzero(u_edges)))
    lam_v = np.zeros(int(np.count_nonzero(v_edges)))
    evaluations = 0

    def unpack(z: FloatArray) -> FloatArray:
        x = start.copy()
        x[free] = z.reshape(n_free, 3)
        return x

    def residuals(
        x: FloatArray,
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """Edge vectors and lengths (u, v), and distance, offset and foot on the tool."""
        eu = x[1:] - x[:-1]
        ev = x[:, 1:] - x[:, :-1]
        lu = np.sqrt(np.einsum("...i,...i->...", eu, eu))
        lv = np.sqrt(np.einsum("...i,...i->...", ev, ev))
        foot, dist = surface.closest_point(x[free])
        return eu, ev, lu, lv, dist, x[free] - foot, foot

    def objective(z: FloatArray) -> tuple[float, FloatArray]:
        nonlocal evaluations
        evaluations += 1
        x = unpack(z)
        with np.errstate(invalid="ignore", divide="ignore"):
            gamma, corner_grads = cell_shear_and_gradient(x)
        g_cells = gamma[cells]
        f = float((np.asarray(table.energy(g_cells), dtype=float) * weight).sum()) * d * d / scale
        torque = np.zeros(cells.shape)
        torque[cells] = np.asarray(table.torque(g_cells), dtype=float) * weight
        coef = (torque * d * d / scale)[..., None]
        grad = np.zeros_like(x)
        g00, g10, g01, g11 = (np.where(cells[..., None], g, 0.0) for g in corner_grads)
        grad[:-1, :-1] += coef * g00
        grad[1:, :-1] += coef * g10
        grad[:-1, 1:] += coef * g01
        grad[1:, 1:] += coef * g11
        eu, ev, lu, lv, dist, offset, _ = residuals(x)
        for edges, vec, length, lam, axis in (
            (u_edges, eu, lu, lam_u, 0),
            (v_edges, ev, lv, lam_v, 1),
        ):
            r = length[edges] / d - 1.0
            f += float(lam @ r + 0.5 * mu * (r @ r))
            g_edge = np.zeros_like(vec)
            g_edge[edges] = ((lam + mu * r) / (d * length[edges]))[:, None] * vec[edges]
            if axis == 0:
                grad[1:] += g_edge
                grad[:-1] -= g_edge
            else:
                grad[:, 1:] += g_edge
                grad[:, :-1] -= g_edge
        # A plain penalty on the distance to the tool: unsigned, so it also holds nodes back at
        # a trimmed edge (a dome's rim), where a signed distance along the normal vanishes.
        r_s = dist / d
        f += float(0.5 * mu * (r_s @ r_s))
        grad[free] += (mu / (d * d)) * offset
        return f, grad[free].ravel()

    z = start[free].ravel().copy()
    violation = math.inf
    rounds = 0
    for rounds in range(1, max_rounds + 1):  # noqa: B007 - reported
        z, settled = _lbfgs(objective, z, first_step=0.05 * d, max_iterations=max_iterations)
        x = unpack(z)
        _, _, lu, lv, dist, _, _ = residuals(x)
        r_u, r_v, r_s = lu[u_edges] / d - 1.0, lv[v_edges] / d - 1.0, dist / d
        new_violation = float(max(np.abs(r_u).max(), np.abs(r_v).max(), np.abs(r_s).max()))
        lam_u += mu * r_u
        lam_v += mu * r_v
        if new_violation <= edge_tolerance and settled:
            violation = new_violation
            break
        # A stiffer penalty only while the tows are still too long: past that it would just
        # worsen the conditioning the soft shear modes already suffer from.
        if new_violation > edge_tolerance and new_violation > 0.25 * violation:
            mu *= 10.0
        violation = new_violation

    x = unpack(z)
    foot, _ = surface.closest_point(x[active])
    x[active] = foot
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma, _ = cell_shear_and_gradient(x)
    gamma = np.where(cells, gamma, 0.0)
    energy = float((np.asarray(law.energy(gamma[cells]), dtype=float) * weight).sum() * d * d)
    _, _, lu, lv, _, _, _ = residuals(x)
    edge_error = float(max(np.abs(lu[u_edges] - d).max(), np.abs(lv[v_edges] - d).max()))
    surface_distance = float(surface.closest_point(x[active])[1].max())
    change = gamma[cells] - result.shear[cells]
    displacement = np.sqrt(
        np.einsum("ij,ij->i", x[active] - start[active], x[active] - start[active])
    )
    nodes = np.where(active[..., None], x, np.nan)
    return RelaxResult(
        nodes=nodes,
        shear=gamma,
        counted=cells,
        energy_J=energy,
        kinematic_energy_J=e_kin,
        max_edge_error_m=edge_error,
        max_surface_distance_m=surface_distance,
        rms_shear_change_rad=float(np.sqrt(np.mean(change * change))),
        max_shear_change_rad=float(np.abs(change).max()),
        max_displacement_m=float(displacement.max()),
        rounds=rounds,
        evaluations=evaluations,
        seconds=time.perf_counter() - clock,
        converged=edge_error <= edge_tolerance * d * 1.5,
    )


__all__ = ["RelaxResult", "cell_shear_and_gradient", "relax_net"]
