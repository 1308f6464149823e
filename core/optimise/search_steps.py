"""Pipeline steps of the minimum-energy drape: E(α), the optimum, and the paper's Fig. 10.

A scene with a ``search`` section asks for them (``outputs: [energy_vs_angle, optimum,
library_energy_png, ...]``); the drape step then drapes at the optimum. The two E(α) figures
are named apart: ``library_energy_png`` is the run-level Fig. 10 (every fabric of the scene on
one figure, drawn once after the cases, nothing per case); ``energy_plot_png`` is one figure
per case, worth its cost only when a fabric is studied on its own. The search section's
fidelity knobs (degrees, as in every scene; defaults in brackets):

    search:
      generator_angle_deg: {min: 30, max: 150, step: 5}   # range [30, 150]; step = scan step
      scan_step_deg: 5            # same as generator_angle_deg.step [5]
      tolerance_deg: 1            # refinement stops below this step [1]
      max_drapes: 60              # budget of the angle search [60]
      min_coverage: 0.0           # angles covering less of the part are infeasible [0]
      wrinkle_area_tolerance: 0.02   # an angle can be made when its share of area past
                                  # jamming or stitch failure is within this of the least [0.02]
      max_wrinkle_area_share: null   # and, when set, at most this share [off]
      part_area_mm2: null         # the part's area; default: the part's own (a bare
                                  # hemisphere: 2πR²), else the best coverage of the scan
      uncovered_shear_deg: null   # price bare part area at W(this shear) [off: no charge];
                                  # when set, the case is partial
      layout: {vary: [orientation, start_point], max_drapes: 60}   # Nelder–Mead [off]
      curved_generators: {terms: 2, mirror_families: false, max_drapes: 120}      # [off]
      relax: false                # beyond the paper; coarse nets only [off]; or
                                  # {max_rounds: 8, max_iterations: 1500}

Every knob used is recorded in the case summary (``search_settings``).

The steps say what the search is worth (``docs/results.md``): an optimum at an end of the
searched range or one the energy's staircase kept from resolving is a warning; a drape at the
optimum that does not cover the ply where it lies over the tool makes the case partial; angles
whose drape shears cells past the law's packing limit or data range are named, since E(α) there
is the law's continuation, not a measured or physical energy; a law that returns NaN, or a start
point off the tool, fails the case with the reason.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base import fidelity
from preform.base.status import CaseFailure
from preform.drape.engine.fields import energy_field
from preform.drape.engine.settings import DrapeSettings
from preform.drape.judging.verdict import coverage, fabric_law_range, law_nonfinite_angle
from preform.drape.judging.wrinkling import WRINKLE_AREA_TOLERANCE, wrinkling
from preform.drape.steps import (
    drape_settings,
    judge_wrinkling,
    record_knobs,
    relaxed_result,
    start_problem,
    summed_law,
)
from preform.optimise.search import (
    AngleSearchResult,
    DrapeEvaluation,
    DrapeObjective,
    SearchError,
    scan_size,
    search_generator_angle,
    search_layout,
)
from preform.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene
    from preform.yamlsource import Document, SourceError

MM = 1e-3


@dataclass(frozen=True)
class AngleStudy:
    """The ``energy_vs_angle`` product: the search and the objective it used."""

    search: AngleSearchResult
    objective: DrapeObjective
    #: The drape set-up the objective was built from (its fidelity knobs resolved once).
    settings: DrapeSettings


def search_knobs(
    scene: Scene, tool_size_m: float | None = None, knobs: fidelity.Knobs | None = None
) -> dict[str, Any]:
    """The search section's settings with the fidelity knobs resolved (degrees, mm²).
    ``knobs``: those a case already resolved (its ``DrapeSettings.fidelity``), else resolved
    here from the scene and the tool's size [m]."""
    section = scene.search
    if section is None:
        raise ValueError("the angle search needs the scene section 'search'")
    knobs = fidelity.resolve(scene, tool_size_m) if knobs is None else knobs
    span = section.generator_angle_deg
    return {
        "range_deg": [span.min, span.max] if span is not None else [30.0, 150.0],
        "scan_step_deg": knobs.scan_step_deg,
        "tolerance_deg": knobs.tolerance_deg,
        "max_drapes": knobs.max_drapes,
        "energy_table_step_deg": knobs.energy_table_step_deg,
        "min_coverage": section.min_coverage,
        "max_wrinkle_area_share": section.max_wrinkle_area_share,
        "wrinkle_area_tolerance": section.wrinkle_area_tolerance,
        "part_area_mm2": section.part_area_mm2,
        "uncovered_shear_deg": section.uncovered_shear_deg,
        "layout": section.layout,
        "curved_generators": section.curved_generators,
        "relax": section.relax,
    }


