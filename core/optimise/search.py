"""The minimum-energy drape: among kinematic drapes, the one needing least shear strain energy.

The paper's energy approach (PHYSICS §6, paper "Energy approach"): vary the generators, drape
each choice as a pin-jointed net, and keep the pattern of least total shear strain energy. Here
the choice is the generator angle α (:func:`search_generator_angle`: a scan, then a local
refinement), optionally also the generator orientation and the start point
(:func:`search_layout`: Nelder–Mead).

The energy of the part [D]
--------------------------
Every drape is judged on the same part (PHYSICS §6 "The energy of a part"): the net is draped
over the tool as far as the ply reaches and clipped to the part (the drape's ``trim``, a
:class:`~preform.drape.engine.part.Part`, further restricted by an optional ``region``); each cell
counts W(γ) times its undeformed area inside the part, s·d² (``DrapeResult.part_weight``), so a
cell cut by the part's edge counts by its share, and

    E(α) = Σ_cells W(γ)·s·d² [J].

No energy is charged for part area the net does not reach. Such a charge has no physical basis
on a part the ply covers, and it biased the optimum: before parts existed, cells straddling a
hemisphere's rim were dropped and cells above it went unreached behind nodes that dipped below
it, for numerical reasons only, and a charge at locked energy on that "bare" area moved
E-BX-318's optimum from about 66.5° to 73.3° (issue 11). Part area the net genuinely cannot
cover (the ply runs out, the net folds or loses its intersection) is reported, as
``coverage(α)`` = covered area / A_ref and as the uncovered area, A_ref being the part's own
area when known (a bare hemisphere: 2πR²; ``part_area_m2``), else the largest area any drape of
the scan covers.

Pricing it is a stated user choice (``uncovered_shear_rad``: the bare area is charged at
W_miss = max(W(+γ_m), W(−γ_m)) per unit area, the same rule for every architecture; the
pipeline then reports the case ``partial``). ``min_coverage`` > 0 marks an α whose coverage
falls below it infeasible instead: never chosen as the optimum (its energy is still reported).

What can be made [D]
--------------------
Least energy is compared among drapes that can be made. A drape needing cells past jamming or
stitch failure wrinkles there (``preform.drape.judging.wrinkling``), and the law's energy for those
cells is its continuation, not a physical energy; 4–7 % of a part sheared past jamming can
carry 95 % of a satin's energy, so E(α) alone would compare continuations. The rule,
feasibility first and by area, the same for every architecture (it reads only the law's
limits): an angle is **makeable** when the share of its covered part area past a wrinkle limit
is within ``wrinkle_area_tolerance`` (scene ``search.wrinkle_area_tolerance``, default 0.02 of
the area [C]) of the least share any evaluated angle reaches, and, when the scene sets
``search.max_wrinkle_area_share``, at most that share. An angle that is not makeable is
infeasible, as one below ``min_coverage`` is: sampled and reported (``SearchPoint.makeable``,
its wrinkle shares), never chosen. Why area and not the energy share of the status rule: the
energy share rewards an angle that shears the whole part more (its physical energy grows)
over one that is nearly unsheared but for a few jammed cells; on the hat mould it made 90°
(1.1 % of the area wrinkled, 0.03 J) unmakeable and chose 107.5° (4.9 %, 0.55 J). The status
rule still says what a drape's energy means (the case is ``partial`` when it is mostly
continuation). When no scanned angle is makeable (only with ``max_wrinkle_area_share``) the
search returns the scanned angle of least wrinkle (least area share past the limits, then
least energy share, then least energy), unrefined, with ``AngleSearchResult.makeable`` False;
the pipeline then makes the case ``partial`` and says that no angle drapes within the cap.

The same fabric at every angle [D]
----------------------------------
A drape can lose ply cells: behind a sharp convex vertex the net folds (its *fold zones*,
:class:`~preform.drape.judging.verdict.Coverage`), or it loses its intersection and the cells behind.
Those cells drop out of Σ W·s·d², so an angle at which a fold zone appears looks cheap for that
reason alone: on the bundled hat mould at α = 90° all four block corners fold and E was
0.27 J, while at 88.74° two of them are draped instead, sheared to about 88° (past the law's
jamming), and E was 13.87 J; the old search returned 88.74° as the optimum. The search
therefore compares angles on **the same fabric**: the ply is laid out in fibre coordinates,
so cell (i, j) is the same piece of fabric at every α; a cell that any feasible sample fails
to drape (``Coverage.lost_cells``: its fold zones and the cells asked for and not covered) is
left out of every sample's energy, as its ``excluded_energy_J``. ``SearchPoint.energy_J``,
what the search ranks, is ``drape_energy_J + uncovered_charge_J − excluded_energy_J``; with no
cell lost anywhere (a hemisphere, a smooth tool) it is the drape's energy to the last bit.
Why this rule and not another: charging the lost fabric at some shear energy would price a
fold (a bending event) as shear, at a shear the law can only continue past jamming; marking
angles that lose fabric infeasible would leave no angle on a tool whose corners fold at every
α. The rule costs range: the fabric compared is what every sampled angle drapes, so a wide
range on a folding tool compares the angles on less of the ply (the excluded fabric area is
reported, ``excluded_fabric_area_m2``, and the pipeline says it). The set grows as samples are
added, and every sample is judged again on it.

Discontinuities [D]
-------------------
E(α) jumps where a fold zone appears or disappears, or where the coverage or the fabric the
net fails to drape changes abruptly. Between neighbouring feasible samples a **jump** is
flagged (:func:`find_discontinuities`) when the number of fold zones changes, or when the
covered part area or the lost fabric area changes by more than :data:`JUMP_AREA_SHARE` (1 %) of
the reference area and faster than :data:`JUMP_RATE_PER_DEG` (5 % of it per degree); each is
reported with its interval and causes (``AngleSearchResult.discontinuities``). The rate is
what tells a jump from a smooth change (a ply running off a plate changes its covered area by
up to about 1.2 %/° on the hemisphere's run-off): a jump's rate grows as the samples close in
on it, so a small jump far from the optimum, between scan samples 5° apart, may go unflagged,
while near the optimum, where the refinement samples densely, it shows. The cell count itself
is not a criterion: sheared cells are smaller, so the count changes smoothly with α where
nothing is lost.

Refinement and symmetry
-----------------------
The scan grid is laid symmetrically about 90° (90° ± k·step, plus the range ends), so a
mirror-symmetric set-up (symmetric law, start at a hemisphere's pole) gives E(α) = E(180° − α)
on the grid. The refinement then fits least-squares parabolas over windows centred on the
current estimate, adding the points estimate ± δ (and the estimate itself) with δ halving each
level: every sample set stays symmetric about a symmetric optimum, so the estimate stays at
90° to rounding. A least-squares fit, not interpolation, so that what remains of the discrete
E(α)'s roughness (clipped cells are smooth in α, but folds or the ply's end still add or drop
whole cells) is averaged rather than chased; when a window's fit is no longer convex the
refinement stops there and says it is noise-limited. A fit uses only the samples on the
estimate's side of every jump (:func:`continuous_span`), and its vertex stays on that side;
where a jump leaves too few samples for a fit the refinement goes on by bisection, keeping the
cheapest sample within the window.

Never dearer than a sample [D]
------------------------------
The optimum's energy is at most the lowest energy of any feasible sample, always: when the
drape at the fit's vertex costs more than the best sample (judged on the same fabric, its own
lost cells included), or when jumps on both sides of the best sample leave no fit, the optimum
is that sample, ``optimum_from`` says "best sample" and ``optimum_note`` why; the bracket is
then its feasible neighbours.

Uncertainty of the optimum [D]
------------------------------
Reported from E(α) near the minimum, not from window sizes: the samples within one scan step
of α* are fitted by least squares with a parabola and with a cubic. The uncertainty combines
the parabola vertex's standard error (the scatter of E about a smooth curve: what is left of
the rim staircase, folds, the ply's end) and the distance between the two fits' minima (what
the parabola's shape assumption costs over that window):
u = √(σ_vertex² + (α*_parabola − α*_cubic)²). The relative rms residual of the cubic fit is
reported too (``residual_rms_rel``), a direct measure of E(α)'s roughness.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.net import DrapeError, drape
from preform.drape.engine.result import DrapeResult
from preform.drape.engine.surface import Surface
from preform.drape.judging.verdict import coverage, law_range
from preform.drape.judging.wrinkling import WRINKLE_AREA_TOLERANCE, WrinkleLimit, makeable, past_any
from preform.drape.judging.wrinkling import wrinkle_limits as limits_of
from preform.shear.law import ShearLaw
from preform.shear.surrogate import TabulatedSurrogate

CentroidPredicate = Callable[[FloatArray], BoolArray]

#: A layout or curved-generator trial must cover at least this share of what its starting
#: drape covers of the part [-] [C]: with no price on bare area, a trial that leaves the part
#: bare would look cheap, so it is infeasible instead (not priced). The slack allows the O(d²)
#: change of the clipped area as the net moves (1.3e-4 of a hemisphere at d = R/40).
COVERAGE_SLACK = 1e-3
#: Defaults of the angle search (documented fidelity knobs) [rad].
DEFAULT_SCAN_STEP_RAD = math.radians(5.0)
DEFAULT_TOLERANCE_RAD = math.radians(1.0)
DEFAULT_MAX_DRAPES = 60
#: Step of the shear law's energy table during a search [rad] (a fidelity knob; see
#: ``preform.shear.surrogate`` for its measured error, below 3e-7 of W at this step).
DEFAULT_ENERGY_TABLE_STEP_RAD = math.radians(0.25)


class SearchError(ValueError):
    """A search that cannot run: empty range, nothing feasible, no drape at all."""


@dataclass(frozen=True)
class DrapeEvaluation:
    """One drape judged on the part (module docstring). Lengths m, angles rad, energy J."""

    generator_angle_rad: float
    orientation_rad: float
    start_xy_m: tuple[float, float]
    #: Σ W(γ)·s·d² over the valid cells in the part, s the share inside it [J].
    drape_energy_J: float
    #: Draped (tool-side) area of those cells inside the part, Σ s·area [m²].
    covered_area_m2: float
    #: Number of cells counted.
    cells_counted: int
    #: Largest |γ| over the counted cells [rad].
    max_abs_shear_rad: float
    #: False when the drape could not start at all (set-up error); energies are then inf.
    draped: bool = True
    #: The net itself, when the caller asked to keep it.
    result: DrapeResult | None = field(default=None, repr=False, compare=False)
    #: Of those, the cells past a limit where the fabric wrinkles (``preform.drape.judging.wrinkling``:
    #: jamming, stitch failure): their energy Σ W·s·d² [J] and draped area Σ s·area [m²].
    wrinkle_energy_J: float = 0.0
    wrinkle_area_m2: float = 0.0

    @property
    def wrinkle_energy_share(self) -> float:
        """Share of the drape energy from cells past a wrinkle limit [-] (0 for no energy)."""
        energy = self.drape_energy_J
        return self.wrinkle_energy_J / energy if math.isfinite(energy) and energy > 0 else 0.0

    @property
    def wrinkle_area_share(self) -> float:
        """Share of the covered part area past a wrinkle limit [-] (0 when nothing covered)."""
        area = self.covered_area_m2
        return self.wrinkle_area_m2 / area if area > 0 else 0.0

    #: The drape's fold zones (``Coverage.fold_zones``: undeformed plan centre (x, y) [m],
    #: fabric area [m²], largest first) and the fabric area [m²] of the ply cells the net
    #: failed to drape (d² a cell: fold zones, and cells asked for and not covered).
    fold_zones: tuple[tuple[tuple[float, float], float], ...] = ()
    lost_area_m2: float = 0.0
    #: Per cell (ni−1, nj−1): the energy it adds to ``drape_energy_J`` [J] (0 where not
    #: counted), and whether the net failed to drape it (``Coverage.lost_cells``). Kept so
    #: the angle search can leave out of every angle's sum a cell lost at any angle.
    cell_energy_J: FloatArray | None = field(default=None, repr=False, compare=False)
    lost_cells: BoolArray | None = field(default=None, repr=False, compare=False)

    @property
    def fold_zone_area_m2(self) -> float:
        """Fabric area of the fold zones [m²]."""
        return float(sum(area for _, area in self.fold_zones))


class DrapeObjective:
    """Drape-and-judge: E(choices) for one fabric on one tool (see the module docstring).

    ``drape_kwargs`` are the fixed keyword arguments of :func:`preform.drape.engine.net.drape`
    (``node_spacing_m``, ``ply``, ``start_xy_m`` or ``start_point``, ``orientation_rad``,
    ``generators``, ``trim``, ``tolerance``, ...); :meth:`evaluate` overrides the generator
    angle and, optionally, the orientation, the start point and the generators.
    ``region`` (a predicate on cell centroids (n, 3) [m]) restricts the part further.
    ``uncovered_shear_rad`` [rad]: price uncovered part area at W_miss = max W(±γ_m) [J/m²]
    (module docstring; default None: no charge). ``wrinkle_limits``: where the fabric wrinkles
    (``preform.drape.judging.wrinkling``; default: the law's, through ``law_range``); each evaluation
    carries the energy and area of its cells past them.
    """

    def __init__(
        self,
        surface: Surface,
        law: ShearLaw,
        *,
        region: CentroidPredicate | None = None,
        uncovered_shear_rad: float | None = None,
        energy_table_step_rad: float | None = DEFAULT_ENERGY_TABLE_STEP_RAD,
        wrinkle_limits: Sequence[WrinkleLimit] | None = None,
        **drape_kwargs: Any,
    ) -> None:
        if "node_spacing_m" not in drape_kwargs or "ply" not in drape_kwargs:
            raise TypeError("DrapeObjective needs node_spacing_m and ply among the drape kwargs")
        drape_kwargs.pop("generator_angle_rad", None)
        self.surface = surface
        self.law = law
        self.region = region
        self.drape_kwargs = drape_kwargs
        #: The shear at which uncovered part area is priced [rad], None: not priced.
        self.uncovered_shear_rad = (
            None if uncovered_shear_rad is None else float(uncovered_shear_rad)
        )
        #: Energy density charged on uncovered part area [J/m²] (0: not priced).
        self.uncovered_energy_density = 0.0
        if self.uncovered_shear_rad is not None:
            g = self.uncovered_shear_rad
            both = np.asarray(law.energy(np.array([g, -g])), dtype=float)
            self.uncovered_energy_density = float(np.max(both))
        trim = drape_kwargs.get("trim")
        #: The part's own area [m²] when it knows it (a bare hemisphere: 2πR²), else None.
        self.part_area_m2: float | None = getattr(trim, "area_m2", None)
        #: Where the fabric wrinkles instead of shearing (``preform.drape.judging.wrinkling``).
        self.wrinkle_limits: tuple[WrinkleLimit, ...] = (
            limits_of(law_range(law)) if wrinkle_limits is None else tuple(wrinkle_limits)
        )
        #: Number of drapes run so far.
        self.drapes = 0
        self._table = (
            None
            if energy_table_step_rad is None
            else TabulatedSurrogate(law, energy_table_step_rad)
        )

    def energy_density(self, gamma: FloatArray) -> FloatArray:
        """W(γ) [J/m²] at signed shear angles γ [rad] (tabulated unless the table is off)."""
        if self._table is None:
            return np.asarray(self.law.energy(gamma), dtype=float)
        return self._table.energy(gamma)

    def evaluate(
        self,
        generator_angle_rad: float,
        *,
        orientation_rad: float | None = None,
        start_xy_m: Sequence[float] | None = None,
        generators: Any = None,
        keep_result: bool = False,
    ) -> DrapeEvaluation:
        """Drape at generator angle α [rad] (and the given overrides) and judge it on the part.

        A set-up that cannot drape at all (start off the tool, α outside (0, π)) returns an
        evaluation with ``draped=False`` and infinite energy instead of raising, so optimisers
        can step there and back.
        """
        kwargs = dict(self.drape_kwargs)
        if orientation_rad is not None:
            kwargs["orientation_rad"] = float(orientation_rad)
        if start_xy_m is not None:
            kwargs.pop("start_point", None)
            kwargs["start_xy_m"] = (float(start_xy_m[0]), float(start_xy_m[1]))
        if generators is not None:
            kwargs["generators"] = generators
        where = kwargs.get("start_xy_m")
        start = (float(where[0]), float(where[1])) if where is not None else (math.nan, math.nan)
        theta = float(kwargs.get("orientation_rad", 0.0) or 0.0)
        self.drapes += 1
        try:
            result = drape(self.surface, generator_angle_rad=float(generator_angle_rad), **kwargs)
        except DrapeError:
            return DrapeEvaluation(
                float(generator_angle_rad), theta, start, math.inf, 0.0, 0, 0.0, draped=False
            )
        return self.judge(result, start_xy_m=start, keep_result=keep_result)

    def counted(self, result: DrapeResult) -> BoolArray:
        """The cells the energy counts: valid, in the part, inside ``region`` (ni−1, nj−1)."""
        mask = result.valid & result.in_part
        if self.region is not None and mask.any():
            keep = np.asarray(self.region(result.centroid[mask]), dtype=bool)
            mask = mask.copy()
            mask[mask] = keep
        return np.asarray(mask, dtype=bool)

    def judge(
        self,
        result: DrapeResult,
        *,
        start_xy_m: tuple[float, float] = (math.nan, math.nan),
        keep_result: bool = False,
    ) -> DrapeEvaluation:
        """Energy [J], covered area [m²] and counted cells of a finished drape, and the
        energy and area of those past a wrinkle limit.

        Equal to :func:`preform.drape.engine.fields.energy_field`'s total over the same cells, up to
        the energy table's interpolation (relative error ~1e-6 at the default step; pass
        ``energy_table_step_rad=None`` for the law itself). The table matters for mechanistic
        laws that cost microseconds per angle: a drape has ~10⁴ cells and a search ~30 drapes.
        """
        mask = self.counted(result)
        gamma = result.shear[mask]
        share = result.part_weight[mask]
        density = self.energy_density(gamma)
        energy = float((density * share).sum() * result.node_spacing**2)
        covered = result.area[mask] * share
        past = past_any(self.wrinkle_limits, gamma)
        per_cell = np.zeros(mask.shape)
        per_cell[mask] = density * share * result.node_spacing**2
        # The flat ply is laid from the start's plan position: the given one, else the start
        # node's own (a start given as a 3-D point).
        if math.isfinite(start_xy_m[0]) and math.isfinite(start_xy_m[1]):
            plan = start_xy_m
        else:
            i0, j0 = result.start_index
            plan = (float(result.nodes[i0, j0, 0]), float(result.nodes[i0, j0, 1]))
        cover = coverage(result, self.surface, plan)
        lost = cover.lost_cells
        return DrapeEvaluation(
            generator_angle_rad=float(result.generator_angle),
            orientation_rad=float(result.orientation),
            start_xy_m=start_xy_m,
            drape_energy_J=energy,
            covered_area_m2=float(covered.sum()),
            cells_counted=int(np.count_nonzero(mask)),
            max_abs_shear_rad=float(np.abs(gamma).max()) if gamma.size else 0.0,
            result=result if keep_result else None,
            wrinkle_energy_J=float((density * share)[past].sum() * result.node_spacing**2),
            wrinkle_area_m2=float(covered[past].sum()),
            fold_zones=cover.fold_zones,
            lost_area_m2=(
                0.0 if lost is None else float(np.count_nonzero(lost)) * result.node_spacing**2
            ),
            cell_energy_J=per_cell,
            lost_cells=lost,
        )

    def charged(self, evaluation: DrapeEvaluation, reference_area_m2: float) -> float:
        """The comparable energy [J]: the drape energy, plus W_miss × uncovered part area when
        the user priced it (module docstring)."""
        if not evaluation.draped:
            return math.inf
        missing = max(0.0, reference_area_m2 - evaluation.covered_area_m2)
        return evaluation.drape_energy_J + self.uncovered_energy_density * missing


@dataclass(frozen=True)
class SearchPoint:
    """One generator angle of the search. Angles rad, energies J, areas m²."""

    generator_angle_rad: float
    #: The comparable objective: drape energy plus the uncovered-area charge.
    energy_J: float
    drape_energy_J: float
    uncovered_charge_J: float
    covered_area_m2: float
    #: covered area / reference area, capped at 1.
    coverage: float
    feasible: bool
    #: "scan", "refine" or "optimum".
    stage: str
    #: Largest |γ| over the counted cells of this drape [rad] (to say where E(α) leaves the
    #: law's trustworthy range).
    max_abs_shear_rad: float = 0.0
    #: Share of the covered part area, and of the drape energy, past a wrinkle limit [-], and
    #: whether the drape can be made by that (``preform.drape.judging.wrinkling.makeable``): an angle
    #: that cannot is not feasible.
    wrinkle_area_share: float = 0.0
    wrinkle_energy_share: float = 0.0
    makeable: bool = True
    #: The energy [J] of this drape's cells that another compared angle fails to drape, left
    #: out of ``energy_J`` so that every angle is judged on the same fabric (module docstring:
    #: ``energy_J`` = ``drape_energy_J`` + ``uncovered_charge_J`` − ``excluded_energy_J``).
    excluded_energy_J: float = 0.0
    #: Cells counted, the drape's fold zones (number, fabric area [m²]) and the fabric area
    #: [m²] of the ply cells the net failed to drape (fold zones and cells not covered).
    cells_counted: int = 0
    fold_zones: int = 0
    fold_zone_area_m2: float = 0.0
    lost_area_m2: float = 0.0

    @property
    def generator_angle_deg(self) -> float:
        return math.degrees(self.generator_angle_rad)


#: A jump of E(α)'s accounting between two neighbouring samples: a change of the covered part
#: area, or of the fabric the net fails to drape, by more than this share of the reference
#: area [-] and faster than :data:`JUMP_RATE_PER_DEG` (module docstring, "Discontinuities");
#: a change of the number of fold zones is a jump whatever its size.
JUMP_AREA_SHARE = 0.01
#: ... and faster than this share of the reference area per degree of α [1/deg]: a jump has
#: no finite rate, so it shows once the samples are close enough; a smooth change of coverage
#: (a ply running off a plate: up to about 1.2 %/° measured on the hemisphere's run-off) does
#: not.
JUMP_RATE_PER_DEG = 0.05


@dataclass(frozen=True)
class Discontinuity:
    """A jump of E(α) between two neighbouring samples α_lo < α_hi [rad], with its causes in
    words (fold zones appearing or disappearing, a jump of the coverage or of the fabric the
    net fails to drape). The jump lies somewhere inside (α_lo, α_hi)."""

    lo_rad: float
    hi_rad: float
    causes: tuple[str, ...]

    def words(self) -> str:
        return (
            f"between {math.degrees(self.lo_rad):.4g}° and {math.degrees(self.hi_rad):.4g}°: "
            + "; ".join(self.causes)
        )

    def summary(self) -> dict[str, Any]:
        return {
            "between_deg": [math.degrees(self.lo_rad), math.degrees(self.hi_rad)],
            "causes": list(self.causes),
        }


def find_discontinuities(
    points: Sequence[SearchPoint],
    reference_area_m2: float,
    share: float = JUMP_AREA_SHARE,
    rate_per_deg: float = JUMP_RATE_PER_DEG,
) -> tuple[Discontinuity, ...]:
    """The jumps of E(α)'s accounting between neighbouring feasible samples (module docstring,
    "Discontinuities"): the number of fold zones changes, or the covered part area [m²] or the
    fabric area the net fails to drape [m²] changes by more than max(``share``,
    ``rate_per_deg`` × the samples' distance in degrees) × the reference area
    ``reference_area_m2`` [m²]. Sorted by angle."""
    usable = sorted(
        (p for p in points if p.feasible and math.isfinite(p.energy_J)),
        key=lambda p: p.generator_angle_rad,
    )
    jumps = []
    for a, b in itertools.pairwise(usable):
        width_deg = math.degrees(b.generator_angle_rad - a.generator_angle_rad)
        step = max(share, rate_per_deg * width_deg) * reference_area_m2
        causes = []
        if a.fold_zones != b.fold_zones:
            causes.append(
                f"fold zones {a.fold_zones} → {b.fold_zones} "
                f"({1e6 * a.fold_zone_area_m2:.0f} → {1e6 * b.fold_zone_area_m2:.0f} mm² of "
                "fabric)"
            )
        if abs(b.lost_area_m2 - a.lost_area_m2) > step:
            causes.append(
                f"fabric the net fails to drape {1e6 * a.lost_area_m2:.0f} → "
                f"{1e6 * b.lost_area_m2:.0f} mm²"
            )
        if abs(b.covered_area_m2 - a.covered_area_m2) > step:
            causes.append(
                f"covered part area {1e6 * a.covered_area_m2:.0f} → "
                f"{1e6 * b.covered_area_m2:.0f} mm² ({a.cells_counted} → {b.cells_counted} "
                "cells counted)"
            )
        if causes:
            jumps.append(Discontinuity(a.generator_angle_rad, b.generator_angle_rad, tuple(causes)))
    return tuple(jumps)


def continuous_span(
    centre_rad: float, jumps: Sequence[Discontinuity], lo_rad: float, hi_rad: float
) -> tuple[float, float]:
    """The span [rad] of ``[lo_rad, hi_rad]`` around ``centre_rad`` that no jump crosses: from
    the upper sample of the nearest jump below to the lower sample of the nearest jump above
    (a single point when the centre is a sample with a jump on both sides). A centre inside an
    unresolved jump (between its two samples) gets the centre alone: which side it belongs to
    is not known until it is draped."""
    low, high = lo_rad, hi_rad
    eps = 1e-12
    for jump in jumps:
        if jump.hi_rad <= centre_rad + eps:
            low = max(low, jump.hi_rad)
        elif jump.lo_rad >= centre_rad - eps:
            high = min(high, jump.lo_rad)
        else:
            return centre_rad, centre_rad
    return low, high


@dataclass(frozen=True)
class AngleSearchResult:
    """The generator-angle search: the optimum, the whole curve, and how well it is resolved."""

    #: The optimum generator angle α* [rad] and its comparable energy [J] (a drape at α*): the
    #: vertex of a least-squares fit, or the best feasible sample when the fit's drape is not
    #: cheaper (``optimum_from``); never more than the lowest feasible sampled energy.
    optimum_angle_rad: float
    optimum_energy_J: float
    #: Every evaluated angle, sorted by angle (scan, refinement and the optimum).
    points: tuple[SearchPoint, ...]
    #: Drapes run by the search.
    drapes: int
    #: The window of the final fit [rad]: α* lies inside it; its half-width is the resolution.
    bracket_rad: tuple[float, float]
    #: Standard error of α* from the final least-squares fit [rad] (None with 3 points).
    vertex_std_rad: float | None
    #: The optimum sits at (within the scan step of) an end of the searched range.
    at_boundary: bool
    #: The refinement stopped because the energy's staircase noise hid the curvature.
    noise_limited: bool
    #: The part's reference area [m²] and the energy density charged where it is bare [J/m²]
    #: (0 unless the user priced it).
    reference_area_m2: float
    uncovered_energy_density_J_per_m2: float
    #: Uncertainty of α* from E(α) near the minimum [rad] (module docstring), None when too
    #: few samples lie near it; and the relative rms residual of E about the local cubic.
    uncertainty_rad: float | None = None
    residual_rms_rel: float | None = None
    #: The knobs the search ran with (degrees, for the record).
    settings: dict[str, Any] = field(default_factory=dict)
    #: False when no scanned angle can be made (module docstring, "What can be made"): the
    #: optimum is then the scan's angle of least wrinkle, not of least energy.
    makeable: bool = True
    #: The jumps of E(α) found between neighbouring samples (module docstring); no fit
    #: straddles one.
    discontinuities: tuple[Discontinuity, ...] = ()
    #: "fit" (α* is a fit's vertex, or a sample the fits confirmed) or "best sample" (the fit's
    #: drape was dearer than the best sample, or no fit could be made: ``optimum_note`` says
    #: why).
    optimum_from: str = "fit"
    optimum_note: str = ""
    #: Fabric area [m²] (d² a cell) left out of every angle's energy because some compared
    #: angle fails to drape it (module docstring), and its share of the counted fabric [-].
    excluded_fabric_area_m2: float = 0.0
    #: The fold zones of the drape at α* (undeformed plan centre (x, y) [m], fabric area
    #: [m²], largest first).
    optimum_fold_zones: tuple[tuple[tuple[float, float], float], ...] = ()

    @property
    def optimum_angle_deg(self) -> float:
        return math.degrees(self.optimum_angle_rad)

    @property
    def bracket_half_width_rad(self) -> float:
        return 0.5 * (self.bracket_rad[1] - self.bracket_rad[0])

    def curve_deg(self) -> list[tuple[float, float]]:
        """(α [deg], E [J]) pairs of every evaluated angle, sorted by angle."""
        return [(p.generator_angle_deg, p.energy_J) for p in self.points]

    def summary(self) -> dict[str, Any]:
        """JSON-ready record (degrees, J, m²)."""
        return {
            "optimum_generator_angle_deg": self.optimum_angle_deg,
            "optimum_energy_J": self.optimum_energy_J,
            "bracket_deg": [math.degrees(a) for a in self.bracket_rad],
            "bracket_half_width_deg": math.degrees(self.bracket_half_width_rad),
            "vertex_std_deg": (
                None if self.vertex_std_rad is None else math.degrees(self.vertex_std_rad)
            ),
            "uncertainty_deg": (
                None if self.uncertainty_rad is None else math.degrees(self.uncertainty_rad)
            ),
            "residual_rms_rel": self.residual_rms_rel,
            "at_boundary": self.at_boundary,
            "noise_limited": self.noise_limited,
            "drapes": self.drapes,
            "reference_area_m2": self.reference_area_m2,
            "uncovered_energy_density_J_per_m2": self.uncovered_energy_density_J_per_m2,
            "min_coverage": min((p.coverage for p in self.points), default=1.0),
            "makeable": self.makeable,
            "discontinuities": [jump.summary() for jump in self.discontinuities],
            "optimum_from": self.optimum_from,
            "optimum_note": self.optimum_note,
            "excluded_fabric_area_m2": self.excluded_fabric_area_m2,
            "optimum_fold_zones": len(self.optimum_fold_zones),
            "optimum_fold_zone_area_m2": float(sum(a for _, a in self.optimum_fold_zones)),
            "optimum_fold_zone_centres_m": [list(c) for c, _ in self.optimum_fold_zones],
            **self.settings,
        }


def _scan_layout(lo_rad: float, hi_rad: float, step_rad: float) -> tuple[float, int, int]:
    """(origin, k_lo, k_hi) of :func:`scan_angles`' grid origin + k·step; raises SearchError
    for an empty range, and for a step so small the grid's indices overflow."""
    if not (lo_rad < hi_rad and step_rad > 0):
        raise SearchError(f"need lo < hi and step > 0, got [{lo_rad}, {hi_rad}], {step_rad}")
    half = 0.5 * math.pi
    eps = 1e-9 * step_rad
    origin = half if lo_rad - eps <= half <= hi_rad + eps else lo_rad
    low, high = (lo_rad - origin - eps) / step_rad, (hi_rad - origin + eps) / step_rad
    if not (math.isfinite(low) and math.isfinite(high)):
        raise SearchError(f"a scan step of {step_rad!r} rad is too small to count")
    return origin, math.ceil(low), math.floor(high)


def scan_size(lo_rad: float, hi_rad: float, step_rad: float) -> int:
    """Number of angles :func:`scan_angles` gives, by arithmetic, so that a budget is checked
    before a grid is built (a step of 1e-12° must not build 10¹⁴ angles)."""
    try:
        origin, k_lo, k_hi = _scan_layout(lo_rad, hi_rad, step_rad)
    except SearchError:
        if lo_rad < hi_rad and step_rad > 0:
            return 2**63  # uncountably many, for any budget
        raise
    eps = 1e-9 * step_rad
    ends = sum(
        1 for end, k in ((lo_rad, k_lo), (hi_rad, k_hi)) if abs(origin + k * step_rad - end) > eps
    )
    return max(k_hi - k_lo + 1, 0) + ends


def scan_angles(lo_rad: float, hi_rad: float, step_rad: float) -> FloatArray:
    """Scan grid [rad] over [lo, hi]: 90° ± k·step when 90° is inside, plus both ends.

    Laid about 90° (not from ``lo``) so a range symmetric about 90° gives a grid symmetric
    about it, and 90° itself is always sampled when the range contains it.
    """
    half = 0.5 * math.pi
    eps = 1e-9 * step_rad
    origin, k_lo, k_hi = _scan_layout(lo_rad, hi_rad, step_rad)
    grid = [origin + k * step_rad for k in range(k_lo, k_hi + 1)]
    # Mirror pairs computed as half ± k·step are symmetric to the last bit.
    if origin == half:
        grid = [
            half + k * step_rad if k >= 0 else half - (-k) * step_rad for k in range(k_lo, k_hi + 1)
        ]
    values = np.array(grid)
    ends = [a for a in (lo_rad, hi_rad) if np.all(np.abs(values - a) > eps)]
    return np.sort(np.concatenate([values, ends]))


@dataclass
class _Fit:
    vertex: float
    curvature: float
    std: float | None


def _parabola(x: FloatArray, y: FloatArray, centre: float) -> _Fit | None:
    """Least-squares y ≈ a·t² + b·t + c, t = x − centre; vertex, 2a, and the vertex's std."""
    if len(x) < 3 or len(np.unique(np.round((x - centre) / max(np.ptp(x), 1e-300), 12))) < 3:
        return None
    t = x - centre
    scale = float(np.max(np.abs(t))) or 1.0
    s = t / scale
    design = np.column_stack([s * s, s, np.ones_like(s)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    a, b = float(coef[0]), float(coef[1])
    if not a > 0:
        return _Fit(math.nan, 2.0 * a / scale**2, None)
    vertex_s = -b / (2.0 * a)
    std = None
    if len(x) > 3:
        residual = y - design @ coef
        var = float(residual @ residual) / (len(x) - 3)
        cov = var * np.linalg.pinv(design.T @ design)
        grad = np.array([b / (2.0 * a * a), -1.0 / (2.0 * a), 0.0])
        std = math.sqrt(max(float(grad @ cov @ grad), 0.0)) * scale
    return _Fit(centre + vertex_s * scale, 2.0 * a / scale**2, std)


def optimum_uncertainty(
    angles_rad: FloatArray, energies_J: FloatArray, optimum_rad: float, window_rad: float
) -> tuple[float | None, float | None]:
    """Uncertainty [rad] of a least-energy angle and E's relative rms roughness [-] from the
    samples (α [rad], E [J]) within ``window_rad`` of ``optimum_rad`` (module docstring).
    (None, None) with fewer than 5 samples there or no convex parabola."""
    x = np.asarray(angles_rad, dtype=float)
    y = np.asarray(energies_J, dtype=float)
    near = (np.abs(x - optimum_rad) <= window_rad * (1 + 1e-9)) & np.isfinite(y)
    x, y = x[near], y[near]
    if len(x) < 5:
        return None, None
    fit = _parabola(x, y, optimum_rad)
    if fit is None or not fit.curvature > 0 or fit.std is None:
        return None, None
    scale = float(np.max(np.abs(x - optimum_rad))) or 1.0
    t = (x - optimum_rad) / scale
    coef = np.polyfit(t, y, 3)
    residual = y - np.polyval(coef, t)
    rms = float(np.sqrt(np.mean(residual**2)) / max(float(np.mean(np.abs(y))), 1e-300))
    # The cubic's minimum nearest the parabola's vertex.
    roots = np.roots(np.polyder(coef))
    real = roots[np.abs(roots.imag) < 1e-12].real
    minima = [r for r in real if np.polyval(np.polyder(coef, 2), r) > 0]
    vertex_t = (fit.vertex - optimum_rad) / scale
    if not minima:
        return None, rms
    cubic = float(min(minima, key=lambda r: abs(r - vertex_t)))
    shape = (cubic - vertex_t) * scale
    return math.sqrt(fit.std**2 + shape**2), rms


def search_generator_angle(
    objective: DrapeObjective,
    *,
    angle_range_rad: tuple[float, float] = (math.radians(30.0), math.radians(150.0)),
    scan_step_rad: float = DEFAULT_SCAN_STEP_RAD,
    tolerance_rad: float = DEFAULT_TOLERANCE_RAD,
    max_drapes: int = DEFAULT_MAX_DRAPES,
    min_coverage: float = 0.0,
    part_area_m2: float | None = None,
    max_wrinkle_area_share: float | None = None,
    wrinkle_area_tolerance: float = WRINKLE_AREA_TOLERANCE,
) -> AngleSearchResult:
    """The generator angle α [rad] of least comparable energy over ``angle_range_rad`` [rad].

    A scan every ``scan_step_rad`` [rad] (:func:`scan_angles`), then least-squares parabolic
    refinement around the best scan point with steps δ = step/2, step/4, ... down to
    ``tolerance_rad`` [rad] (module docstring), at most ``max_drapes`` drapes in all; finally a
    drape at the optimum itself. ``part_area_m2`` [m²] fixes the reference area (default: the
    part's own area when it knows it, else the largest area covered in the scan);
    ``min_coverage`` [-] marks angles below it infeasible, and so does an angle that cannot be
    made (module docstring, "What can be made"): a share of its covered area past a wrinkle
    limit more than ``wrinkle_area_tolerance`` [-] above the least share any evaluated angle
    reaches or, when given, more than ``max_wrinkle_area_share`` [-].
    """
    if not 0.0 <= wrinkle_area_tolerance <= 1.0:
        raise SearchError(f"wrinkle_area_tolerance {wrinkle_area_tolerance!r} must lie in [0, 1]")
    lo, hi = (float(a) for a in angle_range_rad)
    if not (0.0 < lo < hi < math.pi):
        raise SearchError(
            f"the generator-angle range must lie in (0°, 180°), got "
            f"[{math.degrees(lo):.6g}°, {math.degrees(hi):.6g}°]"
        )
    if not tolerance_rad > 0:
        raise SearchError("tolerance must be positive")
    first = objective.drapes
    needed = scan_size(lo, hi, scan_step_rad)
    if needed > max_drapes:
        # Counted before the grid is built: a step of 1e-12° must not build 10¹⁴ angles.
        raise SearchError(
            f"the scan alone needs {needed:,} drapes, more than max_drapes = "
            f"{max_drapes}; widen the step or raise the budget"
        )
    settings: dict[str, Any] = {
        "range_deg": [math.degrees(lo), math.degrees(hi)],
        "scan_step_deg": math.degrees(scan_step_rad),
        "tolerance_deg": math.degrees(tolerance_rad),
        "max_drapes": max_drapes,
        "min_coverage_required": min_coverage,
        "uncovered_shear_deg": (
            None
            if objective.uncovered_shear_rad is None
            else math.degrees(objective.uncovered_shear_rad)
        ),
        "max_wrinkle_area_share": max_wrinkle_area_share,
        "wrinkle_area_tolerance": wrinkle_area_tolerance,
    }
    grid = scan_angles(lo, hi, scan_step_rad)
    evaluated: dict[float, tuple[DrapeEvaluation, str]] = {}
    for alpha in grid:
        evaluated[float(alpha)] = (objective.evaluate(float(alpha)), "scan")
    if part_area_m2 is not None:
        reference = float(part_area_m2)
    elif objective.part_area_m2 is not None:
        reference = float(objective.part_area_m2)
    else:
        reference = max(ev.covered_area_m2 for ev, _ in evaluated.values())
    if not reference > 0:
        raise SearchError("no drape of the scan covers any of the part")

    def least_wrinkle_area_share() -> float:
        """The least wrinkled area share of any evaluated angle that drapes and covers."""
        shares = [
            ev.wrinkle_area_share
            for ev, _ in evaluated.values()
            if ev.draped and min(1.0, ev.covered_area_m2 / reference) >= min_coverage
        ]
        return min(shares, default=0.0)

    def point(alpha: float) -> SearchPoint:
        ev, stage = evaluated[alpha]
        energy = objective.charged(ev, reference)
        coverage = min(1.0, ev.covered_area_m2 / reference)
        can = makeable(
            ev.wrinkle_area_share,
            least_wrinkle_area_share(),
            wrinkle_area_tolerance,
            max_wrinkle_area_share,
        )
        return SearchPoint(
            alpha,
            energy,
            ev.drape_energy_J,
            energy - ev.drape_energy_J,
            ev.covered_area_m2,
            coverage,
            ev.draped and coverage >= min_coverage and can,
            stage,
            ev.max_abs_shear_rad,
            ev.wrinkle_area_share,
            ev.wrinkle_energy_share,
            can,
        )

    accounting = _SameFabric(evaluated, point, float(objective.drape_kwargs["node_spacing_m"]))

    def feasible_samples(centre: float | None = None) -> tuple[FloatArray, FloatArray]:
        """Feasible samples (α, compared E), within the continuous span about ``centre``."""
        pts = accounting.points()
        ok = [p for p in pts if p.feasible and math.isfinite(p.energy_J)]
        if centre is not None:
            low, high = continuous_span(centre, accounting.jumps(reference), lo, hi)
            ok = [p for p in ok if low - 1e-12 <= p.generator_angle_rad <= high + 1e-12]
        return (np.array([p.generator_angle_rad for p in ok]), np.array([p.energy_J for p in ok]))

    xs, _ = feasible_samples()
    if xs.size == 0:
        # No angle can be made: the one that wrinkles least, said so (module docstring).
        scanned = [point(a) for a in sorted(evaluated)]
        return _least_wrinkle(objective, scanned, first, reference, settings, min_coverage)

    def best_sample() -> tuple[float, float]:
        """The feasible sample of least compared energy (α, E); ties (a symmetric set-up) go
        to the angle nearest the middle of the range."""
        x, y = feasible_samples()
        if x.size == 0:
            raise SearchError(f"no generator angle in the scan reaches coverage {min_coverage}")
        # Exact ties only: the optimum's energy may not exceed the lowest by even a rounding.
        ties = np.flatnonzero(y == y.min())
        k = int(ties[np.argmin(np.abs(x[ties] - 0.5 * (lo + hi)))])
        return float(x[k]), float(y[k])

    estimate, _ = best_sample()
    at_boundary = estimate in (float(xs[0]), float(xs[-1]))
    half_window = scan_step_rad
    vertex_std: float | None = None
    noise_limited = False

    def refit(centre: float, window: float) -> tuple[_Fit | None, float, float, bool]:
        """The parabola over the samples within ``window`` of ``centre`` and on its side of
        every jump, the span [rad] its vertex may move in, and whether a jump cuts the
        window."""
        x, y = feasible_samples(centre)
        low, high = continuous_span(centre, accounting.jumps(reference), lo, hi)
        # A relative slack keeps a mirror pair together at the window's edge.
        inside = np.abs(x - centre) <= window * (1 + 1e-6)
        span = (max(low, centre - window), min(high, centre + window))
        eps = 1e-9 * window
        cut = span[0] > max(lo, centre - window) + eps or span[1] < min(hi, centre + window) - eps
        return _parabola(x[inside], y[inside], centre), span[0], span[1], cut

    def cheapest_near(centre: float, window: float) -> float:
        """The feasible sample of least energy within ``window`` of ``centre`` [rad]."""
        x, y = feasible_samples()
        near = np.abs(x - centre) <= window * (1 + 1e-6)
        return float(x[near][np.argmin(y[near])]) if near.any() else centre

    def recentre(centre: float, window: float) -> float:
        # Where a jump cuts the window the minimum may lie on its other side: the fit is made
        # about the cheapest sample of the window, on that sample's side.
        return cheapest_near(centre, window) if refit(centre, window)[3] else centre

    estimate = recentre(estimate, half_window)
    fit, low, high, _ = refit(estimate, half_window)
    if fit is not None and fit.curvature > 0:
        estimate = float(np.clip(fit.vertex, low, high))
        vertex_std = fit.std
    delta = 0.5 * scan_step_rad
    while delta >= tolerance_rad:
        probes = [estimate - delta, estimate, estimate + delta]
        known = np.array(list(evaluated))
        new = [a for a in probes if lo <= a <= hi and np.all(np.abs(known - a) > 1e-9 * delta)]
        if objective.drapes - first + len(new) > max_drapes - 1:
            break
        for alpha in new:
            evaluated[alpha] = (objective.evaluate(alpha), "refine")
        window = 2.0 * delta
        estimate = recentre(estimate, window)
        fit, low, high, cut = refit(estimate, window)
        if fit is None and cut:
            # A jump leaves too few samples on the estimate's side for a fit: go on by
            # bisection about the cheapest sample, which also narrows where the jump lies.
            vertex_std = None
            half_window = delta
            delta *= 0.5
            continue
        if fit is None or not fit.curvature > 0:
            noise_limited = fit is not None
            break
        estimate = float(np.clip(fit.vertex, low, high))
        vertex_std = fit.std
        half_window = window
        delta *= 0.5
    estimate = float(np.clip(estimate, lo, hi))
    known = np.array(list(evaluated))
    nearest = float(known[np.argmin(np.abs(known - estimate))])
    if abs(nearest - estimate) <= 1e-9 * tolerance_rad:
        estimate = nearest
    else:
        evaluated[estimate] = (objective.evaluate(estimate), "optimum")
    # Judged on the fabric every compared angle drapes, the optimum's drape included (its
    # lost cells leave the others' sums too), and never dearer than the best sample.
    final = accounting.point(estimate)
    sample_angle, sample_energy = best_sample()
    optimum_from, note = "fit", ""
    if not final.feasible or not final.energy_J <= sample_energy:
        why = (
            "is not feasible"
            if not final.feasible
            else f"costs {final.energy_J:.6g} J, more than the best sample's {sample_energy:.6g} J"
        )
        note = (
            f"the refined estimate {math.degrees(estimate):.6g}° {why}; the optimum is the "
            f"best sample, {math.degrees(sample_angle):.6g}°"
        )
        optimum_from, estimate = "best sample", sample_angle
        final = accounting.point(estimate)
        vertex_std = None
    jumps = accounting.jumps(reference)
    low, high = continuous_span(estimate, jumps, lo, hi)
    if optimum_from == "fit" and low == high:
        optimum_from = "best sample"
        note = (
            f"E(α) jumps on both sides of the sample {math.degrees(estimate):.6g}°, so no fit "
            "can be made there; the optimum is that sample"
        )
        vertex_std = None
    at_boundary = at_boundary or min(estimate - lo, hi - estimate) < 0.5 * scan_step_rad
    points = accounting.points()
    ok = [
        p
        for p in points
        if p.feasible
        and math.isfinite(p.energy_J)
        and low - 1e-12 <= p.generator_angle_rad <= high + 1e-12
    ]
    uncertainty, roughness = optimum_uncertainty(
        np.array([p.generator_angle_rad for p in ok]),
        np.array([p.energy_J for p in ok]),
        estimate,
        scan_step_rad,
    )
    if optimum_from == "best sample":
        # The minimum lies between the best sample's feasible neighbours, as far as the
        # samples tell.
        angles = sorted(p.generator_angle_rad for p in points if p.feasible)
        k = angles.index(estimate)
        bracket = (angles[max(k - 1, 0)], angles[min(k + 1, len(angles) - 1)])
    else:
        bracket = (max(lo, estimate - half_window), min(hi, estimate + half_window))
    final_ev = evaluated[estimate][0]
    return AngleSearchResult(
        optimum_angle_rad=estimate,
        optimum_energy_J=final.energy_J,
        points=points,
        drapes=objective.drapes - first,
        bracket_rad=bracket,
        vertex_std_rad=vertex_std,
        at_boundary=at_boundary,
        noise_limited=noise_limited,
        reference_area_m2=reference,
        uncovered_energy_density_J_per_m2=objective.uncovered_energy_density,
        uncertainty_rad=uncertainty,
        residual_rms_rel=roughness,
        settings=settings,
        discontinuities=jumps,
        optimum_from=optimum_from,
        optimum_note=note,
        excluded_fabric_area_m2=accounting.excluded_area_m2(),
        optimum_fold_zones=final_ev.fold_zones,
    )


def _least_wrinkle(
    objective: DrapeObjective,
    scanned: list[SearchPoint],
    first: int,
    reference: float,
    settings: dict[str, Any],
    min_coverage: float,
) -> AngleSearchResult:
    """The scan's angle of least wrinkle when none can be made (module docstring): least
    area share past the wrinkle limits, then least energy share, then least energy, among the
    angles that drape and reach ``min_coverage``; ties to the middle of the range. Not
    refined: the wrinkle shares are no smooth objective, and the angle is a sampled one."""
    candidates = [p for p in scanned if p.coverage >= min_coverage and math.isfinite(p.energy_J)]
    if not candidates:
        raise SearchError(f"no generator angle in the scan reaches coverage {min_coverage}")
    lo, hi = (math.radians(a) for a in settings["range_deg"])
    best = min(
        candidates,
        # rounded, so that mirror angles of a symmetric set-up tie to the last bits
        key=lambda p: (
            round(p.wrinkle_area_share, 12),
            round(p.wrinkle_energy_share, 12),
            p.energy_J,
            abs(p.generator_angle_rad - 0.5 * (lo + hi)),
        ),
    )
    step = math.radians(settings["scan_step_deg"])
    alpha = best.generator_angle_rad
    return AngleSearchResult(
        optimum_angle_rad=alpha,
        optimum_energy_J=best.energy_J,
        points=tuple(scanned),
        drapes=objective.drapes - first,
        bracket_rad=(max(lo, alpha - step), min(hi, alpha + step)),
        vertex_std_rad=None,
        at_boundary=min(alpha - lo, hi - alpha) < 0.5 * step,
        noise_limited=False,
        reference_area_m2=reference,
        uncovered_energy_density_J_per_m2=objective.uncovered_energy_density,
        settings=settings,
        makeable=False,
    )


class _SameFabric:
    """The search's samples judged on the same fabric (module docstring, "The same fabric at
    every angle"): a ply cell that a feasible sample fails to drape (a fold zone, or a cell
    asked for and not covered) is left out of every sample's energy. Recomputed only when a
    sample is added."""

    def __init__(
        self,
        evaluated: dict[float, tuple[DrapeEvaluation, str]],
        point: Callable[[float], SearchPoint],
        node_spacing_m: float,
    ) -> None:
        self._evaluated = evaluated
        self._point = point
        self._spacing = float(node_spacing_m)
        self._reference = math.nan
        self._count = -1
        self._points: dict[float, SearchPoint] = {}
        self._excluded: BoolArray | None = None
        self._jumps: tuple[Discontinuity, ...] = ()

    def _update(self) -> None:
        if self._count == len(self._evaluated):
            return
        base = {alpha: self._point(alpha) for alpha in self._evaluated}
        masks = [
            ev.lost_cells
            for alpha, (ev, _) in self._evaluated.items()
            if base[alpha].feasible and ev.lost_cells is not None
        ]
        shapes = {mask.shape for mask in masks}
        excluded = None
        if len(shapes) == 1 and any(mask.any() for mask in masks):
            excluded = np.logical_or.reduce(masks)
        self._excluded = excluded
        self._points = {}
        for alpha, p in base.items():
            ev = self._evaluated[alpha][0]
            removed = 0.0
            cells = ev.cell_energy_J
            if excluded is not None and cells is not None and cells.shape == excluded.shape:
                removed = float(cells[excluded].sum())
            self._points[alpha] = dataclasses.replace(
                p,
                energy_J=p.energy_J - removed,
                excluded_energy_J=removed,
                cells_counted=ev.cells_counted,
                fold_zones=len(ev.fold_zones),
                fold_zone_area_m2=ev.fold_zone_area_m2,
                lost_area_m2=ev.lost_area_m2,
            )
        self._count = len(self._evaluated)
        self._jumps = ()
        self._reference = math.nan

    def point(self, alpha: float) -> SearchPoint:
        self._update()
        return self._points[alpha]

    def points(self) -> tuple[SearchPoint, ...]:
        self._update()
        return tuple(self._points[a] for a in sorted(self._points))

    def jumps(self, reference_area_m2: float) -> tuple[Discontinuity, ...]:
        self._update()
        if self._reference != reference_area_m2:
            self._jumps = find_discontinuities(self.points(), reference_area_m2)
            self._reference = reference_area_m2
        return self._jumps

    def excluded_area_m2(self) -> float:
        self._update()
        if self._excluded is None:
            return 0.0
        return float(np.count_nonzero(self._excluded)) * self._spacing**2


# --------------------------------------------------------------------------------------------
# Orientation and start point


@dataclass(frozen=True)
class LayoutResult:
    """The best (generator angle, orientation, start point) found by :func:`search_layout`."""

    generator_angle_rad: float
    orientation_rad: float
    start_xy_m: tuple[float, float]
    energy_J: float
    #: Energy [J] of the layout the search started from.
    initial_energy_J: float
    drapes: int
    converged: bool
    #: Names of the varied quantities.
    varied: tuple[str, ...]


_LAYOUT_VARIABLES = ("generator_angle", "orientation", "start_point")


def search_layout(
    objective: DrapeObjective,
    *,
    generator_angle_rad: float,
    orientation_rad: float = 0.0,
    start_xy_m: tuple[float, float] = (0.0, 0.0),
    vary: Sequence[str] = _LAYOUT_VARIABLES,
    reference_area_m2: float | None = None,
    angle_step_rad: float = math.radians(5.0),
    orientation_step_rad: float = math.radians(10.0),
    start_step_m: float | None = None,
    tolerance_rad: float = math.radians(0.5),
    max_drapes: int = 80,
    wrinkle_area_tolerance: float = WRINKLE_AREA_TOLERANCE,
) -> LayoutResult:
    """Nelder–Mead over the generator angle α [rad], orientation θ [rad] and start (x, y) [m].

    Chosen over a coordinate search because the variables interact (turning the generators
    and moving the start both move where the shear lands) and because it needs no gradient of
    an energy with a small staircase in it. Variables are scaled by their initial steps
    (``angle_step_rad``, ``orientation_step_rad``, ``start_step_m``, default 4·d), which also
    size the starting simplex; it stops when the simplex is smaller than ``tolerance_rad``
    in scaled angle units or after ``max_drapes`` drapes. The reference area (for a priced
    uncovered area) is fixed for the whole search (default: the starting layout's coverage),
    so every layout is judged on the same part; a layout that covers less of the part than the
    starting one (by more than :data:`COVERAGE_SLACK`) is infeasible, and so is one with a
    share of its covered part past a wrinkle limit more than ``wrinkle_area_tolerance`` [-]
    above the starting layout's (module docstring, "What can be made": the start is the angle
    search's makeable optimum).
    """
    from scipy.optimize import minimize

    names = tuple(vary)
    unknown = set(names) - set(_LAYOUT_VARIABLES)
    if unknown or not names:
        raise SearchError(f"vary must name some of {_LAYOUT_VARIABLES}, got {names}")
    d = float(objective.drape_kwargs["node_spacing_m"])
    start_step = 4.0 * d if start_step_m is None else float(start_step_m)
    x0: list[float] = []
    scale: list[float] = []
    if "generator_angle" in names:
        x0.append(generator_angle_rad)
        scale.append(angle_step_rad)
    if "orientation" in names:
        x0.append(orientation_rad)
        scale.append(orientation_step_rad)
    if "start_point" in names:
        x0 += [float(start_xy_m[0]), float(start_xy_m[1])]
        scale += [start_step, start_step]
    steps = np.array(scale)
    first = objective.drapes

    def unpack(z: FloatArray) -> tuple[float, float, tuple[float, float]]:
        values = list(np.asarray(z) * steps)
        alpha = values.pop(0) if "generator_angle" in names else generator_angle_rad
        theta = values.pop(0) if "orientation" in names else orientation_rad
        xy = (values[0], values[1]) if "start_point" in names else start_xy_m
        return float(alpha), float(theta), (float(xy[0]), float(xy[1]))

    initial = objective.evaluate(
        generator_angle_rad, orientation_rad=orientation_rad, start_xy_m=start_xy_m
    )
    reference = initial.covered_area_m2 if reference_area_m2 is None else float(reference_area_m2)
    initial_energy = objective.charged(initial, reference)

    must_cover = (1.0 - COVERAGE_SLACK) * min(initial.covered_area_m2, reference)
    most_wrinkle = initial.wrinkle_area_share + wrinkle_area_tolerance

    def energy(z: FloatArray) -> float:
        alpha, theta, xy = unpack(z)
        if not 0.0 < alpha < math.pi:
            return math.inf
        ev = objective.evaluate(alpha, orientation_rad=theta, start_xy_m=xy)
        if ev.covered_area_m2 < must_cover:
            return math.inf  # leaves the part barer than the start: infeasible, not priced
        if ev.wrinkle_area_share > most_wrinkle:
            return math.inf  # wrinkles more than the start: cannot be made, not cheap
        return objective.charged(ev, reference)

    z0 = np.array(x0) / steps
    simplex = np.vstack([z0, z0 + np.eye(len(z0))])
    budget = max(max_drapes - 1, len(z0) + 2)
    res = minimize(
        energy,
        z0,
        method="Nelder-Mead",
        options={
            "initial_simplex": simplex,
            "xatol": tolerance_rad / angle_step_rad,
            "fatol": 1e-9 * max(abs(initial_energy), 1e-300),
            "maxfev": budget,
        },
    )
    alpha, theta, xy = unpack(res.x)
    best = float(res.fun)
    if not best < initial_energy:
        alpha, theta, xy, best = generator_angle_rad, orientation_rad, start_xy_m, initial_energy
    return LayoutResult(
        alpha,
        theta,
        (float(xy[0]), float(xy[1])),
        best,
        initial_energy,
        objective.drapes - first,
        bool(res.success),
        names,
    )


def with_generators(objective: DrapeObjective, generators: Any) -> DrapeObjective:
    """A copy of ``objective`` draping with other ``generators`` (e.g. curved ones)."""
    clone = DrapeObjective.__new__(DrapeObjective)
    clone.__dict__.update(objective.__dict__)
    clone.drape_kwargs = {**objective.drape_kwargs, "generators": generators}
    clone.drapes = 0
    return clone


__all__ = [
    "COVERAGE_SLACK",
    "AngleSearchResult",
    "DrapeEvaluation",
    "DrapeObjective",
    "LayoutResult",
    "SearchError",
    "SearchPoint",
    "scan_angles",
    "scan_size",
    "search_generator_angle",
    "search_layout",
    "with_generators",
]
