"""What a drape result is worth: its coverage, its finiteness, and where it leaves the law.

The pipeline's status vocabulary (``preform.base.status``) promises ``ok`` only for a
result that is complete and finite. This module turns a :class:`DrapeResult` and its
:class:`EnergyField` into the words that back that promise; the steps route them to
``CaseContext.partial`` / ``warn`` or raise ``CaseFailure``. See ``docs/results.md``.

What the scene asks of a drape [C]
----------------------------------
The scene asks for *the ply, draped wherever it lies over the tool* (the part, which the
energies and extremes are of, clips the draped net: ``preform.drape.engine.part``). A ply larger than the tool hangs over its edge, and a kinematic net cannot build a node
whose construction passes through a node off the tool: those nodes are the ply's overhang, not
missing coverage. Node (i, j) is built from the generators through its whole *dependency
rectangle*, the nodes between it and the start node (i0, j0) in both indices, so a node missing
for want of a parent inherits the cause of whichever node of that rectangle failed:

- **past the edge** (fine): OFF_TOOL itself, or a non-placed node with an OFF_TOOL node in its
  rectangle;
- **missing** (coverage lost): NO_INTERSECTION or FOLDED itself, or NOT_REACHED behind such a
  node (or behind a notch of the ply outline), with no OFF_TOOL node in its rectangle, and lying
  over the tool.

The generator marchers mark *any* stop as OFF_TOOL, also a geodesic that cannot cross a
concave crease while the tool goes on (on meshes the exact walking geodesics and placement of
``preform.plugins.surfaces.mesh_kernels`` stop only at the mesh's boundary, and are trusted). So an OFF_TOOL
node on a generator is taken as the tool's edge only when the generator's last chord, continued
one step straight on, lands outside the tool's plan or farther than a node spacing from it; a
generator that stops where the tool goes on is a failure ("stopped on the tool"). The same
test judges the interior OFF_TOOL nodes of the general Newton placement (continuing the cell's
parallelogram), which calls a node at a concave crease of a mesh OFF_TOOL too. A tool that
ends at the foot of a vertical wall (no plate beyond) cannot be told from a crease by this test
and reads as "stopped on the tool".

Behind a sharp convex vertex a pin-jointed net cannot go on: the fibre angle there changes
by the vertex's angle deficit (90° at a box corner), so the net closes up and folds. The
*fold zones* are the connected patches of ply cells lost behind a FOLDED node (none past the
tool's edge), reported with their undeformed plan centre and fabric area, also where that
fabric would have hung past the tool's plan.

A missing node has no position, so "lying over the tool" is judged on its undeformed position:
the flat ply laid on the plan at the start point, its +u fibres along the orientation and +v at
the generator angle. Draping over relief pulls fabric towards the start, so this under-counts
missing nodes near the tool's edge: ``covered_fraction`` is then an upper bound.

``covered_fraction`` is a fraction of fabric area: each cell of the net is d² of undeformed
fabric, so it is the number of valid cells over the number of cells asked for, a cell being
asked for when it is valid, or when one of its corners is missing and none is past the edge.
A drape is complete (fraction 1) exactly when no cell asked for is missing.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.result import DrapeResult, EnergyField, NodeStatus
from preform.drape.judging.wrinkling import (
    PAST_JAMMING,
    PAST_STITCH_FAILURE,
    WrinkleLimit,
    connected_patches,
    wrinkle_limits,
    wrinkling,
)
from preform.shear.law import ShearLaw


def dependency_shadow(mask: BoolArray, start: tuple[int, int]) -> BoolArray:
    """True at every node whose dependency rectangle (module docstring) holds a True node.

    Per quadrant around the start node, a running OR along both indices away from the start:
    node (a, b) of a quadrant depends on exactly the nodes (a', b') with a' ≤ a, b' ≤ b.
    """
    from preform.drape.kernels import verdict_kernels

    out = np.empty(np.shape(mask), dtype=bool)
    verdict_kernels.dependency_shadow(
        np.ascontiguousarray(mask, dtype=bool), int(start[0]), int(start[1]), out
    )
    return out


def _tool_goes_on(surface: Any, last: FloatArray, before: FloatArray, spacing: float) -> BoolArray:
    """Whether the tool goes on where the net stopped (m,): the chord from ``before`` through
    ``last`` (m, 3) [m], continued one step straight on, lands over the tool in plan and within
    one node spacing of the surface. At a rim or a plate's edge it lands outside the tool's plan
    (a chord through two points of a convex surface continues outside it); at a concave crease
    (a wall's foot on a plate) it lands on the tool."""
    ahead = 2.0 * np.asarray(last, dtype=float) - np.asarray(before, dtype=float)
    finite = np.all(np.isfinite(ahead), axis=1)
    out = np.zeros(len(ahead), dtype=bool)
    if not finite.any():
        return out
    _, over = surface.point_at_plan(ahead[finite, :2])
    _, dist = surface.closest_point(ahead[finite])
    out[finite] = np.asarray(over, dtype=bool) & (np.asarray(dist) <= spacing)
    return out


def generator_stops_on_tool(result: DrapeResult, surface: Any) -> BoolArray:
    """OFF_TOOL nodes where the tool in fact goes on (module docstring): True there (ni, nj).

    Checked: the first OFF_TOOL node of each half-generator (the marchers call any stop
    OFF_TOOL) and, on tools placed by the general Newton solve, the interior OFF_TOOL nodes
    (that solve calls a node OFF_TOOL when its closest point lies on an edge of the tool, which
    a concave crease between two faces of a mesh also is). Closed-form placements decide
    OFF_TOOL from the tool's own shape and are trusted."""
    status = result.status
    nodes = np.asarray(result.nodes, dtype=float)
    ni, nj = result.shape
    i0, j0 = result.start_index
    targets: list[tuple[int, int]] = []
    lasts: list[FloatArray] = []
    befores: list[FloatArray] = []
    for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        count = (ni - 1 - i0 if di > 0 else i0) if di else (nj - 1 - j0 if dj > 0 else j0)
        k = np.arange(1, count + 1)
        stops = np.flatnonzero(status[i0 + di * k, j0 + dj * k] == NodeStatus.OFF_TOOL)
        if stops.size == 0:
            continue
        step = int(k[stops[0]])
        last = nodes[i0 + di * (step - 1), j0 + dj * (step - 1)]
        if step >= 2:
            before = nodes[i0 + di * (step - 2), j0 + dj * (step - 2)]
        else:
            # Only the start is placed: continue from the opposite half-generator's first node.
            oi, oj = i0 - di, j0 - dj
            if not (0 <= oi < ni and 0 <= oj < nj) or status[oi, oj] != NodeStatus.PLACED:
                continue
            before = nodes[oi, oj]
        targets.append((i0 + di * step, j0 + dj * step))
        lasts.append(last)
        befores.append(before)
    if not hasattr(surface, "place_nodes"):
        ii, jj = np.indices(status.shape)
        inner = np.argwhere((status == NodeStatus.OFF_TOOL) & (ii != i0) & (jj != j0))
        if inner.size:
            i, j = inner[:, 0], inner[:, 1]
            si, sj = np.sign(i - i0), np.sign(j - j0)
            a, b, c = nodes[i - si, j], nodes[i, j - sj], nodes[i - si, j - sj]
            # The cell's parallelogram a + b − c: the chord from c through (a + b)/2, continued.
            targets += [(int(p), int(q)) for p, q in inner]
            lasts += list(0.5 * (a + b))
            befores += list(c)
    out = np.zeros(status.shape, dtype=bool)
    if targets:
        goes_on = _tool_goes_on(surface, np.array(lasts), np.array(befores), result.node_spacing)
        for (ti, tj), flag in zip(targets, goes_on, strict=True):
            out[ti, tj] = bool(flag)
    return out


def flat_plan_positions(result: DrapeResult, start_xy_m: tuple[float, float]) -> FloatArray:
    """Undeformed plan position (ni, nj, 2) [m] of every node: the flat ply laid on the plan
    at the start point, +u along the orientation, +v at the generator angle from it."""
    return plan_positions_at(result, start_xy_m, *np.indices(result.shape))


def plan_positions_at(
    result: DrapeResult, start_xy_m: tuple[float, float], ii: NDArray[np.intp], jj: NDArray[np.intp]
) -> FloatArray:
    """:func:`flat_plan_positions` (..., 2) [m] of the nodes (ii, jj) only."""
    i0, j0 = result.start_index
    d = result.node_spacing
    theta, alpha = result.orientation, result.generator_angle
    e_u = np.array([math.cos(theta), math.sin(theta)])
    e_v = np.array([math.cos(theta + alpha), math.sin(theta + alpha)])
    xi = (np.asarray(ii) - i0) * d
    eta = (np.asarray(jj) - j0) * d
    return np.asarray(start_xy_m, dtype=float) + xi[..., None] * e_u + eta[..., None] * e_v


@dataclass(frozen=True)
class Coverage:
    """How much of what the scene asked (module docstring) a drape covers, and why not more."""

    #: Cells asked for, and the valid ones among them (each d² of undeformed fabric).
    cells_asked: int
    cells_covered: int
    #: Failed nodes (stopped_on_tool, no_intersection, folded), and nodes over the tool not
    #: reached behind them or behind a notch of the ply outline (not_reached_behind_failure,
    #: not_reached_behind_outline).
    missing_nodes: dict[str, int]
    #: Nodes of the ply not placed and not asked for: past the tool's edge, or (undeformed)
    #: not over the tool at all; the overhang.
    nodes_overhang: int
    #: Where the first missing node nearest the start lies, undeformed, in plan [m], if any.
    #: Nodes over the tool that are not placed (failed or not reached), the coverage lost.
    nodes_missing: int = 0
    first_missing_xy_m: tuple[float, float] | None = None
    node_spacing_m: float = 0.0
    #: Fabric area [m²] (undeformed, d² a cell) of the cells asked for and not covered, by the
    #: first cause among their corners: folded, no_intersection, stopped_on_tool,
    #: behind_failure, behind_outline.
    uncovered_area_m2: Mapping[str, float] = dataclasses.field(default_factory=dict)
    #: The fold zones: each connected patch of ply cells lost to a fold (a corner FOLDED or not
    #: reached behind a FOLDED node, none past the tool's edge: a sharp convex vertex's
    #: shadow), also where that fabric would hang past the tool's plan, as (undeformed plan
    #: centre (x, y) [m], fabric area [m²]), largest first.
    fold_zones: tuple[tuple[tuple[float, float], float], ...] = ()
    #: The ply cells the net failed to drape (ni−1, nj−1): the cells asked for and not
    #: covered, and the fold zones' cells (also those past the tool's plan). Cell (i, j) is the
    #: same piece of fabric at every generator angle (the ply is laid out in fibre
    #: coordinates), which is what lets the angle search leave a cell lost at one angle out of
    #: every angle's sum (``preform.optimise.search``). None when not computed.
    lost_cells: BoolArray | None = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def covered_fraction(self) -> float:
        """Valid cells / cells asked for: a fraction of fabric area (1.0 when nothing asked)."""
        return 1.0 if self.cells_asked == 0 else self.cells_covered / self.cells_asked

    @property
    def complete(self) -> bool:
        """No cell asked for is missing (then ``covered_fraction`` is 1)."""
        return self.cells_asked == self.cells_covered

    def reason(self) -> str:
        """Why the drape is partial, in words (empty when complete)."""
        if self.complete:
            return ""
        d_mm = self.node_spacing_m * 1e3
        why = {
            "stopped_on_tool": "stopped on the tool (the net could not be continued across a "
            "crease or corner there, although the tool goes on)",
            "folded": "folded (the net would turn over there: behind a sharp convex vertex of "
            "the tool, or at an edge or corner sharper than a net of this spacing can follow)",
            "no_intersection": "had no intersection (no point of the tool at distance "
            f"d = {d_mm:.3g} mm from both parent nodes: the curvature is too high for the node "
            "spacing)",
            "not_reached_behind_failure": "over the tool were not reached because a node "
            "between them and the start failed",
            "not_reached_behind_outline": "over the tool were not reached because the ply "
            "outline cuts a generator before them",
        }
        m = self.missing_nodes
        causes = [f"{m[key]} node(s) {words}" for key, words in why.items() if m.get(key)]
        if self.fold_zones:
            causes.append(self.fold_words())
        where = ""
        if self.first_missing_xy_m is not None:
            # rounded first, then + 0.0, so that -0.4 mm reads "0", not "-0"
            x, y = (round(1e3 * v) + 0.0 for v in self.first_missing_xy_m)
            where = (
                "; the first missing node nearest the start lies near "
                f"(x, y) = ({x:.0f}, {y:.0f}) mm"
            )
        return (
            f"the net covers {100 * self.covered_fraction:.1f} % of the ply's fabric area that "
            f"lies over the tool ({self.cells_covered} of {self.cells_asked} cells): "
            + "; ".join(causes)
            + where
        )

    def fold_words(self) -> str:
        """The fold zones in words (empty when there are none)."""
        if not self.fold_zones:
            return ""
        zones = ", ".join(
            f"{1e6 * area:.0f} mm² around ({round(1e3 * x) + 0.0:.0f}, "
            f"{round(1e3 * y) + 0.0:.0f}) mm"
            for (x, y), area in self.fold_zones
        )
        return f"{len(self.fold_zones)} fold zone(s) of the flat ply lost behind a fold: {zones}"

    def fold_warning(self) -> str:
        """For a complete drape that still folded (its fold zones lie past the tool's plan,
        e.g. behind a box corner whose walls are vertical): what the coverage does not say."""
        if not (self.complete and self.fold_zones):
            return ""
        return (
            "the net folded (behind a sharp convex vertex of the tool, where the fibre angle "
            "changes by the vertex's angle deficit); the fabric lost there lies past the tool's "
            "plan, so the coverage counts it as overhang: " + self.fold_words()
        )

    def summary(self) -> dict[str, Any]:
        """Scalar results for the case summary."""
        out: dict[str, Any] = {
            "covered_fraction": self.covered_fraction,
            "coverage_cells_asked": self.cells_asked,
            "coverage_cells_covered": self.cells_covered,
            "nodes_overhang": self.nodes_overhang,
            "nodes_missing": self.nodes_missing,
        }
        for key, value in self.missing_nodes.items():
            out[f"nodes_missing_{key}"] = value
        for key, area in self.uncovered_area_m2.items():
            out[f"uncovered_area_m2_{key}"] = area
        out["fold_zones"] = len(self.fold_zones)
        out["fold_zone_area_m2"] = float(sum(area for _, area in self.fold_zones))
        for k, ((x, y), area) in enumerate(self.fold_zones, start=1):
            out[f"fold_zone_{k}_x_m"], out[f"fold_zone_{k}_y_m"] = x, y
            out[f"fold_zone_{k}_area_m2"] = area
        return out


def coverage(result: DrapeResult, surface: Any, start_xy_m: tuple[float, float]) -> Coverage:
    """The coverage of ``result`` on ``surface`` (module docstring); ``start_xy_m`` [m] is the
    plan position of the start point (the flat ply is laid from there)."""
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

    # undeformed plan positions only where they are asked (the lost nodes): the whole net's
    # would be a net-sized array for the few nodes a drape loses
    over = np.zeros(status.shape, dtype=bool)
    if lost.any():
        ii, jj = np.nonzero(lost)
        _, mask = surface.point_at_plan(plan_positions_at(result, start_xy_m, ii, jj))
        over[ii, jj] = np.asarray(mask, dtype=bool)
    from preform.drape.kernels import verdict_kernels

    # The rest in two compiled passes (``preform.drape.kernels.verdict_kernels``): each node's part
    # in the counts, then each cell's from its corners. The failed nodes themselves are
    # counted wherever they lie (they say why the net stopped); the nodes behind them only
    # where they lie over the tool (they are the coverage lost).
    bits = np.empty(status.shape, dtype=np.uint8)
    node_counts, first_flat = verdict_kernels.coverage_nodes(
        np.ascontiguousarray(status, dtype=np.int8),
        np.ascontiguousarray(stopped),
        np.ascontiguousarray(lost),
        np.ascontiguousarray(past_edge),
        behind_failure,
        behind_outline,
        dependency_shadow(status == NodeStatus.FOLDED, start),
        over,
        int(start[0]),
        int(start[1]),
        bits,
    )
    counts = {
        name: int(node_counts[k])
        for k, name in enumerate(
            (
                "stopped_on_tool",
                "no_intersection",
                "folded",
                "not_reached_behind_failure",
                "not_reached_behind_outline",
            )
        )
    }
    # A node that is missing for none of these reasons would be an engine bug; say so rather
    # than let it pass as coverage.
    if node_counts[5]:
        counts["not_reached_unexplained"] = int(node_counts[5])

    # Cells: valid ones are covered; a non-valid cell inside the ply is asked for when one of
    # its corners is missing and none is past the edge (so complete ⇔ nothing missing). Each
    # missing cell (asked, not valid) is d² of undeformed fabric, given to the first cause
    # among its corners in the order of verdict_kernels.CAUSES. The fold zone is all the
    # fabric lost behind a fold, also where it would have hung past the tool's plan (a
    # vertex's shadow on a tool with vertical walls lies wholly there).
    cell_status = np.ascontiguousarray(result.cell_status, dtype=np.int8)
    fold_cells = np.empty(cell_status.shape, dtype=bool)
    lost_mask = np.empty(cell_status.shape, dtype=bool)
    asked, covered, lost_cells = verdict_kernels.coverage_cells(
        cell_status, bits, fold_cells, lost_mask
    )
    d2 = result.node_spacing**2
    uncovered = {name: float(lost_cells[k]) * d2 for k, name in enumerate(verdict_kernels.CAUSES)}
    if lost_cells[5]:
        uncovered["other"] = float(lost_cells[5]) * d2
    zones = (
        _fold_zones(fold_cells, flat_plan_positions(result, start_xy_m), result.node_spacing)
        if fold_cells.any()
        else ()
    )

    first: tuple[float, float] | None = None
    if first_flat >= 0:
        fi, fj = divmod(int(first_flat), status.shape[1])
        x, y = plan_positions_at(result, start_xy_m, np.array([fi]), np.array([fj]))[0]
        first = (float(x), float(y))
    return Coverage(
        cells_asked=int(asked),
        cells_covered=int(covered),
        missing_nodes=counts,
        nodes_overhang=int(node_counts[6]),
        nodes_missing=int(node_counts[7]),
        first_missing_xy_m=first,
        node_spacing_m=result.node_spacing,
        uncovered_area_m2=uncovered,
        fold_zones=zones,
        lost_cells=lost_mask,
    )


def _fold_zones(
    cells: BoolArray, plan: FloatArray, spacing: float
) -> tuple[tuple[tuple[float, float], float], ...]:
    """Connected patches (edge or corner neighbours) of ``cells`` (ni−1, nj−1): undeformed
    plan centre [m] and fabric area (d² a cell) [m²] of each, largest first."""
    centre = 0.25 * (plan[:-1, :-1] + plan[1:, :-1] + plan[:-1, 1:] + plan[1:, 1:])
    return tuple(connected_patches(cells, centre, np.full(cells.shape, spacing**2)))


# --------------------------------------------------------------------------------------------
# Finiteness


def first_nonfinite_energy(result: DrapeResult, energy: EnergyField) -> str | None:
    """Why the energy of a drape is not finite, in words, or None when it is finite."""
    density = np.asarray(energy.energy_density, dtype=float)
    shear = np.asarray(result.shear, dtype=float)
    bad_shear = result.valid & ~np.isfinite(shear)
    if bad_shear.any():
        i, j = (int(v) for v in np.argwhere(bad_shear)[0])
        return (
            f"the drape gave a non-finite shear angle in {int(bad_shear.sum())} cell(s), first "
            f"cell ({i}, {j}): the net's geometry is broken there"
        )
    bad = ~np.isfinite(density)
    if bad.any():
        i, j = (int(v) for v in np.argwhere(bad)[0])
        value = density[i, j]
        word = "NaN" if math.isnan(value) else ("+inf" if value > 0 else "-inf")
        return (
            f"the shear law returned {word} at γ = {math.degrees(float(shear[i, j])):.4g}° "
            f"(cell ({i}, {j}); {int(bad.sum())} cell(s) in all): total energy is not finite"
        )
    if not math.isfinite(energy.total_energy):
        return (
            f"total energy is not finite ({energy.total_energy!r} J) although every cell's "
            "energy density is: the sum overflows"
        )
    return None


def law_nonfinite_angle(law: ShearLaw, max_deg: float = 89.0, step_deg: float = 0.5) -> str | None:
    """Where a law's energy is not finite on a grid of ±``max_deg`` [deg], in words, or None."""
    angles = np.radians(np.arange(-max_deg, max_deg + 0.5 * step_deg, step_deg))
    with np.errstate(all="ignore"):
        values = np.asarray(law.energy(angles), dtype=float)
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size == 0:
        return None
    # The failing angle nearest zero is the one a drape meets first.
    k = int(bad[np.argmin(np.abs(angles[bad]))])
    value = values[k]
    word = "NaN" if math.isnan(value) else ("+inf" if value > 0 else "-inf")
    return f"the shear law returned {word} at γ = {math.degrees(float(angles[k])):.4g}°"


# --------------------------------------------------------------------------------------------
# Where the drape leaves the law's trustworthy range


@dataclass(frozen=True)
class LawRange:
    """The angles [rad, > 0] past which a law's numbers stop being measured or physical."""

    locking: float | None = None
    failure: float | None = None
    #: Stitch-failure angle magnitude in the perpendicular sense (γ < 0), if the law has one.
    failure_negative: float | None = None
    #: Physical limit of the model (fabric jammed), past which it holds its torque artificially.
    packing: float | None = None
    #: End of the measured/fitted data in the positive and negative senses, and what the law
    #: does past it ("hold", "linear", "extrapolate").
    data_positive: float | None = None
    data_negative: float | None = None
    beyond: str | None = None
    #: Further limits past which the law's fabric wrinkles, as the law states them
    #: (``wrinkle_limits``, ``preform.drape.judging.wrinkling``).
    further: tuple[WrinkleLimit, ...] = ()


def _deg_or_none(value: Any) -> float | None:
    try:
        out = float(value)
    except (TypeError, ValueError):
        return None
    return math.radians(out) if math.isfinite(out) else None


def fabric_law_range(law: ShearLaw, fabric: Any) -> LawRange:
    """:func:`law_range` of ``law`` with ``fabric``'s shear-law block, or its architecture's
    default block when the entry gives none."""
    block = getattr(fabric, "shear_law", None)
    if block is None and hasattr(fabric, "default_shear_law"):
        block = fabric.default_shear_law()
    return law_range(law, block)


def law_range(law: ShearLaw, law_block: Any = None) -> LawRange:
    """The limits of ``law``. Read from the law when it offers them (``packing_angle`` [rad],
    ``data_range`` = (negative end, positive end) [rad], ``wrinkle_limits``); else the data range is read from the
    fabric's shear-law block (``law_block``): the generic fields ``max_angle_deg`` (positive
    sense), ``max_angle_negative_deg`` / ``max_angle_perpendicular_deg`` (negative sense) of
    fitted laws, the last ``angle_deg`` / ``angle_negative_deg`` of tabulated ones, and
    ``beyond_range``."""
    packing = getattr(law, "packing_angle", None)
    data = getattr(law, "data_range", None)
    positive = negative = None
    beyond = None
    if data is not None:
        negative, positive = (None if v is None else float(v) for v in data)
    elif law_block is not None:
        block: Mapping[str, Any]
        if isinstance(law_block, Mapping):
            block = law_block
        elif hasattr(law_block, "model_dump"):
            block = law_block.model_dump()
        else:
            block = {}
        positive = _deg_or_none(block.get("max_angle_deg"))
        table = block.get("angle_deg")
        if positive is None and isinstance(table, list | tuple) and table:
            positive = _deg_or_none(table[-1])
        negative = _deg_or_none(
            block.get("max_angle_negative_deg") or block.get("max_angle_perpendicular_deg")
        )
        neg_table = block.get("angle_negative_deg")
        if negative is None and isinstance(neg_table, list | tuple) and neg_table:
            negative = _deg_or_none(neg_table[-1])
        if negative is None:
            negative = positive
        beyond = block.get("beyond_range")
        beyond = str(beyond) if beyond is not None else None
    # A data range reaching 90° is no range at all.
    if positive is not None and positive >= 0.5 * math.pi - 1e-9:
        positive = None
    if negative is not None and negative >= 0.5 * math.pi - 1e-9:
        negative = None
    return LawRange(
        locking=law.locking_angle,
        failure=law.failure_angle,
        failure_negative=getattr(law, "failure_angle_negative", None),
        packing=None if packing is None else float(packing),
        data_positive=positive,
        data_negative=negative,
        beyond=beyond,
        further=_further_limits(law),
    )


def _further_limits(law: ShearLaw) -> tuple[WrinkleLimit, ...]:
    """The law's own ``wrinkle_limits`` (``preform.drape.judging.wrinkling``), checked."""
    stated = tuple(getattr(law, "wrinkle_limits", None) or ())
    for limit in stated:
        if not isinstance(limit, WrinkleLimit):
            raise TypeError(
                f"{type(law).__name__}.wrinkle_limits must hold "
                f"preform.drape.judging.wrinkling.WrinkleLimit, not {type(limit).__name__}"
            )
    return stated


def _fraction(mask: BoolArray, area: FloatArray, counted: BoolArray) -> float:
    """The share of the counted area under ``mask`` [-]."""
    total = float(area[counted].sum())
    return float(area[mask].sum()) / total if total > 0 else 0.0


def _share(mask: BoolArray, area: FloatArray, counted: BoolArray) -> str:
    total = float(area[counted].sum())
    part = float(area[mask].sum())
    percent = 100.0 * part / total if total > 0 else 0.0
    # Cells sheared to near 90° have almost no area: say how little rather than "0.0 %".
    shown = f"{percent:.1f}" if percent >= 0.1 or percent == 0 else f"{percent:.2g}"
    return f"{int(np.count_nonzero(mask))} cells ({shown} % of the part's draped area)"


def shear_limit_notes(
    result: DrapeResult, energy: EnergyField, limits: LawRange
) -> tuple[list[tuple[str, dict[str, Any]]], dict[str, Any]]:
    """Sentences about the counted cells past the law's limits, each with what it is about
    (``CaseContext.warn``'s ``cause``, ``area_share``, ``energy_share``), and their counts
    for the summary. Counted cells are those the energy sums (``energy_field``); their shares
    of area and energy are of the part (a cut cell by its area inside it)."""
    counted = result.valid & result.in_part
    gamma = np.where(counted, np.asarray(result.shear, dtype=float), 0.0)
    # Shares of the part: a cell cut by its edge counts by its area inside it.
    weight = np.asarray(result.part_weight, dtype=float)
    area = np.asarray(result.area, dtype=float) * weight
    density = np.asarray(energy.energy_density, dtype=float)
    total = float((density * result.node_spacing**2 * weight)[counted].sum())
    messages: list[tuple[str, dict[str, Any]]] = []
    counts: dict[str, Any] = {}
    if limits.locking is not None:
        past = np.asarray(energy.past_locking, dtype=bool) & counted
        counts["cells_past_locking"] = int(np.count_nonzero(past))
        if past.any():
            messages.append(
                (
                    f"{_share(past, area, counted)} are sheared past the locking angle "
                    f"{math.degrees(limits.locking):.1f}°: its tows touch and compact there (stiffer; "
                    "it wrinkles only past jamming)",
                    {"cause": "past locking", "area_share": _fraction(past, area, counted)},
                )
            )
    # Jamming and stitch failure are where the fabric would wrinkle (preform.drape.judging.wrinkling):
    # said with their energy share, where and how far; the same numbers as the wrinkling block.
    wrinkles = wrinkling(result, energy.energy_density, wrinkle_limits(limits))
    for zone in wrinkles.zones:
        cause = zone.limit.cause
        key = {PAST_JAMMING: "cells_past_packing", PAST_STITCH_FAILURE: "cells_past_failure"}
        counts[key.get(cause, f"cells_{cause}")] = zone.cells
        if zone.cells:
            past = counted & zone.limit.past(gamma)
            messages.append(
                (
                    f"{_share(past, area, counted)} are sheared past {zone.limit.name}: "
                    f"{zone.limit.consequence}, so their energy, {100 * zone.energy_share:.3g} % "
                    f"of the total {total:.3g} J, is not a physical energy but the law's "
                    f"continuation past that limit ({zone.where()})",
                    {
                        "cause": cause.replace("_", " "),
                        "area_share": zone.area_share,
                        "energy_share": zone.energy_share,
                    },
                )
            )
    beyond_pos = (
        counted & (gamma > limits.data_positive)
        if limits.data_positive is not None
        else np.zeros_like(counted)
    )
    beyond_neg = (
        counted & (gamma < -limits.data_negative)
        if limits.data_negative is not None
        else np.zeros_like(counted)
    )
    if limits.data_positive is not None or limits.data_negative is not None:
        outside = beyond_pos | beyond_neg
        counts["cells_outside_law_data"] = int(np.count_nonzero(outside))
        if outside.any():
            ends = []
            if limits.data_positive is not None:
                ends.append(f"+{math.degrees(limits.data_positive):.1f}°")
            if limits.data_negative is not None:
                ends.append(f"−{math.degrees(limits.data_negative):.1f}°")
            how = {
                "hold": "holds the last measured value",
                "linear": "continues the last tangent",
                "extrapolate": "extrapolates the fitted curve",
            }.get(limits.beyond or "", "is extrapolated")
            messages.append(
                (
                    f"{_share(outside, area, counted)} are sheared beyond the shear law's data "
                    f"range ({' / '.join(ends)}), where the law {how}: their energy is not measured",
                    {
                        "cause": "beyond the law's data",
                        "area_share": _fraction(outside, area, counted),
                    },
                )
            )
    return messages, counts
