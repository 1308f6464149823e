"""Generic polynomial and tabulated shear laws."""

from __future__ import annotations

import math
import pickle
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError
from scipy.integrate import quad

from preform.shear.law import ShearLaw, force_per_length_N_per_mm
from preform.shear.laws import (
    SHEAR_LAWS,
    PolynomialParams,
    TabulatedParams,
    build_polynomial,
    build_tabulated,
)

RAD = math.pi / 180


def polynomial(**fields: Any) -> ShearLaw:
    return build_polynomial(PolynomialParams(law="polynomial", **fields))


def tabulated(**fields: Any) -> ShearLaw:
    return build_tabulated(TabulatedParams(law="tabulated", **fields))


def test_registry_tuples_name_their_models() -> None:
    for name, model, builder in SHEAR_LAWS:
        assert model.model_fields["law"].annotation.__args__ == (name,)
        assert callable(builder)


def test_torque_polynomial_energy_is_exact() -> None:
    # C = 2·(γ/deg) N/m → W = ∫ 2·g·(180/π) dg = (180/π) γ² J/m².
    law = polynomial(torque_coefficients_N_per_m=[0.0, 2.0], max_angle_deg=89.0)
    gamma = np.radians([5.0, 30.0, 60.0])
    np.testing.assert_allclose(law.energy(gamma), 180 / math.pi * gamma**2, rtol=1e-12)
    np.testing.assert_allclose(law.torque(gamma), 2 * np.degrees(gamma))


def test_force_polynomial_is_consistent_with_picture_frame_kinematics() -> None:
    law = polynomial(force_coefficients_N_per_mm=[0.0, 1e-3, 2e-5], max_angle_deg=60.0)
    deg = np.array([10.0, 35.0, 55.0])
    force = 1e-3 * deg + 2e-5 * deg**2
    np.testing.assert_allclose(force_per_length_N_per_mm(law, np.radians(deg)), force, rtol=1e-12)
    np.testing.assert_allclose(law.torque(np.radians(deg)), 1000 * force * np.cos(np.radians(deg)))


def test_symmetric_law_is_odd_in_torque_and_even_in_energy() -> None:
    law = polynomial(force_coefficients_N_per_mm=[0.0, 1e-3], max_angle_deg=50.0)
    g = np.radians(np.linspace(0, 80, 17))
    np.testing.assert_array_equal(law.torque(-g), -law.torque(g))
    np.testing.assert_array_equal(law.energy(-g), law.energy(g))


def test_asymmetric_law_uses_the_negative_branch() -> None:
    law = polynomial(
        force_coefficients_N_per_mm=[0.0, 2e-3],
        force_coefficients_negative_N_per_mm=[0.0, 5e-4],
        max_angle_deg=60.0,
    )
    g = 30 * RAD
    assert force_per_length_N_per_mm(law, g) == pytest.approx(0.06)
    assert force_per_length_N_per_mm(law, -g) == pytest.approx(-0.015)
    assert law.energy(g) > law.energy(-g) > 0.0


@pytest.mark.parametrize(
    ("policy", "expected_at_70"), [("hold", 0.225), ("linear", 0.0), ("extrapolate", 0.0)]
)
def test_beyond_range_policies_never_give_negative_torque(
    policy: str, expected_at_70: float
) -> None:
    # F = 0.05 γ − 1e-3 γ² (γ in deg) peaks at 25° and is 0.225 N/mm at the range end, 45°;
    # its tangent there falls at 0.04 N/mm/deg, so both continuations cross zero before 70°.
    law = polynomial(
        force_coefficients_N_per_mm=[0.0, 0.05, -1e-3], max_angle_deg=45.0, beyond_range=policy
    )
    assert force_per_length_N_per_mm(law, 70 * RAD) == pytest.approx(expected_at_70, abs=1e-15)
    g = np.radians(np.linspace(0, 89, 90))
    assert np.all(law.torque(g) >= 0.0)
    assert np.all(np.diff(law.energy(g)) >= -1e-12)


def test_linear_policy_continues_the_tangent() -> None:
    law = polynomial(
        force_coefficients_N_per_mm=[0.0, 0.0, 1e-4], max_angle_deg=40.0, beyond_range="linear"
    )
    # F(40) = 0.16, F'(40) = 8e-3 per degree.
    assert force_per_length_N_per_mm(law, 50 * RAD) == pytest.approx(0.16 + 0.08)


