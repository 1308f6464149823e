"""Shear laws in their corners: angles at 0 (±1e-12, subnormals), at and past ±90°, at the
locking angle, tows as wide as their spacing, the Gutowski pole, zero friction and pre-tension,
parameters from 1e-9 to 1e9, angles past the fitted range.

Why: the drape evaluates every law on every cell, including cells sheared towards 90° and
cells with γ = 0 exactly; one NaN, inf or decreasing energy there corrupts the total energy
and so the generator-angle optimum, without any error being raised.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from preform.plugins.warpknit.shear import StitchPolynomialParams, build_stitch_polynomial
from preform.plugins.woven.compaction import BundleCompaction
from preform.plugins.woven.shear import (
    FrictionCompactionLaw,
    FrictionCompactionParams,
    plain_weave_geometry,
)
from preform.plugins.woven.tow_jamming import TowCompaction
from preform.shear.law import ShearLaw
from preform.shear.laws import (
    PolynomialParams,
    TabulatedParams,
    build_polynomial,
    build_tabulated,
)

HALF_PI = math.pi / 2
#: Every corner of the angle axis: zero, ±1e-12, subnormals, just below/at/past ±90°, far past.
CORNER_ANGLES = np.array(
    [
        0.0,
        -0.0,
        5e-324,
        -5e-324,
        1e-300,
        1e-12,
        -1e-12,
        HALF_PI - 1e-12,
        HALF_PI,
        -HALF_PI,
        HALF_PI + 1e-9,
        -HALF_PI - 1e-9,
        3.0,
        -3.0,
        1e300,
        -1e300,
    ]
)
#: A dense sweep of magnitudes [rad] for monotonicity checks, up to and past 90°.
SWEEP = np.concatenate([np.linspace(0.0, HALF_PI, 1441), [HALF_PI + 1e-9, 2.0, 10.0]])

MAGNITUDES = st.sampled_from([0.0, 1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e9])


def assert_sound(law: ShearLaw) -> None:
    """Finite torque and energy everywhere, W(0) = 0, W ≥ 0, W non-decreasing in |γ| on both
    sides, torque sign follows γ (a non-negative law never drives its own shear)."""
    torque = np.asarray(law.torque(CORNER_ANGLES))
    energy = np.asarray(law.energy(CORNER_ANGLES))
    assert np.all(np.isfinite(torque)), torque
    assert np.all(np.isfinite(energy)), energy
    assert float(law.energy(0.0)) == 0.0
    assert float(law.energy(np.array([0.0]))[0]) == 0.0
    assert np.all(energy >= 0.0)
    assert np.all(torque * np.sign(CORNER_ANGLES) >= 0.0)
    for sense in (1.0, -1.0):
        w = np.asarray(law.energy(sense * SWEEP))
        assert np.all(np.isfinite(w)) and np.all(w >= 0.0)
        # Rounding may wobble the last bits; a real decrease would be far larger.
        assert np.all(np.diff(w) >= -1e-9 * max(1.0, float(w.max()))), sense


def fc_law(
    width_mm: float = 3.1,
    spacing_mm: float = 4.0,
    tex: float = 1190.0,
    tows: TowCompaction | None = None,
    tow_height_mm: float = 0.5,
    **params: float | None,
) -> FrictionCompactionLaw:
    """A plain weave's law; ``tows`` the tows' compaction constants (issue 24: per tow)."""
    base: dict[str, float | None] = {"pretension_N": 100.0, "fabric_thickness_mm": 2.0}
    base.update(params)
    geometry = plain_weave_geometry(width_mm, spacing_mm, tex, tow_height_mm=tow_height_mm)
    if tows is not None:
        geometry = replace(geometry, compaction_warp=tows, compaction_weft=tows)
    return FrictionCompactionLaw(
        geometry,
        FrictionCompactionParams.model_validate({"law": "friction_compaction", **base}),
    )


# -- friction_compaction ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("width_mm", "spacing_mm"),
    [(3.1, 4.0), (4.0, 4.0), (4.0 * (1 - 1e-15), 4.0), (5.0, 4.0), (40.0, 4.0)],
    ids=["gap", "width=spacing", "width just below spacing", "width>spacing", "width=10x"],
)
def test_friction_compaction_tow_width_at_and_beyond_spacing(
    width_mm: float, spacing_mm: float
) -> None:
    """Tows at or past their spacing lock at γ_L = 0 (not a NaN from acos(>1))."""
    law = fc_law(width_mm, spacing_mm)
    assert law.locking_angle == pytest.approx(math.acos(min(1.0, width_mm / spacing_mm)), abs=1e-7)
    assert_sound(law)


def test_friction_compaction_is_continuous_at_the_locking_angle() -> None:
    """Tow width Tw0 → Ts·cos γ is continuous at γ_L, so torque and energy are continuous
    there from both sides; W is C¹ (its slope is the torque)."""
    law = fc_law()
    lock = law.locking_angle
    assert lock is not None and 0 < lock < HALF_PI
    for sign in (1.0, -1.0):
        eps = 1e-9
        below, at, above = law.torque(sign * np.array([lock - eps, lock, lock + eps]))
        assert abs(above - below) <= 1e-6 * abs(at)
        w_below, w_at, w_above = law.energy(sign * np.array([lock - eps, lock, lock + eps]))
        assert w_below <= w_at <= w_above
        assert abs(w_above - w_below) <= 4 * eps * abs(at) + 1e-12 * w_at


def test_friction_compaction_zero_friction_and_zero_pretension() -> None:
    """μ = 0 gives exactly zero; pre-tension 0 leaves compaction only: zero before locking."""
    assert_sound(fc_law(friction_coefficient=0.0))
    assert np.all(fc_law(friction_coefficient=0.0).torque(SWEEP) == 0.0)
    law = fc_law(pretension_N=0.0)
    assert_sound(law)
    assert law.locking_angle is not None
    before = SWEEP[SWEEP < law.locking_angle]
    assert np.all(law.torque(before) == 0.0)
    assert law.torque(HALF_PI - 1e-3) > 0.0


def test_friction_compaction_at_the_gutowski_pole() -> None:
    """V_f0 just under the cap, a margin at float resolution, and a margin the cap cannot
    resolve (must be a ValueError, not an inf torque past the cap)."""
    cap = math.pi / 4 * (1 - 1e-2)
    fibre_area = 1190 / 2.55e3  # mm²

    def height_for(fraction: float) -> float:
        return fibre_area / (math.pi / 4 * 3.1 * fraction)

    assert_sound(fc_law(tow_height_mm=height_for(cap * (1 - 1e-12))))
    assert_sound(fc_law(tows=TowCompaction(packing_margin=1e-15)))
    with pytest.raises(ValueError, match="packing_margin"):
        fc_law(tows=TowCompaction(packing_margin=1e-300))
    with pytest.raises(ValueError, match="packing cap"):
        fc_law(tow_height_mm=height_for(cap * (1 + 1e-9)))
    with pytest.raises(ValueError, match="V_o < V_a"):
        BundleCompaction(72e9, 30.0, 0.3, onset_fraction=0.9, max_fraction=0.785)


@settings(max_examples=60, deadline=None)
@given(
    width=st.sampled_from([1e-9, 1e-3, 3.1, 4.0, 1e3, 1e9]),
    spacing=st.sampled_from([1e-9, 4.0, 1e9]),
    tex=st.sampled_from([1e-9, 1190.0, 1e9]),
    thickness=st.sampled_from([1e-9, 2.0, 1e9]),
    pretension=st.sampled_from([0.0, 1e-9, 100.0, 1e9]),
    mu=st.sampled_from([0.0, 1e-9, 0.3, 1e9]),
    beta=st.sampled_from([1e-9, 30.0, 1e9]),
    coupling=st.sampled_from([0.0, 1e-9, 1.0, 1e9]),
)
def test_friction_compaction_huge_and_tiny_parameters(
    width: float,
    spacing: float,
    tex: float,
    thickness: float,
    pretension: float,
    mu: float,
    beta: float,
    coupling: float,
) -> None:
    """Any combination either builds a sound law or is refused with a ValueError."""
    try:
        law = fc_law(
            width,
            spacing,
            tex,
            fabric_thickness_mm=thickness,
            pretension_N=pretension,
            friction_coefficient=mu,
            tows=TowCompaction(fibre_wave_ratio=beta, coupling_compliance=coupling * 1e-9),
        )
    except ValueError as exc:
        assert str(exc)
        return
    assert_sound(law)


@pytest.mark.parametrize(
    "bad",
    [
        {"pretension_N": -1.0},
        {"fabric_thickness_mm": 0.0},
        {"friction_coefficient": -0.1},
        {"max_volume_fraction": 1.0},
        {"packing_margin": 0.0},
        {"tow_volume_fraction": 0.0},
        {"fabric_thickness_mm": float("nan")},
        {"pretension_N": float("inf")},
    ],
)
def test_friction_compaction_invalid_parameters_are_validation_errors(
    bad: dict[str, float],
) -> None:
    data = {"law": "friction_compaction", "pretension_N": 100.0, "fabric_thickness_mm": 2.0}
    with pytest.raises(ValidationError):
        FrictionCompactionParams.model_validate({**data, **bad})


# -- stitch_polynomial -----------------------------------------------------------------------


@settings(max_examples=80, deadline=None)
@example(  # W fell by 128 J/m² at the end of a 5° drop (closed form of a cancelling piece)
    parallel=[0.001, 1e9],
    perpendicular=[0.0],
    post=[0.0, 0.001, 0.001],
    failure=1e-09,
    width=5.0,
    max_angle=60.0,
    beyond="hold",
)
@given(
    parallel=st.lists(MAGNITUDES, min_size=1, max_size=6),
    perpendicular=st.lists(MAGNITUDES, min_size=1, max_size=6),
    post=st.none() | st.lists(MAGNITUDES, min_size=1, max_size=5),
    failure=st.sampled_from([1e-9, 0.5, 35.0]),
    width=st.sampled_from([1e-9, 1e-3, 5.0]),
    max_angle=st.sampled_from([1e-9, 1.0, 60.0, 90.0]),
    beyond=st.sampled_from(["hold", "linear", "extrapolate"]),
)
def test_stitch_polynomial_random_non_negative_coefficients(
    parallel: list[float],
    perpendicular: list[float],
    post: list[float] | None,
    failure: float,
    width: float,
    max_angle: float,
    beyond: str,
) -> None:
    """Non-negative coefficients from 1e-9 to 1e9, sharp (1e-9°) failure drops, fitted ranges
    down to 1e-9°: a sound law or a ValidationError."""
    data = {
        "law": "stitch_polynomial",
        "parallel_force_coefficients_N_per_mm": parallel,
        "perpendicular_force_coefficients_N_per_mm": perpendicular,
        "max_angle_deg": max_angle,
        "beyond_range": beyond,
    }
    if post is not None:
        data |= {
            "failure_angle_deg": failure,
            "failure_width_deg": width,
            "post_failure_force_coefficients_N_per_mm": post,
        }
    try:
        params = StitchPolynomialParams.model_validate(data)
    except ValidationError:
        return
    assert_sound(build_stitch_polynomial(params))


def test_stitch_polynomial_sharp_failure_keeps_energy_continuous() -> None:
    """A failure drop 1e-9° wide with a steep post-failure branch: the closed-form energy of
    such a piece cancels catastrophically; W must stay continuous and increasing across it."""
    params = StitchPolynomialParams(
        law="stitch_polynomial",
        parallel_force_coefficients_N_per_mm=[1.0, 1e-9],
        perpendicular_force_coefficients_N_per_mm=[1e-3],
        max_angle_deg=60.0,
        failure_angle_deg=35.0,
        failure_width_deg=1e-9,
        post_failure_force_coefficients_N_per_mm=[1e9, 1e9],
        beyond_range="extrapolate",
    )
    law = build_stitch_polynomial(params)
    assert_sound(law)
    fail = math.radians(35.0)
    w = law.energy(np.array([fail - 1e-9, fail, fail + 1e-9]))
    # Before failure F ≈ 1 N/mm, C ≈ 1000·cos γ N/m: W(35°) = 1000·sin 35° J/m².
    assert w[1] == pytest.approx(1000.0 * math.sin(fail), rel=1e-6)
    assert w[0] <= w[1] <= w[2] < w[1] + 1e-9 * 1e15


def test_stitch_polynomial_nan_angle_is_not_hidden() -> None:
    """A NaN shear angle gives a NaN torque (as the symmetric laws do), never a clean 0."""
    law = build_stitch_polynomial(
        StitchPolynomialParams(
            law="stitch_polynomial",
            parallel_force_coefficients_N_per_mm=[0.0, 1e-3],
            perpendicular_force_coefficients_N_per_mm=[0.0, 1e-4],
            max_angle_deg=60.0,
        )
    )
    assert np.isnan(law.torque(np.array([np.nan]))[0])
    assert np.isnan(law.energy(np.array([np.nan]))[0])
    assert float(law.torque(0.0)) == 0.0


@pytest.mark.parametrize(
    "bad",
    [
        {"parallel_force_coefficients_N_per_mm": []},
        {"parallel_force_coefficients_N_per_mm": [float("nan")]},
        {"max_angle_deg": 0.0},
        {"max_angle_deg": 90.0 + 1e-9},
        {"failure_angle_deg": 30.0},  # without post-failure coefficients
        {
            "failure_angle_deg": 58.0,
            "failure_width_deg": 5.0,
            "post_failure_force_coefficients_N_per_mm": [0.1],
        },  # drop ends past the fitted range
        {"failure_width_deg": 0.0},
    ],
)
def test_stitch_polynomial_invalid_parameters(bad: dict[str, object]) -> None:
    data = {
        "law": "stitch_polynomial",
        "parallel_force_coefficients_N_per_mm": [0.0, 1e-3],
        "perpendicular_force_coefficients_N_per_mm": [0.0, 1e-4],
        "max_angle_deg": 60.0,
    }
    with pytest.raises(ValidationError):
        StitchPolynomialParams.model_validate({**data, **bad})


# -- polynomial and tabulated ----------------------------------------------------------------


@settings(max_examples=80, deadline=None)
@example(  # W fell by 2 J/m² near γ = 0 (closed-form primitive of ~1e16 J/m² terms cancelling)
    coefficients=[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -0.001],
    quantity="force_coefficients_N_per_mm",
    max_angle=60.0,
    beyond="hold",
)
@given(
    coefficients=st.lists(
        st.tuples(MAGNITUDES, st.sampled_from([1.0, -1.0])).map(lambda t: t[0] * t[1]),
        min_size=1,
        max_size=8,
    ),
    quantity=st.sampled_from(["force_coefficients_N_per_mm", "torque_coefficients_N_per_m"]),
    max_angle=st.sampled_from([1e-9, 1.0, 60.0, 90.0]),
    beyond=st.sampled_from(["hold", "linear", "extrapolate"]),
)
def test_polynomial_any_sign_coefficients(
    coefficients: list[float], quantity: str, max_angle: float, beyond: str
) -> None:
    """Coefficients of either sign (roots next to huge ones, negative stretches to clip): a
    polynomial negative inside its fitted range is refused by the model, located at its
    coefficients; the law object, given it anyway, clips the torque at zero and the energy of
    the clipped curve is still non-decreasing."""
    data = {"law": "polynomial", quantity: coefficients, "max_angle_deg": max_angle}
    data["beyond_range"] = beyond
    try:
        params = PolynomialParams.model_validate(data)
    except ValidationError as exc:
        assert [(e["type"], e["loc"]) for e in exc.errors()] == [
            ("negative_shear_law", (quantity,))
        ]
        assert "comes out negative" in exc.errors()[0]["msg"]
        params = PolynomialParams.model_construct(**data)  # type: ignore[arg-type]
    assert_sound(build_polynomial(params))


def test_polynomial_small_root_next_to_a_huge_one() -> None:
    """F = 1e9·(1 − γ/deg) − 1e-9·γ³: roots at 1° and ~1.8e4°. The companion-matrix root at
    1° is off by ~1e-4 rad; unpolished, W decreased by 1e5 J/m² past it."""
    data = {
        "law": "polynomial",
        "force_coefficients_N_per_mm": [1e9, -1e9, 1e-6, -1e-9],
        "max_angle_deg": 90.0,
        "beyond_range": "linear",
    }
    with pytest.raises(ValidationError, match="negative"):  # negative from 1° on: a bad fit
        PolynomialParams.model_validate(data)
    law = build_polynomial(PolynomialParams.model_construct(**data))  # type: ignore[arg-type]
    assert_sound(law)
    assert float(law.torque(math.radians(1.0) + 1e-9)) == 0.0


@settings(max_examples=60, deadline=None)
@given(
    points=st.lists(
        st.tuples(st.integers(0, 90), MAGNITUDES), min_size=2, max_size=8, unique_by=lambda p: p[0]
    ),
    beyond=st.sampled_from(["hold", "linear"]),
)
def test_tabulated_random_tables(points: list[tuple[int, float]], beyond: str) -> None:
    """Tables with values from 0 to 1e9, first angle above 0, last at 90°: sound."""
    points = sorted(points)
    law = build_tabulated(
        TabulatedParams(
            law="tabulated",
            angle_deg=[float(a) for a, _ in points],
            torque_N_per_m=[v for _, v in points],
            beyond_range=beyond,
        )
    )
    assert_sound(law)


@pytest.mark.parametrize(
    "bad",
    [
        {"angle_deg": [0.0, 0.0], "torque_N_per_m": [0.0, 1.0]},
        {"angle_deg": [0.0, 91.0], "torque_N_per_m": [0.0, 1.0]},
        {"angle_deg": [-1.0, 10.0], "torque_N_per_m": [0.0, 1.0]},
        {"angle_deg": [0.0, 10.0], "torque_N_per_m": [0.0, -1.0]},
        {"angle_deg": [0.0, 10.0], "torque_N_per_m": [0.0, float("inf")]},
        {"angle_deg": [0.0, 10.0], "torque_N_per_m": [0.0]},
    ],
)
def test_tabulated_invalid_tables(bad: dict[str, object]) -> None:
    with pytest.raises(ValidationError):
        TabulatedParams.model_validate({"law": "tabulated", **bad})
