"""The angle search never reports an angle dearer than one it sampled, judges every angle on
the same fabric, says where E(α) jumps, and gives a symmetric problem its symmetric answer.

Independent truths: the hat mould's mirror symmetry (a symmetric law started on the block's
centre line: E(α) = E(180° − α), so the least energy is at 90°), the samples the search itself
reports (its optimum may not cost more than any of them), and synthetic objectives whose
energies, folds and jumps are written here in closed form."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from preform.drape.engine.ply import PlyOutline
from preform.optimise.search import (
    AngleSearchResult,
    DrapeEvaluation,
    DrapeObjective,
    SearchPoint,
    continuous_span,
    find_discontinuities,
    search_generator_angle,
)
from preform.plugins.surfaces.basic import Cylinder, Hemisphere
from preform.plugins.surfaces.mesh import read_obj

HAT = Path(__file__).resolve().parents[2] / "materials" / "tools" / "hat_mould.obj"
PLY = PlyOutline.rectangle((0.36, 0.36))


def _lowest_feasible(result: AngleSearchResult) -> float:
    return min(p.energy_J for p in result.points if p.feasible and math.isfinite(p.energy_J))


class PlainWeaveLike:
    """A symmetric stiffening law, W = a·γ² + b·γ⁴ [J/m²] (illustrative constants)."""

    locking_angle: float | None = math.radians(50.0)
    failure_angle: float | None = None

    def torque(self, gamma: object) -> np.ndarray:
        g = np.asarray(gamma, dtype=float)
        return 2.0 * 0.5 * g + 4.0 * 20.0 * g**3

    def energy(self, gamma: object) -> np.ndarray:
        g = np.asarray(gamma, dtype=float)
        return 0.5 * g**2 + 20.0 * g**4


# -- the hat mould ---------------------------------------------------------------------------


def _hat_search(
    feature_angle_deg: float, spacing: float, start: tuple[float, float], law: object = None
):
    hat = read_obj(HAT, feature_angle_deg=feature_angle_deg)
    law = PlainWeaveLike() if law is None else law
    objective = DrapeObjective(hat, law, node_spacing_m=spacing, ply=PLY)  # type: ignore[arg-type]
    objective.drape_kwargs["start_xy_m"] = start
    return search_generator_angle(objective)


@pytest.mark.parametrize("feature_angle_deg", [30.0, 180.0])
def test_the_hat_mould_started_on_its_centre_has_its_least_energy_at_90(feature_angle_deg):
    """Started at the block's centre the set-up is mirror-symmetric (x → −x maps α to 180° − α)
    and the net folds at the four block corners near 90°; before, those fold zones dropped out
    of the sum at some angles and not at others and the search returned 88.74°."""
    result = _hat_search(feature_angle_deg, 0.01, (0.0, 0.0))
    assert result.optimum_angle_deg == pytest.approx(90.0, abs=0.2)
    assert result.optimum_energy_J <= _lowest_feasible(result)
    # its fold zones are reported: one behind each block corner, mirror pairs of equal area
    zones = result.optimum_fold_zones
    assert len(zones) == 4
    centres = np.array([c for c, _ in zones])
    assert np.all(np.abs(centres[:, 0]) > 0.05) and np.all(np.abs(centres[:, 1]) > 0.03)
    assert result.excluded_fabric_area_m2 >= sum(a for _, a in zones)
    # the compared curve is the mirror image of itself
    by_angle = {round(p.generator_angle_deg, 6): p for p in result.points}
    pairs = [a for a in by_angle if a < 90 and round(180.0 - a, 6) in by_angle]
    assert len(pairs) >= 12
    for a in pairs:
        mirror = by_angle[round(180.0 - a, 6)]
        assert by_angle[a].energy_J == pytest.approx(mirror.energy_J, rel=1e-6, abs=1e-12)
        assert by_angle[a].fold_zones == mirror.fold_zones
    # the jumps where the number of fold zones changes are said, each between two samples
    # whose fold counts differ
    folds = {p.generator_angle_rad: p.fold_zones for p in result.points}
    counted = [j for j in result.discontinuities if j.causes[0].startswith("fold zones")]
    assert counted
    assert all(folds[j.lo_rad] != folds[j.hi_rad] for j in counted)


@pytest.mark.parametrize("feature_angle_deg", [30.0, 180.0])
def test_the_benchmarks_hat_mould_study_returns_90(feature_angle_deg):
    """``benchmarks/bench_mesh.py``'s study: plain-weave-600, d = 2.5 mm, start (4, 3) mm
    (was 88.74° at 13.87 J with creases on, against 0.27 J at 90°). The start is off the
    block's centre lines, so the set-up is only nearly symmetric: with another law the
    same-fabric comparison may pick another angle (measured with the soft law above: 81.7°
    creases on, 87.5° off), so this pins the benchmark's own case."""
    from preform.library import load_library

    law = load_library().shear_law("plain-weave-600")
    result = _hat_search(feature_angle_deg, 0.0025, (0.004, 0.003), law)
    assert result.optimum_angle_deg == pytest.approx(90.0, abs=0.2)
    assert result.optimum_energy_J <= _lowest_feasible(result)
    assert len(result.optimum_fold_zones) == 4