def test_tabulated_law_passes_through_its_points_and_stays_monotone() -> None:
    angles = [5.0, 15.0, 30.0, 45.0, 55.0]
    forces = [0.01, 0.02, 0.05, 0.2, 0.6]
    law = tabulated(angle_deg=angles, force_N_per_mm=forces)
    np.testing.assert_allclose(force_per_length_N_per_mm(law, np.radians(angles)), forces)
    fine = np.radians(np.linspace(0, 55, 500))
    assert np.all(np.diff(force_per_length_N_per_mm(law, fine)) >= -1e-12)
    assert force_per_length_N_per_mm(law, 0.0) == pytest.approx(0.0)
    assert force_per_length_N_per_mm(law, 70 * RAD) == pytest.approx(0.6)  # hold


def test_tabulated_energy_matches_quadrature() -> None:
    law = tabulated(angle_deg=[0.0, 20.0, 40.0, 60.0], torque_N_per_m=[0.0, 10.0, 15.0, 60.0])
    for deg in (10.0, 40.0, 75.0):
        expected, _ = quad(lambda g: float(law.torque(g)), 0, deg * RAD, limit=200)
        assert law.energy(deg * RAD) == pytest.approx(expected, rel=1e-9)


def test_tabulated_separate_senses() -> None:
    law = tabulated(
        angle_deg=[10.0, 40.0],
        force_N_per_mm=[0.02, 0.2],
        angle_negative_deg=[10.0, 40.0],
        force_negative_N_per_mm=[0.01, 0.05],
    )
    assert force_per_length_N_per_mm(law, -40 * RAD) == pytest.approx(-0.05)
    assert force_per_length_N_per_mm(law, 40 * RAD) == pytest.approx(0.2)


@pytest.mark.parametrize(
    "fields",
    [
        {"max_angle_deg": 40.0},
        {
            "force_coefficients_N_per_mm": [1.0],
            "torque_coefficients_N_per_m": [1.0],
            "max_angle_deg": 40.0,
        },
        {
            "force_coefficients_N_per_mm": [1.0],
            "torque_coefficients_negative_N_per_m": [1.0],
            "max_angle_deg": 40.0,
        },
        {"force_coefficients_N_per_mm": [1.0], "max_angle_deg": 40.0, "unknown": 1},
        {"force_coefficients_N_per_mm": [float("nan")], "max_angle_deg": 40.0},
    ],
)
def test_polynomial_params_reject_bad_blocks(fields: dict[str, Any]) -> None:
    with pytest.raises(ValidationError):
        PolynomialParams(law="polynomial", **fields)


@pytest.mark.parametrize(
    "fields",
    [
        {"angle_deg": [10.0, 5.0], "force_N_per_mm": [0.1, 0.2]},
        {"angle_deg": [10.0, 20.0], "force_N_per_mm": [0.1]},
        {"angle_deg": [10.0, 20.0], "force_N_per_mm": [0.1, -0.2]},
        {"angle_deg": [10.0, 20.0], "force_N_per_mm": [0.1, 0.2], "angle_negative_deg": [1.0, 2.0]},
    ],
)
def test_tabulated_params_reject_bad_blocks(fields: dict[str, Any]) -> None:
    with pytest.raises(ValidationError):
        TabulatedParams(law="tabulated", **fields)


def test_laws_pickle() -> None:
    law = tabulated(angle_deg=[10.0, 40.0], force_N_per_mm=[0.02, 0.2])
    clone = pickle.loads(pickle.dumps(law))
    g = np.radians([-30.0, 20.0])
    np.testing.assert_array_equal(clone.energy(g), law.energy(g))


positive_coefficients = st.lists(st.floats(0.0, 1e-2), min_size=1, max_size=4)


@settings(max_examples=40, deadline=None)
@given(
    positive_coefficients,
    st.floats(10.0, 89.0),
    st.lists(st.floats(-89.9, 89.9), min_size=1, max_size=8),
)
def test_energy_properties_of_non_negative_laws(
    coef: list[float], max_angle: float, angles_deg: list[float]
) -> None:
    law = polynomial(force_coefficients_N_per_mm=coef, max_angle_deg=max_angle)
    g = np.radians(np.array(angles_deg))
    assert law.energy(0.0) == 0.0
    np.testing.assert_array_equal(law.energy(g), law.energy(-g))
    assert np.all(law.torque(g) * g >= 0.0)
    order = np.argsort(np.abs(g))
    assert np.all(np.diff(law.energy(g[order])) >= -1e-12)
    np.testing.assert_allclose(
        force_per_length_N_per_mm(law, g) * 1000 * np.cos(g), law.torque(g), rtol=1e-12, atol=1e-12
    )
