"""Picture-frame and bias-extension normalisation, and fitting the result."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import ArrayLike
from scipy.integrate import cumulative_trapezoid

from preform.shear.fit import (
    block_to_yaml,
    fit_polynomial,
    fit_table,
    shear_law_block,
)
from preform.shear.law import force_per_length_N_per_mm
from preform.shear.laws import PolynomialParams, TabulatedParams, build_polynomial, build_tabulated
from preform.shear.testdata import (
    bias_extension_displacement,
    bias_extension_force,
    bias_extension_shear_angle,
    normalise_bias_extension,
    normalise_picture_frame,
    picture_frame_displacement,
    picture_frame_shear_angle,
)

SIDE = 150.0
TRUE_COEFFICIENTS = [0.0, 1.5e-3, -2e-5, 1e-6]  # F_s/L [N/mm] in γ [deg]


def true_force(deg: ArrayLike) -> np.ndarray:
    return np.asarray(np.polynomial.polynomial.polyval(np.asarray(deg, float), TRUE_COEFFICIENTS))


def test_picture_frame_kinematics() -> None:
    assert picture_frame_shear_angle(0.0, SIDE) == pytest.approx(0.0, abs=1e-12)
    # Fully closed frame: (√2 L + δ)/(2L) = 1 → γ = 90°.
    closed = (2 - math.sqrt(2)) * SIDE
    assert picture_frame_shear_angle(closed, SIDE) == pytest.approx(math.pi / 2)
    g = np.radians(np.linspace(0, 80, 9))
    np.testing.assert_allclose(
        picture_frame_shear_angle(picture_frame_displacement(g, SIDE), SIDE), g, atol=1e-12
    )


def raw_picture_frame(deg: np.ndarray, side: float = SIDE) -> tuple[np.ndarray, np.ndarray]:
    """Synthesise (δ [mm], F [N]) from the known F_s/L law: F = 2 cos ψ · F_s."""
    g = np.radians(deg)
    psi = (math.pi / 2 - g) / 2
    return picture_frame_displacement(g, side), 2 * np.cos(psi) * true_force(deg) * side


def test_picture_frame_normalisation_round_trip_recovers_the_law() -> None:
    deg = np.linspace(1, 65, 40)
    delta, force = raw_picture_frame(deg)
    result = normalise_picture_frame(delta, force, SIDE)
    np.testing.assert_allclose(np.degrees(result.shear_angle), deg, rtol=1e-10)
    np.testing.assert_allclose(result.force_per_length_N_per_mm, true_force(deg), rtol=1e-10)
    fit = fit_polynomial(np.degrees(result.shear_angle), result.force_per_length_N_per_mm, 3)
    np.testing.assert_allclose(fit.coefficients_N_per_mm, TRUE_COEFFICIENTS, atol=1e-12)
    assert fit.quality.r_squared == pytest.approx(1.0)
    assert fit.quality.rmse_N_per_mm < 1e-12


def test_picture_frame_work_equals_strain_energy() -> None:
    # Independent of the normalisation formula: ∫F dδ = W(γ)·L² (power balance).
    deg = np.linspace(0, 60, 2001)
    delta, force = raw_picture_frame(deg)
    work_J = cumulative_trapezoid(force, delta * 1e-3, initial=0.0)
    law = build_polynomial(
        PolynomialParams(
            law="polynomial", force_coefficients_N_per_mm=TRUE_COEFFICIENTS, max_angle_deg=60
        )
    )
    energy = law.energy(np.radians(deg)) * (SIDE * 1e-3) ** 2
    np.testing.assert_allclose(work_J[1:], energy[1:], rtol=2e-5)


def test_cruciform_specimen_scales_with_the_sheared_area() -> None:
    delta, force = raw_picture_frame(np.array([20.0, 40.0]))
    full = normalise_picture_frame(delta, force, SIDE)
    cross = normalise_picture_frame(delta, force, SIDE, fabric_side_mm=100.0)
    np.testing.assert_allclose(cross.torque_N_per_m, full.torque_N_per_m * (SIDE / 100.0) ** 2)


@settings(max_examples=30, deadline=None)
@given(st.floats(1.0, 85.0), st.floats(0.1, 500.0), st.floats(50.0, 300.0))
def test_picture_frame_torque_and_force_are_kinematically_consistent(
    deg: float, force: float, side: float
) -> None:
    g = math.radians(deg)
    result = normalise_picture_frame(picture_frame_displacement(g, side), force, side)
    psi = (math.pi / 2 - g) / 2
    assert result.force_per_length_N_per_mm == pytest.approx(force / (2 * math.cos(psi)) / side)
    assert result.torque_N_per_m == pytest.approx(
        1000 * result.force_per_length_N_per_mm * math.cos(g)
    )


HEIGHT, WIDTH = 300.0, 100.0


def test_bias_extension_kinematics_invert() -> None:
    g = np.radians(np.linspace(0, 70, 8))
    delta = bias_extension_displacement(g, HEIGHT, WIDTH)
    assert delta[0] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(bias_extension_shear_angle(delta, HEIGHT, WIDTH), g, atol=1e-12)
    with pytest.raises(ValueError):
        bias_extension_shear_angle(1.0, 150.0, 100.0)


def test_bias_extension_normalisation_recovers_the_law_and_the_energy() -> None:
    deg = np.linspace(0.0, 60.0, 1201)
    g = np.radians(deg)
    force = bias_extension_force(g, true_force(deg), true_force(deg / 2), HEIGHT, WIDTH)
    delta = bias_extension_displacement(g, HEIGHT, WIDTH)
    # Independent truth: work of the axial force = energy of regions A (γ) and B (γ/2).
    law = build_polynomial(
        PolynomialParams(
            law="polynomial", force_coefficients_N_per_mm=TRUE_COEFFICIENTS, max_angle_deg=60
        )
    )
    area_a = (HEIGHT * WIDTH - 1.5 * WIDTH**2) * 1e-6
    area_b = WIDTH**2 * 1e-6
    energy = area_a * law.energy(g) + area_b * law.energy(g / 2)
    work = cumulative_trapezoid(force, delta * 1e-3, initial=0.0)
    np.testing.assert_allclose(work[10:], energy[10:], rtol=1e-4)
    result = normalise_bias_extension(delta, force, HEIGHT, WIDTH)
    np.testing.assert_allclose(
        result.force_per_length_N_per_mm[1:], true_force(deg[1:]), rtol=1e-4, atol=1e-8
    )


def test_fitted_blocks_validate_and_round_trip_through_yaml() -> None:
    deg = np.linspace(0, 50, 26)
    fit = fit_polynomial(deg, true_force(deg), 3)
    block = shear_law_block(fit, fit_polynomial(deg, 0.5 * true_force(deg), 3))
    text = block_to_yaml(block, ["a comment"])
    assert text.startswith("# a comment\n")
    loaded = yaml.safe_load(text)["shear_law"]
    law = build_polynomial(PolynomialParams.model_validate(loaded))
    assert force_per_length_N_per_mm(law, math.radians(30)) == pytest.approx(true_force(30.0))
    assert force_per_length_N_per_mm(law, -math.radians(30)) == pytest.approx(
        -0.5 * true_force(30.0)
    )


def test_table_fit_gives_a_valid_tabulated_law() -> None:
    rng = np.random.default_rng(1)
    deg = np.sort(rng.uniform(0, 50, 400))
    fit = fit_table(deg, true_force(deg), step_deg=2.0)
    assert len(fit.angle_deg) == 25
    assert fit.quality.r_squared > 0.999
    law = build_tabulated(TabulatedParams.model_validate(shear_law_block(fit)))
    assert force_per_length_N_per_mm(law, math.radians(25)) == pytest.approx(
        true_force(25.0), rel=0.02
    )


def test_fit_rejects_bad_input() -> None:
    with pytest.raises(ValueError):
        fit_polynomial([1.0, 2.0], [0.1, 0.2], 0)
    with pytest.raises(ValueError):
        fit_polynomial([1.0], [0.1], 1)