# -- the same fabric at every angle ----------------------------------------------------------


def test_a_tool_that_loses_no_fabric_is_judged_on_its_whole_drape():
    hemi = Hemisphere(0.1, run_off_m=0.025)
    objective = DrapeObjective(
        hemi,
        PlainWeaveLike(),
        node_spacing_m=0.01,
        ply=PLY,
        start_xy_m=(0.0, 0.0),
        trim=hemi.part(),
    )
    result = search_generator_angle(objective)
    assert result.excluded_fabric_area_m2 == 0.0
    assert not result.discontinuities and result.optimum_from == "fit"
    assert result.optimum_angle_deg == pytest.approx(90.0, abs=1e-9)
    for p in result.points:
        assert p.excluded_energy_J == 0.0
        assert p.energy_J == p.drape_energy_J + p.uncovered_charge_J


def test_a_fit_dearer_than_a_sample_gives_way_to_the_sample():
    """The hemisphere's run-off plate, no part, coarse net: E(α) has two shallow minima and a
    staircase. The last fit's vertex (84.64°, measured 0.18600 J) is dearer than the sample at
    85.89° (0.18411 J; the same at its mirror 94.11°); the search used to return it anyway."""
    hemi = Hemisphere(0.1, run_off_m=0.025)
    objective = DrapeObjective(
        hemi, PlainWeaveLike(), node_spacing_m=0.01, ply=PLY, start_xy_m=(0.0, 0.0)
    )
    result = search_generator_angle(objective)
    assert result.optimum_energy_J <= _lowest_feasible(result)
    assert result.optimum_from == "best sample"
    assert "more than the best sample" in result.optimum_note
    # the set-up is mirror-symmetric: either mirror image of that sample (rounding decides)
    assert min(abs(result.optimum_angle_deg - a) for a in (85.89, 94.11)) < 0.01


# -- a synthetic objective with folds and jumps ----------------------------------------------


class SyntheticObjective:
    """Stands in for :class:`DrapeObjective`: a 'ply' of a few cells whose energies [J] and
    losses at each α [rad] are given by ``cells(α) -> (energies, lost, fold_zones)``; the
    covered area is 1 m² per cell counted. No drape is run."""

    uncovered_energy_density = 0.0
    uncovered_shear_rad = None

    def __init__(self, cells, covered=None) -> None:
        self.cells = cells
        #: covered(α) -> (covered area [m²], cells counted) when not one per cell counted
        self.covered = covered
        self.part_area_m2 = None
        self.drape_kwargs = {"node_spacing_m": 1.0}
        self.drapes = 0

    def evaluate(self, alpha: float) -> DrapeEvaluation:
        self.drapes += 1
        energies, lost, folds = self.cells(alpha)
        energies = np.asarray(energies, dtype=float)[None, :]
        lost = np.asarray(lost, dtype=bool)[None, :]
        counted = ~lost
        cell_energy = np.where(counted, energies, 0.0)
        area, count = (
            (float(counted.sum()), int(counted.sum()))
            if self.covered is None
            else self.covered(alpha)
        )
        return DrapeEvaluation(
            generator_angle_rad=alpha,
            orientation_rad=0.0,
            start_xy_m=(0.0, 0.0),
            drape_energy_J=float(cell_energy.sum()),
            covered_area_m2=area,
            cells_counted=count,
            max_abs_shear_rad=0.0,
            fold_zones=tuple(((0.0, 0.0), 1.0) for _ in range(folds)),
            lost_area_m2=float(lost.sum()),
            cell_energy_J=cell_energy,
            lost_cells=lost,
        )

    def charged(self, evaluation: DrapeEvaluation, reference_area_m2: float) -> float:
        return DrapeObjective.charged(self, evaluation, reference_area_m2)  # type: ignore[arg-type]