def build_objective(ctx: CaseContext, settings: DrapeSettings) -> DrapeObjective:
    """The drape-and-judge objective of the case: its tool, ply, start and shear law."""
    if not isinstance(settings.generators, str):
        raise ValueError(
            "the generator-angle search needs geodesic or plan generators, not "
            "polylines (polylines fix the angle themselves)"
        )
    knobs = search_knobs(ctx.scene, knobs=settings.fidelity)
    shear = knobs["uncovered_shear_deg"]
    table = knobs["energy_table_step_deg"]
    return DrapeObjective(
        ctx.products["surface"],
        ctx.products["shear_law"],
        uncovered_shear_rad=None if shear is None else math.radians(float(shear)),
        energy_table_step_rad=math.radians(table) if table > 0 else None,
        **settings.keywords(),
    )


def run_energy_vs_angle(ctx: CaseContext) -> dict[str, Any]:
    settings = drape_settings(ctx.scene, ctx.products["surface"])
    knobs = search_knobs(ctx.scene, knobs=record_knobs(ctx, settings))
    with np.errstate(invalid="ignore", over="ignore"):
        objective = build_objective(ctx, settings)
    where = objective.drape_kwargs.get("start_xy_m")
    if where is not None:
        problem = start_problem(objective.surface, where)
        if problem is not None:
            raise CaseFailure(f"the search cannot drape: {problem}")
    area = knobs["part_area_mm2"]
    try:
        # A non-finite law is detected below and failed in words; numpy's own warnings about
        # it (from the energy table) would only repeat that without the angle.
        with np.errstate(invalid="ignore", over="ignore"):
            result = search_generator_angle(
                objective,
                angle_range_rad=(
                    math.radians(knobs["range_deg"][0]),
                    math.radians(knobs["range_deg"][1]),
                ),
                scan_step_rad=math.radians(knobs["scan_step_deg"]),
                tolerance_rad=math.radians(knobs["tolerance_deg"]),
                max_drapes=knobs["max_drapes"],
                min_coverage=knobs["min_coverage"],
                part_area_m2=None if area is None else float(area) * MM * MM,
                max_wrinkle_area_share=knobs["max_wrinkle_area_share"],
                wrinkle_area_tolerance=knobs["wrinkle_area_tolerance"],
            )
    except SearchError as error:
        broken = law_nonfinite_angle(objective.law)
        if broken is not None:
            raise CaseFailure(f"{broken}: no drape of the search has a finite energy") from None
        raise CaseFailure(f"the generator-angle search failed: {error}") from None
    bad = [p for p in result.points if p.coverage > 0 and not math.isfinite(p.energy_J)]
    if bad:
        broken = law_nonfinite_angle(objective.law)
        angles = ", ".join(f"{p.generator_angle_deg:.4g}°" for p in bad[:5])
        lead = broken or "total energy is not finite"
        raise CaseFailure(
            f"{lead}: E(α) is not finite at generator angle(s) {angles}"
            + (f" and {len(bad) - 5} more" if len(bad) > 5 else "")
        )
    _warn_law_range(ctx, result)
    ctx.summary["energy_vs_angle"] = [[a, e] for a, e in result.curve_deg()]
    ctx.summary["energy_vs_angle_coverage"] = [
        [p.generator_angle_deg, p.coverage] for p in result.points
    ]
    ctx.summary["energy_vs_angle_feasible"] = [
        [p.generator_angle_deg, p.feasible] for p in result.points
    ]
    ctx.summary["energy_vs_angle_table"] = trade_table(result)
    ctx.summary["search_makeable"] = result.makeable
    ctx.summary["search_angles_not_makeable"] = sum(not p.makeable for p in result.points)
    # The curve above is what the search compares (the same fabric at every angle); this is
    # each drape's whole energy of the part, fold zones' neighbours and all.
    ctx.summary["energy_vs_angle_drape_J"] = [
        [p.generator_angle_deg, p.drape_energy_J] for p in result.points
    ]
    ctx.summary["energy_vs_angle_fold_zones"] = [
        [p.generator_angle_deg, p.fold_zones, p.fold_zone_area_m2] for p in result.points
    ]
    ctx.summary["search_discontinuities"] = [jump.summary() for jump in result.discontinuities]
    ctx.summary["search_excluded_fabric_area_m2"] = result.excluded_fabric_area_m2
    ctx.summary["search_min_coverage"] = min(p.coverage for p in result.points)
    ctx.summary["search_reference_area_m2"] = result.reference_area_m2
    ctx.summary["search_uncovered_energy_density_J_per_m2"] = (
        result.uncovered_energy_density_J_per_m2
    )
    ctx.summary["search_drapes"] = result.drapes
    ctx.summary["search_settings"] = {**knobs, **result.settings}
    return {"energy_vs_angle": AngleStudy(result, objective, settings)}


