"""Curved generators: the paper's next stage, generator paths chosen for least energy.

The paper's optimum drapes used straight (geodesic) generators and noted that the real
generator fibres on the formed hemispheres are curved. Here each generator family (u, v) is a
path through the start point whose geodesic curvature is a low-order polynomial in signed arc
length s along the family:

    κ_f(s) = (1/L) · Σ_k c_{f,k} · (s/L)^k,   f ∈ {u, v},   k = 0 .. terms − 1,

with L a length of the tool (its ``size``, e.g. the hemisphere radius), so the coefficients
c are dimensionless (c_0 = 1 bends the path with radius L). κ > 0 turns the path to its left,
seen from the tool's outward normal. c = 0 gives the geodesic generators. A half-line walked
from the start in the −u sense sees κ_walk(σ) = −κ_u(−σ) (σ ≥ 0 the distance walked): the
tangent is reversed, so a left turn of the path is a right turn of the walker.

Marching (vectorised over the four half-lines): sub-steps h = d / substeps; per sub-step the
tangent turns by κ·h/2 in the tangent plane, the point advances h and is brought back to the
tool along the mean of the normals at both ends, and the tangent turns by the other κ·h/2 —
the half-turns make the scheme second order, as the projection makes the geodesic (κ = 0) part.
A node is put where the path crosses chord d from the previous node, then slid onto the tool at
exact chord d (``tolerance``·d).

:func:`optimise_curved_generators` chooses the coefficients (and the generator angle) for
least comparable energy with Nelder–Mead, starting from the straight-generator optimum, and
reports the energy saved against straight generators marched by the same code (c = 0), so
marching error is never counted as a saving.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.generators import GeneratorNodes, _dot, _unit
from preform.drape.engine.result import NodeStatus
from preform.drape.engine.surface import Surface
from preform.drape.judging.wrinkling import WRINKLE_AREA_TOLERANCE
from preform.optimise.search import COVERAGE_SLACK, DrapeObjective, SearchError, with_generators


def _turn(t: FloatArray, n: FloatArray, angle: FloatArray) -> FloatArray:
    """Tangents ``t`` turned by ``angle`` [rad] about normals ``n``, kept in the tangent plane."""
    t = _unit(t - _dot(t, n)[:, None] * n)
    return np.cos(angle)[:, None] * t + np.sin(angle)[:, None] * np.cross(n, t)


@dataclass(frozen=True)
class CurvedGenerators:
    """Generator paths with polynomial geodesic curvature (module docstring).

    ``coefficients``: (u family, v family), each ``terms`` dimensionless c_k; ``length_m``: the
    scale L [m] (None: the tool's ``size``). Pass an instance as ``generators=`` to
    :func:`preform.drape.engine.net.drape`.
    """

    coefficients: tuple[tuple[float, ...], tuple[float, ...]]
    length_m: float | None = None

    @classmethod
    def straight(cls, terms: int = 2, length_m: float | None = None) -> CurvedGenerators:
        """Zero curvature: geodesic generators marched by this code."""
        return cls(((0.0,) * terms, (0.0,) * terms), length_m)

    @classmethod
    def from_vector(cls, values: Any, length_m: float | None = None) -> CurvedGenerators:
        """From a flat vector [c_u0, c_u1, ..., c_v0, c_v1, ...] (equal terms per family)."""
        flat = [float(v) for v in np.asarray(values, dtype=float).ravel()]
        if len(flat) % 2:
            raise ValueError("need the same number of coefficients for both families")
        half = len(flat) // 2
        return cls((tuple(flat[:half]), tuple(flat[half:])), length_m)

    def vector(self) -> FloatArray:
        return np.array([*self.coefficients[0], *self.coefficients[1]], dtype=float)

    def curvature(self, family: int, s_m: FloatArray, length_m: float) -> FloatArray:
        """κ_f(s) [1/m] of family 0 (u) or 1 (v) at signed arc lengths ``s_m`` [m]."""
        coef = np.asarray(self.coefficients[family], dtype=float)
        x = np.asarray(s_m, dtype=float) / length_m
        return np.asarray(np.polynomial.polynomial.polyval(x, coef) / length_m, dtype=float)

    def nodes(
        self,
        surface: Surface,
        start: FloatArray,
        t_u: FloatArray,
        t_v: FloatArray,
        spacing: float,
        count: int,
        *,
        substeps: int = 16,
        tolerance: float = 1e-9,
    ) -> GeneratorNodes:
        """Nodes on the half-generators +u, −u, +v, −v (in that order) from ``start`` (3,) [m]
        with unit tangents ``t_u``, ``t_v`` there: ``count`` nodes each, chord ``spacing`` [m]
        apart to ``tolerance``·d, marched in ``substeps`` sub-steps per spacing."""
        length = float(self.length_m if self.length_m is not None else surface.size)
        start = np.asarray(start, dtype=float)
        directions = np.stack([t_u, -t_u, t_v, -t_v]).astype(float)
        family = np.array([0, 0, 1, 1])
        walker_sign = np.array([1.0, -1.0, 1.0, -1.0])
        m = 4
        points = np.full((m, count, 3), np.nan)
        residual = np.zeros((m, count))
        on_tool = np.zeros((m, count), dtype=bool)
        if count == 0:
            return GeneratorNodes(points, np.zeros((m, 0), np.int8), residual)
        h = spacing / max(int(substeps), 1)
        x = np.broadcast_to(start, (m, 3)).copy()
        n = surface.normal(x)
        t = _unit(directions)
        walked = np.zeros(m)
        last = x.copy()
        found = np.zeros(m, dtype=int)
        running = np.ones(m, dtype=bool)

        def kappa(rows: NDArray[np.intp], sigma: FloatArray) -> FloatArray:
            out = np.empty(len(rows))
            for f in (0, 1):
                sel = family[rows] == f
                if sel.any():
                    sign = walker_sign[rows[sel]]
                    out[sel] = sign * self.curvature(f, sign * sigma[sel], length)
            return out

        lo_bound = np.array(surface.bounds[0]) - 0.5 * h
        hi_bound = np.array(surface.bounds[1]) + 0.5 * h
        for _ in range(4 * count * max(int(substeps), 1) + 16):
            rows = np.flatnonzero(running & (found < count))
            if rows.size == 0:
                break
            xa, na = x[rows], n[rows]
            turn = 0.5 * h * kappa(rows, walked[rows] + 0.5 * h)
            ta = _turn(t[rows], na, turn)
            ahead = xa + h * ta
            foot, _ = surface.closest_point(ahead)
            n_foot = surface.normal(foot)
            # Back to the tool along the mean normal of the step: the symmetric choice, so a
            # κ = 0 path is a discrete geodesic to second order.
            n_mean = _unit(na + n_foot)
            with np.errstate(divide="ignore", invalid="ignore"):
                lam = _dot(foot - ahead, n_foot) / _dot(n_mean, n_foot)
            x_new, dist = surface.closest_point(ahead + lam[:, None] * n_mean)
            step = x_new - xa
            progress = _dot(step, ta)
            outside = np.any((x_new < lo_bound) | (x_new > hi_bound), axis=1)
            # Past the tool's edge the closest point sticks to the edge: no progress.
            off = ~np.isfinite(progress) | (progress < 0.5 * h) | (dist > 0.5 * h) | outside
            running[rows[off]] = False
            keep = ~off
            rows, xa, x_new, step = rows[keep], xa[keep], x_new[keep], step[keep]
            if rows.size == 0:
                continue
            n_new = surface.normal(x_new)
            t_new = _turn(step, n_new, turn[keep])
            reach = _dot(x_new - last[rows], x_new - last[rows]) >= spacing * spacing
            if reach.any():
                idx = rows[reach]
                node = self._cross_chord(
                    surface, last[idx], xa[reach], step[reach], spacing, tolerance
                )
                anchor = last[idx]
                points[idx, found[idx]] = node
                on_tool[idx, found[idx]] = True
                chord = np.sqrt(_dot(node - anchor, node - anchor))
                residual[idx, found[idx]] = np.maximum(
                    np.abs(chord - spacing), surface.closest_point(node)[1]
                )
                found[idx] += 1
                last[idx] = node
            walked[rows] += np.sqrt(_dot(step, step))
            x[rows], n[rows], t[rows] = x_new, n_new, t_new
        return _statuses(points, on_tool, residual)

    @staticmethod
    def _cross_chord(
        surface: Surface,
        anchor: FloatArray,
        x0: FloatArray,
        step: FloatArray,
        spacing: float,
        tolerance: float,
    ) -> FloatArray:
        """The point of the sub-step x0 → x0 + step at chord ``spacing`` from ``anchor``, on the
        tool: the root of |x0 + τ·step − anchor| = d, then rescale-and-project rounds (each
        shrinks the chord error by ~(d/R)²)."""
        w = x0 - anchor
        a = _dot(step, step)
        b = _dot(w, step)
        c = _dot(w, w) - spacing * spacing
        tau = (-b + np.sqrt(np.maximum(b * b - a * c, 0.0))) / a
        node = x0 + tau[:, None] * step
        for _ in range(10):
            node, _ = surface.closest_point(anchor + spacing * _unit(node - anchor))
            chord = np.sqrt(_dot(node - anchor, node - anchor))
            if np.all(np.abs(chord - spacing) <= tolerance * spacing):
                break
        return node


def _statuses(points: FloatArray, on_tool: BoolArray, residual: FloatArray) -> GeneratorNodes:
    """PLACED up to the first missing node, which is OFF_TOOL; NOT_REACHED after it."""
    alive = np.logical_and.accumulate(on_tool, axis=1)
    first_dead = ~alive & np.concatenate([np.ones((len(alive), 1), bool), alive[:, :-1]], axis=1)
    status = np.full(alive.shape, NodeStatus.NOT_REACHED, dtype=np.int8)
    status[alive] = NodeStatus.PLACED
    status[first_dead] = NodeStatus.OFF_TOOL
    return GeneratorNodes(
        np.where(alive[..., None], points, np.nan), status, np.where(alive, residual, 0.0)
    )


@dataclass(frozen=True)
class CurvedResult:
    """The least-energy curved generators found by :func:`optimise_curved_generators`."""

    generators: CurvedGenerators
    generator_angle_rad: float
    #: Comparable energy [J] with these generators, and with straight ones (c = 0, same
    #: marching) at the starting angle.
    energy_J: float
    straight_energy_J: float
    drapes: int
    converged: bool

    @property
    def relative_saving(self) -> float:
        """1 − E_curved / E_straight [-]."""
        return 1.0 - self.energy_J / self.straight_energy_J

    def summary(self) -> dict[str, Any]:
        return {
            "curved_coefficients_u": list(self.generators.coefficients[0]),
            "curved_coefficients_v": list(self.generators.coefficients[1]),
            "curved_generator_angle_deg": math.degrees(self.generator_angle_rad),
            "curved_energy_J": self.energy_J,
            "straight_energy_J": self.straight_energy_J,
            "curved_relative_saving": self.relative_saving,
            "curved_drapes": self.drapes,
            "curved_converged": self.converged,
        }


def optimise_curved_generators(
    objective: DrapeObjective,
    *,
    generator_angle_rad: float,
    terms: int = 2,
    vary_angle: bool = True,
    mirror_families: bool = False,
    reference_area_m2: float | None = None,
    coefficient_step: float = 0.3,
    angle_step_rad: float = math.radians(5.0),
    tolerance: float = 0.05,
    max_drapes: int = 120,
    length_m: float | None = None,
    wrinkle_area_tolerance: float = WRINKLE_AREA_TOLERANCE,
) -> CurvedResult:
    """Curvature coefficients (``terms`` per family) and, with ``vary_angle``, the generator
    angle [rad] of least comparable energy, by Nelder–Mead from straight generators at
    ``generator_angle_rad`` [rad].

    ``mirror_families`` ties the v family to the u family, κ_v = −κ_u: the shape a
    mirror-symmetric set-up (a dome started at its pole) gives, since reflecting across the
    generators' bisector swaps the families, keeps the shear sense and reverses turning. It
    halves the unknowns, which Nelder–Mead's convergence feels.

    Variables are scaled by ``coefficient_step`` and ``angle_step_rad`` (they size the first
    simplex: a wide one, so the staircase in the energy does not stall it); the search stops when the simplex is smaller than ``tolerance`` scaled units or
    after ``max_drapes`` drapes. ``reference_area_m2`` [m²] fixes the part's reference area for
    a priced uncovered area (default: what the straight generators cover). A trial covering
    less of the part than the straight generators (by more than ``COVERAGE_SLACK``) is
    infeasible, and so is one with a share of its covered part past a wrinkle limit more than
    ``wrinkle_area_tolerance`` [-] above the straight generators' (what can be made,
    ``preform.optimise.search``).
    """
    from scipy.optimize import minimize

    if terms < 1:
        raise SearchError("curved generators need at least one coefficient per family")
    straight = CurvedGenerators.straight(terms, length_m)
    base = with_generators(objective, straight)
    first = base.evaluate(generator_angle_rad)
    if not first.draped:
        raise SearchError("the straight generators do not drape at the starting angle")
    reference = first.covered_area_m2 if reference_area_m2 is None else float(reference_area_m2)
    straight_energy = base.charged(first, reference)
    must_cover = (1.0 - COVERAGE_SLACK) * min(first.covered_area_m2, reference)
    most_wrinkle = first.wrinkle_area_share + wrinkle_area_tolerance
    drapes = base.drapes
    n_coef = terms if mirror_families else 2 * terms
    steps = np.r_[[angle_step_rad] if vary_angle else [], [coefficient_step] * n_coef]

    def unpack(z: FloatArray) -> tuple[float, CurvedGenerators]:
        values = np.asarray(z) * steps
        alpha = float(values[0]) if vary_angle else generator_angle_rad
        coef = values[1:] if vary_angle else values
        if mirror_families:
            coef = np.r_[coef, -coef]
        return alpha, CurvedGenerators.from_vector(coef, length_m)

    calls = 0

    def energy(z: FloatArray) -> float:
        nonlocal calls
        calls += 1
        alpha, gens = unpack(z)
        if not 0.0 < alpha < math.pi:
            return math.inf
        trial = with_generators(objective, gens)
        evaluation = trial.evaluate(alpha)
        if evaluation.covered_area_m2 < must_cover:
            # Bare part area is not priced, so a net that leaves more of the part bare than
            # the straight generators is infeasible rather than cheap.
            return math.inf
        if evaluation.wrinkle_area_share > most_wrinkle:
            return math.inf  # wrinkles more than the straight generators: cannot be made
        return trial.charged(evaluation, reference)

    z0 = np.r_[[generator_angle_rad / angle_step_rad] if vary_angle else [], np.zeros(n_coef)]
    simplex = np.vstack([z0, z0 + np.eye(len(z0))])
    res = minimize(
        energy,
        z0,
        method="Nelder-Mead",
        options={
            "initial_simplex": simplex,
            "xatol": tolerance,
            "fatol": 1e-4 * abs(straight_energy),
            "maxfev": max(max_drapes - 1, 2),
        },
    )
    drapes += calls
    alpha, gens = unpack(res.x)
    best = float(res.fun)
    if not best < straight_energy:
        alpha, gens, best = generator_angle_rad, straight, straight_energy
    return CurvedResult(gens, alpha, best, straight_energy, drapes, bool(res.success))


__all__ = ["CurvedGenerators", "CurvedResult", "optimise_curved_generators"]