def _search(objective: SyntheticObjective, **kwargs) -> AngleSearchResult:
    return search_generator_angle(objective, **kwargs)  # type: ignore[arg-type]


def test_a_fold_that_drops_a_dear_cell_does_not_make_its_angle_cheap():
    """Cell B costs 10 J wherever it drapes and folds away for α ≥ 96°; cell A costs
    (α − 97°)² (α in degrees). On the same fabric E(α) is A's alone, least at 97°; the fold
    is said as a jump between two samples around 96°, and the optimum lies on its right side.
    The old search judged α ≥ 96° cheap because B dropped out, and α < 96° dear."""

    def cells(alpha):
        deg = math.degrees(alpha)
        folded = deg >= 96.0
        return [(deg - 97.0) ** 2, 10.0], [False, folded], int(folded)

    result = _search(SyntheticObjective(cells), tolerance_rad=math.radians(0.1))
    assert result.optimum_angle_deg == pytest.approx(97.0, abs=0.05)
    assert result.optimum_energy_J <= _lowest_feasible(result)
    (jump,) = result.discontinuities
    assert math.degrees(jump.lo_rad) < 96.0 <= math.degrees(jump.hi_rad)
    assert "fold zones 0 → 1" in jump.causes[0]
    assert result.optimum_angle_rad > jump.hi_rad - 1e-12
    # B's 10 J is out of every angle's compared energy, and said
    for p in result.points:
        assert p.energy_J == pytest.approx((p.generator_angle_deg - 97.0) ** 2, abs=1e-9)
        assert p.excluded_energy_J == (0.0 if p.generator_angle_deg >= 96.0 else 10.0)
    assert result.excluded_fabric_area_m2 == 1.0


def test_a_jump_in_the_counted_area_is_not_straddled_by_a_fit():
    """E = (α − 93°)² over one cell, plus a cell that is counted (and costs 40 J) only from
    94° on: the coverage jumps there. The least energy is at 93°, left of the jump; a
    parabola through samples on both sides would put its vertex elsewhere."""

    def cells(alpha):
        deg = math.degrees(alpha)
        # below 94° the second cell lies outside the part: not counted, and not lost either
        return [(deg - 93.0) ** 2, 40.0 if deg >= 94.0 else 0.0], [False, False], 0

    def covered(alpha):
        return (2.0, 2) if math.degrees(alpha) >= 94.0 else (1.0, 1)

    objective = SyntheticObjective(cells, covered)
    result = _search(objective, tolerance_rad=math.radians(0.1))
    assert result.optimum_angle_deg == pytest.approx(93.0, abs=0.05)
    assert result.optimum_energy_J <= _lowest_feasible(result)
    assert any(
        math.degrees(j.lo_rad) < 94.0 <= math.degrees(j.hi_rad) and "covered part area" in c
        for j in result.discontinuities
        for c in j.causes
    )


def test_a_sample_between_two_jumps_is_the_optimum_and_says_so():
    """A V-shaped minimum exactly at a sample, with the fold count changing on both sides:
    no fit can be made; the optimum is the sample, in words."""

    def cells(alpha):
        deg = math.degrees(alpha)
        return [abs(deg - 90.0) + 1.0], [False], 4 if deg == 90.0 else 2

    result = _search(SyntheticObjective(cells))
    assert result.optimum_angle_deg == 90.0
    assert result.optimum_from == "best sample"
    assert "jumps on both sides" in result.optimum_note


def test_the_span_between_jumps():
    def point(deg: float, folds: int) -> SearchPoint:
        return SearchPoint(
            math.radians(deg),
            1.0,
            1.0,
            0.0,
            1.0,
            1.0,
            True,
            "scan",
            0.0,
            excluded_energy_J=0.0,
            cells_counted=1,
            fold_zones=folds,
            fold_zone_area_m2=float(folds),
            lost_area_m2=float(folds),
        )

    pts = [point(80, 0), point(85, 0), point(90, 1), point(95, 1), point(100, 2)]
    jumps = find_discontinuities(pts, 1.0)
    assert [(round(math.degrees(j.lo_rad)), round(math.degrees(j.hi_rad))) for j in jumps] == [
        (85, 90),
        (95, 100),
    ]
    lo, hi = math.radians(30), math.radians(150)
    span = continuous_span(math.radians(92), jumps, lo, hi)
    assert span == pytest.approx((math.radians(90), math.radians(95)))
    assert continuous_span(math.radians(80), jumps, lo, hi) == pytest.approx((lo, math.radians(85)))
    # inside an unresolved jump: nothing to fit with
    assert continuous_span(math.radians(87), jumps, lo, hi) == (math.radians(87),) * 2