#: Columns of the energy/wrinkle trade table (``energy_vs_angle.csv``, the summary's
#: ``energy_vs_angle_table``), one row per evaluated angle.
TRADE_COLUMNS = (
    "generator_angle_deg",
    "energy_J",
    "drape_energy_J",
    "coverage",
    "wrinkle_area_share",
    "wrinkle_energy_share",
    "makeable",
    "feasible",
    "max_abs_shear_deg",
    "stage",
)


def trade_table(search: AngleSearchResult) -> list[dict[str, Any]]:
    """The energy/wrinkle trade table of a search: per evaluated angle, by angle, its
    comparable energy [J], drape energy [J], coverage [-], the shares of its covered area and
    of its energy past a wrinkle limit [-], whether it can be made and is feasible, its
    largest |γ| [deg] and the search stage that drew it."""
    return [
        {
            "generator_angle_deg": p.generator_angle_deg,
            "energy_J": p.energy_J,
            "drape_energy_J": p.drape_energy_J,
            "coverage": p.coverage,
            "wrinkle_area_share": p.wrinkle_area_share,
            "wrinkle_energy_share": p.wrinkle_energy_share,
            "makeable": p.makeable,
            "feasible": p.feasible,
            "max_abs_shear_deg": math.degrees(p.max_abs_shear_rad),
            "stage": p.stage,
        }
        for p in search.points
    ]


def _angles_text(angles_deg: list[float]) -> str:
    shown = ", ".join(f"{a:.4g}°" for a in angles_deg[:6])
    return shown + (f" and {len(angles_deg) - 6} more" if len(angles_deg) > 6 else "")


def _warn_law_range(ctx: CaseContext, result: AngleSearchResult) -> None:
    """Name the searched angles whose drape leaves the law's physical or measured range."""
    law = ctx.products["shear_law"]
    limits = fabric_law_range(law, ctx.fabric)
    points = [p for p in result.points if p.coverage > 0]
    if limits.packing is not None:
        past = [p for p in points if p.max_abs_shear_rad > limits.packing]
        ctx.summary["search_angles_past_packing"] = len(past)
        if past:
            worst = max(p.energy_J for p in past)
            ctx.warn(
                f"at generator angle(s) {_angles_text([p.generator_angle_deg for p in past])} "
                f"the drape shears cells past {math.degrees(limits.packing):.1f}°, where the "
                "law's fabric is jammed: E(α) there (up to "
                f"{worst:.3g} J) is the law's continuation past that physical limit, not a "
                "physical energy",
                scan=True,
            )
    ends = [e for e in (limits.data_positive, limits.data_negative) if e is not None]
    if ends:
        # The search keeps only |γ|, so the smaller end of the two senses is the safe bound.
        end = min(ends)
        past = [p for p in points if p.max_abs_shear_rad > end]
        ctx.summary["search_angles_outside_law_data"] = len(past)
        if past:
            ctx.warn(
                f"at generator angle(s) {_angles_text([p.generator_angle_deg for p in past])} "
                f"the drape shears cells beyond the shear law's data range (up to "
                f"{math.degrees(end):.1f}° in one sense at least): E(α) there rests on the "
                "law's continuation past its data, not on measurements",
                scan=True,
            )


def _warn_accounting(ctx: CaseContext, search: AngleSearchResult) -> None:
    """Say how E(α) was compared and where it jumps (``preform.optimise.search``)."""
    if search.excluded_fabric_area_m2 > 0:
        ctx.warn(
            f"{1e6 * search.excluded_fabric_area_m2:.0f} mm² of the ply's fabric is left out "
            "of every angle's energy because the net fails to drape it (a fold zone, or fabric "
            "not reached) at some compared angle: the angles are compared on the fabric they "
            "all drape, so no angle looks cheap because part of the part dropped out of its sum",
            cause="fabric left out of the comparison",
        )
    jumps = search.discontinuities
    if jumps:
        shown = "; ".join(jump.words() for jump in jumps[:4])
        more = f"; and {len(jumps) - 4} more" if len(jumps) > 4 else ""
        ctx.warn(
            f"E(α) jumps at {len(jumps)} place(s) (no fit straddles one): {shown}{more}",
            scan=True,
        )
    if search.optimum_from != "fit":
        ctx.warn(
            f"the least-energy generator angle is a sample, not a fit: {search.optimum_note}",
            cause="optimum not resolved",
        )


def _warn_resolution(ctx: CaseContext, search: AngleSearchResult) -> None:
    lo, hi = search.settings.get("range_deg", [None, None])
    if search.at_boundary:
        ctx.warn(
            f"the least-energy generator angle {search.optimum_angle_deg:.4g}° lies at an end "
            f"of the searched range [{lo:.4g}°, {hi:.4g}°]: the true optimum may lie outside "
            "it; widen search.generator_angle_deg",
            cause="optimum at an end of the searched range",
        )
    if search.noise_limited:
        a, b = (math.degrees(v) for v in search.bracket_rad)
        ctx.warn(
            "the angle refinement stopped noise-limited: the energy's staircase (rim cells "
            "appearing and disappearing as α changes) hid its curvature, so the optimum "
            f"{search.optimum_angle_deg:.4g}° is resolved only to [{a:.4g}°, {b:.4g}°]; a "
            "finer node spacing resolves it better",
            cause="optimum not resolved",
        )


def _drape_at(objective: DrapeObjective, optimum: dict[str, Any]) -> DrapeEvaluation:
    """The optimum's drape judged on the part, its net kept (``keep_result``)."""
    return objective.evaluate(
        float(optimum["generator_angle_rad"]),
        orientation_rad=optimum.get("orientation_rad"),
        start_xy_m=optimum.get("start_xy_m"),
        generators=optimum.get("generators"),
        keep_result=True,
    )


def _judge_optimum_drape(
    ctx: CaseContext, objective: DrapeObjective, optimum: dict[str, Any]
) -> None:
    """Drape once at the optimum and mark the case partial when it does not cover the ply
    where it lies over the tool (the same words the drape step uses for the same net). Only
    for scenes that do not drape anyway."""
    evaluation = _drape_at(objective, optimum)
    if evaluation.result is None:
        raise CaseFailure("the drape at the least-energy generator angle cannot start")
    start = optimum.get("start_xy_m") or objective.drape_kwargs.get("start_xy_m") or (0.0, 0.0)
    cover = coverage(evaluation.result, objective.surface, (float(start[0]), float(start[1])))
    ctx.summary["optimum_covered_fraction"] = cover.covered_fraction
    if not cover.complete:
        ctx.partial(cover.reason(), cover.covered_fraction)
    elif cover.fold_zones:
        ctx.warn(cover.fold_warning(), cause="fold zones")
    # the status rule on wrinkling, as the drape step gives it (preform.drape.judging.wrinkling)
    result = evaluation.result
    counted = objective.counted(result)
    density = np.zeros(counted.shape)
    density[counted] = objective.energy_density(result.shear[counted])
    judge_wrinkling(
        ctx, wrinkling(result, density, objective.wrinkle_limits), cover.covered_fraction
    )