# -- never dearer than a sample: properties --------------------------------------------------


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    coefficients=st.lists(st.floats(-3.0, 3.0), min_size=5, max_size=5),
    fold_at=st.one_of(st.none(), st.floats(35.0, 145.0)),
    fold_cost=st.floats(0.0, 50.0),
    bump_at=st.one_of(st.none(), st.floats(35.0, 145.0)),
    bump=st.floats(-5.0, 5.0),
)
def test_synthetic_optimum_is_never_dearer_than_a_sample(
    coefficients, fold_at, fold_cost, bump_at, bump
):
    """Random quartic energies in α, a cell that folds away past a random angle, and a random
    step of the energy: the optimum is never dearer than the cheapest feasible sample."""
    c = np.array(coefficients)

    def cells(alpha):
        t = (math.degrees(alpha) - 90.0) / 60.0
        smooth = 10.0 + float(np.polyval(c, t)) + 3.0 * t * t
        step = bump if bump_at is not None and math.degrees(alpha) >= bump_at else 0.0
        folded = fold_at is not None and math.degrees(alpha) >= fold_at
        return [smooth + step + 20.0, fold_cost], [False, folded], int(folded)

    result = _search(SyntheticObjective(cells), tolerance_rad=math.radians(0.25))
    assert result.optimum_energy_J <= _lowest_feasible(result)
    assert any(p.generator_angle_rad == result.optimum_angle_rad for p in result.points)


class PolynomialLaw:
    """W(γ) = Σ_k c_k·γ^k, k = 2..4, with separate coefficients for γ < 0 (asymmetric when
    they differ) [J/m²]; kept non-negative by squaring the polynomial's value."""

    locking_angle: float | None = None
    failure_angle: float | None = None

    def __init__(self, positive: list[float], negative: list[float]) -> None:
        self.positive, self.negative = np.array(positive), np.array(negative)

    def _poly(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        coef = np.where(g[..., None] >= 0, self.positive, self.negative)
        a = np.abs(g)
        value = coef[..., 0] * a + coef[..., 1] * a**2 + coef[..., 2] * a**3
        slope = coef[..., 0] + 2 * coef[..., 1] * a + 3 * coef[..., 2] * a**2
        return value, slope * np.sign(g)

    def energy(self, gamma: object) -> np.ndarray:
        value, _ = self._poly(np.asarray(gamma, dtype=float))
        return value**2

    def torque(self, gamma: object) -> np.ndarray:
        value, slope = self._poly(np.asarray(gamma, dtype=float))
        return 2.0 * value * slope


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    positive=st.lists(st.floats(0.1, 5.0), min_size=3, max_size=3),
    negative=st.one_of(st.none(), st.lists(st.floats(0.1, 5.0), min_size=3, max_size=3)),
    tool=st.sampled_from(["hemisphere", "hemisphere part", "cylinder"]),
    start=st.tuples(st.floats(-0.03, 0.03), st.floats(-0.03, 0.03)),
    radius=st.floats(0.06, 0.12),
)
def test_optimum_on_analytic_tools_is_never_dearer_than_a_sample(
    positive, negative, tool, start, radius
):
    law = PolynomialLaw(positive, positive if negative is None else negative)
    kwargs: dict[str, object] = {}
    if tool == "cylinder":
        surface = Cylinder(radius, 0.4)
    else:
        surface = Hemisphere(radius, run_off_m=radius / 4)
        if tool == "hemisphere part":
            kwargs["trim"] = surface.part()
    objective = DrapeObjective(
        surface,
        law,
        node_spacing_m=radius / 6,
        ply=PlyOutline.rectangle((3 * radius, 3 * radius)),
        start_xy_m=start,
        **kwargs,
    )
    result = search_generator_angle(objective, scan_step_rad=math.radians(10.0))
    assert result.optimum_energy_J <= _lowest_feasible(result)