def run_optimum(ctx: CaseContext) -> dict[str, Any]:
    study: AngleStudy = ctx.products["energy_vs_angle"]
    search = study.search
    knobs = search_knobs(ctx.scene, knobs=study.settings.fidelity)
    optimum: dict[str, Any] = {
        "generator_angle_rad": search.optimum_angle_rad,
        "energy_J": search.optimum_energy_J,
    }
    record = search.summary()
    ctx.summary.update(
        {
            key if key.startswith("optimum_") else f"optimum_{key}": record[key]
            for key in (
                "optimum_generator_angle_deg",
                "optimum_energy_J",
                "bracket_deg",
                "bracket_half_width_deg",
                "vertex_std_deg",
                "uncertainty_deg",
                "residual_rms_rel",
                "at_boundary",
                "noise_limited",
                "optimum_from",
                "optimum_note",
                "optimum_fold_zones",
                "optimum_fold_zone_area_m2",
                "optimum_fold_zone_centres_m",
            )
        }
    )
    objective = study.objective
    at_optimum = min(
        search.points, key=lambda p: abs(p.generator_angle_rad - search.optimum_angle_rad)
    )
    uncovered = max(0.0, search.reference_area_m2 - at_optimum.covered_area_m2)
    ctx.summary["optimum_makeable"] = at_optimum.makeable
    ctx.summary["optimum_wrinkle_area_share"] = at_optimum.wrinkle_area_share
    ctx.summary["optimum_wrinkle_energy_share"] = at_optimum.wrinkle_energy_share
    ctx.summary["optimum_part_area_m2"] = search.reference_area_m2
    ctx.summary["optimum_uncovered_part_area_m2"] = uncovered
    if objective.uncovered_energy_density > 0:
        # A priced bare area is the user's stated choice: the energy is not the part's alone.
        assert objective.uncovered_shear_rad is not None
        ctx.partial(
            f"the search priced uncovered part area at the shear energy of "
            f"{math.degrees(objective.uncovered_shear_rad):.4g}° (search.uncovered_shear_deg, "
            f"{objective.uncovered_energy_density:.4g} J/m²): E(α) is not the part's shear "
            f"energy alone; at the optimum {uncovered * 1e6:.4g} mm² of the part is bare",
            min(1.0, at_optimum.coverage),
        )
    if not search.makeable:
        ctx.partial(_no_makeable_angle(search, at_optimum), min(1.0, at_optimum.coverage))
    layout = knobs["layout"]
    if layout:
        _run_layout(ctx, objective, search, layout, optimum)
    curved = knobs["curved_generators"]
    if curved:
        _run_curved(ctx, objective, search, curved, optimum)
    relax = knobs["relax"]
    if relax:
        _run_relax(ctx, study, optimum, relax if isinstance(relax, Mapping) else {})
    _warn_resolution(ctx, search)
    _warn_accounting(ctx, search)
    from preform.pipeline.planner import plan

    if "drape" not in {step.name for step in plan(ctx.scene, ctx.registry)}:
        # Otherwise the drape step drapes at the optimum and judges that same net itself.
        _judge_optimum_drape(ctx, objective, optimum)
    return {"optimum": optimum}


def _no_makeable_angle(search: AngleSearchResult, at: Any) -> str:
    """Why a search that found no makeable angle is partial, in words."""
    lo, hi = search.settings.get("range_deg", [math.nan, math.nan])
    cap = search.settings.get("max_wrinkle_area_share")
    rule = (
        f"more than {100 * cap:.3g} % of its covered area lies past jamming or stitch failure "
        "(search.max_wrinkle_area_share)"
        if cap is not None
        else "its area past jamming or stitch failure is more than the tolerance above the least"
    )
    return (
        f"no generator angle in [{lo:.4g}°, {hi:.4g}°] drapes within the wrinkling cap: at every "
        f"scanned angle {rule}; the search returns the angle of least wrinkle, "
        f"{search.optimum_angle_deg:.4g}°, where {100 * at.wrinkle_energy_share:.3g} % of the "
        f"energy comes from {100 * at.wrinkle_area_share:.3g} % of the covered area past those "
        "limits (not the angle of least energy)"
    )


def _run_layout(
    ctx: CaseContext,
    objective: DrapeObjective,
    search: AngleSearchResult,
    layout: Mapping[str, Any],
    optimum: dict[str, Any],
) -> None:
    settings = objective.drape_kwargs
    start = settings.get("start_xy_m") or (0.0, 0.0)
    vary = tuple(layout.get("vary", ("orientation", "start_point")))
    found = search_layout(
        objective,
        generator_angle_rad=search.optimum_angle_rad,
        orientation_rad=float(settings.get("orientation_rad") or 0.0),
        start_xy_m=(float(start[0]), float(start[1])),
        vary=vary,
        reference_area_m2=search.reference_area_m2,
        max_drapes=int(layout.get("max_drapes", 60)),
        wrinkle_area_tolerance=float(
            search.settings.get("wrinkle_area_tolerance", WRINKLE_AREA_TOLERANCE)
        ),
    )
    optimum.update(
        generator_angle_rad=found.generator_angle_rad,
        orientation_rad=found.orientation_rad,
        start_xy_m=found.start_xy_m,
        energy_J=found.energy_J,
    )
    ctx.summary.update(
        {
            "layout_varied": list(found.varied),
            "layout_generator_angle_deg": math.degrees(found.generator_angle_rad),
            "layout_orientation_deg": math.degrees(found.orientation_rad),
            "layout_start_mm": [found.start_xy_m[0] / MM, found.start_xy_m[1] / MM],
            "layout_energy_J": found.energy_J,
            "layout_relative_saving": 1.0 - found.energy_J / found.initial_energy_J,
            "layout_drapes": found.drapes,
        }
    )


def _run_curved(
    ctx: CaseContext,
    objective: DrapeObjective,
    search: AngleSearchResult,
    curved: Any,
    optimum: dict[str, Any],
) -> None:
    from preform.optimise.curved import optimise_curved_generators

    options = curved if isinstance(curved, Mapping) else {}
    result = optimise_curved_generators(
        objective,
        generator_angle_rad=float(optimum["generator_angle_rad"]),
        terms=int(options.get("terms", 2)),
        mirror_families=bool(options.get("mirror_families", False)),
        reference_area_m2=search.reference_area_m2,
        max_drapes=int(options.get("max_drapes", 120)),
        wrinkle_area_tolerance=float(
            search.settings.get("wrinkle_area_tolerance", WRINKLE_AREA_TOLERANCE)
        ),
    )
    ctx.summary.update(result.summary())
    claimed = _judge_curved_saving(ctx, objective, result)
    if result.relative_saving > 0 and claimed:
        # The drape step drapes with these when it honours optimum["generators"].
        optimum.update(
            generators=result.generators,
            generator_angle_rad=result.generator_angle_rad,
            energy_J=result.energy_J,
        )


#: Largest share of the part's fabric a curved-generator optimum may shear beyond the law's
#: data (or packing) range for its saving to be claimed [-]: past it the saving rests on the
#: law's continuation, not on measurements (issue 26: E-BX-318's 43.9 % came from cells
#: sheared to 78° where its law holds its 60° value).
CURVED_UNMEASURED_SHARE_MAX = 0.01


def _judge_curved_saving(ctx: CaseContext, objective: DrapeObjective, curved: Any) -> bool:
    """Whether a curved-generator optimum's saving is claimed: its drape shears at most
    ``CURVED_UNMEASURED_SHARE_MAX`` of the part's fabric beyond the law's data (or packing)
    range. The share is recorded next to the saving (``curved_area_share_outside_law_data``,
    ``curved_saving_claimed``); a saving not claimed is said in words and the straight
    generators stay the result."""
    evaluation = objective.evaluate(
        curved.generator_angle_rad, generators=curved.generators, keep_result=True
    )
    result = evaluation.result
    if result is None:
        ctx.summary["curved_saving_claimed"] = False
        return False
    counted = objective.counted(result)
    gamma = np.where(counted, result.shear, 0.0)
    ctx.summary["curved_max_abs_shear_deg"] = float(np.degrees(np.abs(gamma).max()))
    limits = fabric_law_range(objective.law, ctx.fabric)
    beyond = np.zeros_like(counted)
    if limits.data_positive is not None:
        beyond |= counted & (gamma > limits.data_positive)
    if limits.data_negative is not None:
        beyond |= counted & (gamma < -limits.data_negative)
    if limits.packing is not None:
        beyond |= counted & (np.abs(gamma) > limits.packing)
    count = int(np.count_nonzero(beyond))
    # shares of the part's fabric: each counted cell by its share inside the part (d² each)
    weight = np.asarray(result.part_weight, dtype=float)
    share = float(weight[beyond].sum() / max(float(weight[counted].sum()), 1e-300))
    claimed = share <= CURVED_UNMEASURED_SHARE_MAX
    ctx.summary["curved_cells_outside_law_data"] = count
    ctx.summary["curved_area_share_outside_law_data"] = share
    ctx.summary["curved_saving_claimed"] = claimed
    if not count:
        return True
    where = (
        f"shears {count} cells ({100 * share:.2g} % of the part's fabric) beyond the shear "
        f"law's data range, up to {ctx.summary['curved_max_abs_shear_deg']:.1f}°"
    )
    if claimed:
        ctx.warn(
            f"the curved-generator optimum saves {100 * curved.relative_saving:.3g} % of the "
            f"energy and {where}: that much of the saving rests on the law's continuation "
            "there, not on measurements",
            cause="beyond the law's data",
            area_share=share,
        )
    else:
        ctx.warn(
            f"no saving is claimed for curved generators: their optimum {where}, more than "
            f"{100 * CURVED_UNMEASURED_SHARE_MAX:g} % of it, where the energy is the law's "
            f"continuation, not measurements (on it the saving would be "
            f"{100 * curved.relative_saving:.3g} %, curved_relative_saving); the straight "
            "generators stay the result",
            cause="beyond the law's data under curved generators (their saving not claimed)",
            area_share=share,
        )
    return claimed


def _run_relax(
    ctx: CaseContext, study: AngleStudy, optimum: dict[str, Any], options: Mapping[str, Any]
) -> None:
    """Relax the optimum's net (``preform.optimise.relax``) and keep it when it holds less
    energy than the kinematic net, both summed as the drape step sums ``total_energy_J``: each
    counted cell by its own share of the part, under the same law (issue 26: the relaxation's
    objective holds every cell's kinematic share, so it is not the relaxed net's energy)."""
    from preform.optimise.relax import relax_net

    objective = study.objective
    kinematic = _drape_at(objective, optimum)
    assert kinematic.result is not None
    relaxed = relax_net(
        kinematic.result,
        objective.surface,
        objective.law,
        counted=objective.counted(kinematic.result),
        max_rounds=int(options.get("max_rounds", 8)),
        max_iterations=int(options.get("max_iterations", 1500)),
    )
    ctx.summary.update(relaxed.summary())
    assert study.settings.fidelity is not None  # a scene's settings carry its knobs
    law = summed_law(ctx, study.settings.fidelity)
    part = objective.drape_kwargs.get("trim")
    net = relaxed_result(kinematic.result, relaxed.nodes, part)
    with np.errstate(all="ignore"):
        before = energy_field(kinematic.result, law).total_energy
        after = energy_field(net, law).total_energy
    kept = after < before
    ctx.summary.update(
        relaxed_energy_J=after,
        relaxed_kinematic_energy_J=before,
        relaxed_relative_saving=1.0 - after / before if before > 0 else 0.0,
        relaxed_kept=kept,
    )
    if kept:
        # The drape step exports the relaxed net when it drapes the same kinematic net.
        optimum["relaxed_nodes"] = relaxed.nodes
    else:
        ctx.warn(
            f"the relaxed net holds {after:.6g} J, not less than the kinematic drape's "
            f"{before:.6g} J (each cell by its own share of the part): the result is the "
            "kinematic net",
            cause="relaxation saved nothing",
        )


def write_energy_plot_png(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.fig_curves import energy_vs_angle_figure

    study: AngleStudy = ctx.products["energy_vs_angle"]
    name = ctx.fabric.name
    energy_vs_angle_figure(
        {name: study.search.curve_deg()},
        ctx.case_dir / "energy_vs_angle.png",
        optima={name: math.degrees(float(ctx.products["optimum"]["generator_angle_rad"]))},
        title=f"{name}: total shear strain energy against generator angle",
    )
    return {"energy_plot_png": "energy_vs_angle.png"}


def write_energy_vs_angle_csv(ctx: CaseContext) -> dict[str, Any]:
    """energy_vs_angle.csv: the energy/wrinkle trade table (:func:`trade_table`)."""
    from preform.export.csv_columns import write_csv_columns

    study: AngleStudy = ctx.products["energy_vs_angle"]
    rows = trade_table(study.search)
    write_csv_columns(
        {name: [row[name] for row in rows] for name in TRADE_COLUMNS},
        ctx.case_dir / "energy_vs_angle.csv",
    )
    return {"energy_vs_angle_csv": "energy_vs_angle.csv"}


def run_library_energy_png(ctx: CaseContext) -> dict[str, Any]:
    """Nothing per case: the figure is drawn once per scene, by ``energy_vs_angle_library``,
    from the curves the case summaries hold (``energy_vs_angle``, which this step requires)."""
    return {"library_energy_png": []}


def energy_vs_angle_library(folder: Path, summaries: list[Mapping[str, Any]]) -> list[str]:
    """The scene-wide figure (paper Fig. 10): one E(α) curve per fabric, optima marked.

    Written to ``folder``/energy_vs_angle.png from the case summaries (``material``,
    ``energy_vs_angle``, ``optimum_generator_angle_deg``); returns the file names written.
    """
    from preform.export.fig_curves import energy_vs_angle_figure

    curves: dict[str, list[tuple[float, float]]] = {}
    optima: dict[str, float] = {}
    for summary in summaries:
        pairs = summary.get("energy_vs_angle")
        if not pairs:
            continue
        name = str(summary.get("material", f"case {len(curves) + 1}"))
        curves[name] = [(float(a), float(e)) for a, e in pairs]
        best = summary.get("optimum_generator_angle_deg")
        if best is not None:
            optima[name] = float(best)
    if not curves:
        return []
    folder.mkdir(parents=True, exist_ok=True)
    energy_vs_angle_figure(
        curves,
        folder / "energy_vs_angle.png",
        optima=optima,
        title="Total shear strain energy against generator angle",
        size_px=(1200, 650),
    )
    return ["energy_vs_angle.png"]


def scene_problems(scene: Scene, doc: Document, registry: Any) -> list[SourceError]:
    """Problems of the search section that would only surface at run time (or take the
    machine first), checked by arithmetic (the optimum step's ``check``)."""
    search = scene.search
    if search is None:
        return []
    errors: list[SourceError] = []
    if scene.start is not None and scene.start.generators == "polyline":
        errors.append(
            doc.error(
                ("start", "generators"),
                "the generator-angle search needs geodesic or plan generators: polylines "
                "fix the angle themselves; remove the search section or the polylines",
            )
        )
    span = search.generator_angle_deg
    lo, hi = (span.min, span.max) if span is not None else (30.0, 150.0)
    at: tuple[str | int, ...] = (
        ("search", "generator_angle_deg") if span is not None else ("search",)
    )
    if not 0.0 < lo < hi < 180.0:
        return [
            *errors,
            doc.error(
                at,
                f"the generator-angle range must satisfy 0 < min < max < 180°, got [{lo:g}°, {hi:g}°]",
            ),
        ]
    knobs = fidelity.resolve(scene)
    needed = scan_size(np.radians(lo), np.radians(hi), np.radians(knobs.scan_step_deg))
    if search.scan_step_deg is not None:
        at = ("search", "scan_step_deg")
    elif span is not None and span.step is not None:
        at = ("search", "generator_angle_deg", "step")
    if needed > knobs.max_drapes:
        count = "too many" if needed >= 2**63 else f"{needed:,}"
        errors.append(
            doc.error(
                at,
                f"a scan of [{lo:g}°, {hi:g}°] every {knobs.scan_step_deg:g}° needs "
                f"{count} drapes, more than the budget max_drapes = "
                f"{knobs.max_drapes}; widen the step (search.scan_step_deg) or raise "
                "search.max_drapes",
            )
        )
    return errors


STEPS = [
    Step(
        "energy_vs_angle",
        ("energy_vs_angle",),
        ("surface", "shear_law"),
        "1",
        run_energy_vs_angle,
        "Total shear strain energy of the drape against generator angle, with part coverage.",
        scene_sections=("tool", "ply", "start", "search"),
    ),
    Step(
        "optimum",
        ("optimum",),
        ("energy_vs_angle",),
        "1",
        run_optimum,
        "The minimum-energy generator angle (and layout, curved generators, relaxation when "
        "the search section asks).",
        scene_sections=("search",),
        sections={"search": None},
        check=scene_problems,
    ),
]

EXPORTERS = [
    Step.exporter(
        "energy_plot_png",
        ("energy_vs_angle", "optimum"),
        write_energy_plot_png,
        "energy_vs_angle.png per case (one fabric's E(α), its optimum marked)",
    ),
    Step.exporter(
        "energy_vs_angle_csv",
        ("energy_vs_angle",),
        write_energy_vs_angle_csv,
        "energy_vs_angle.csv per case: the energy/wrinkle trade table (energy, coverage, wrinkle "
        "area and energy shares, makeable) at every searched angle",
    ),
    Step.exporter(
        "library_energy_png",
        ("energy_vs_angle", "optimum"),
        run_library_energy_png,
        "energy_vs_angle.png in the scene folder: every fabric's E(α) on one figure (paper "
        "Fig. 10), drawn once after the cases",
        aggregate=energy_vs_angle_library,
    ),
]
