"""Warp-knit ``stitch_polynomial`` law: asymmetry, stitch failure, exact energy."""

from __future__ import annotations

import math
import pickle
from typing import Any

import numpy as np
import pytest
from pydantic import ValidationError
from scipy.integrate import quad

from preform.plugins.warpknit.shear import (
    SHEAR_LAWS,
    StitchPolynomialParams,
    build_stitch_polynomial,
)
from preform.shear.law import ShearLaw, force_per_length_N_per_mm

RAD = math.pi / 180

#: The illustrative library blocks (no digitised data exists; shapes from the paper's text).
TRICOT_936: dict[str, Any] = {
    "law": "stitch_polynomial",
    "parallel_force_coefficients_N_per_mm": [0.0, 2.0e-3, 4.0e-5],
    "perpendicular_force_coefficients_N_per_mm": [0.0, 5.0e-4, 1.5e-5],
    "max_angle_deg": 60.0,
    "beyond_range": "hold",
}
CHAIN_318: dict[str, Any] = {
    "law": "stitch_polynomial",
    "parallel_force_coefficients_N_per_mm": [0.0, 4.0e-3, 9.0e-5],
    "perpendicular_force_coefficients_N_per_mm": [0.0, 3.0e-4, 1.0e-5],
    "failure_angle_deg": 35.0,
    "failure_width_deg": 5.0,
    "post_failure_force_coefficients_N_per_mm": [0.03, 0.0, 0.0, 1.0e-6],
    "max_angle_deg": 60.0,
    "beyond_range": "hold",
}


def law_of(block: dict[str, Any], **changes: Any) -> ShearLaw:
    return build_stitch_polynomial(StitchPolynomialParams.model_validate({**block, **changes}))


def force(law: ShearLaw, deg: Any) -> np.ndarray:
    return force_per_length_N_per_mm(law, np.radians(deg))


def test_registry_tuple() -> None:
    assert SHEAR_LAWS[0][0] == "stitch_polynomial"


@pytest.mark.parametrize("block", [TRICOT_936, CHAIN_318])
def test_parallel_is_stiffer_than_perpendicular(block: dict[str, Any]) -> None:
    law = law_of(block)
    deg = np.linspace(1.0, 60.0, 60)
    parallel, perpendicular = force(law, deg), -force(law, -deg)
    assert np.all(parallel > perpendicular) and np.all(perpendicular > 0.0)
    assert np.all(law.energy(np.radians(deg)) > law.energy(-np.radians(deg)))
    assert np.all(force(law, deg) < 0.5)  # typical NCF magnitudes below 60°


def test_chain_stitch_peaks_at_failure_falls_then_rises() -> None:
    law = law_of(CHAIN_318)
    assert law.failure_angle == pytest.approx(35 * RAD)
    deg = np.linspace(0.0, 60.0, 1201)
    f = force(law, deg)
    peak = deg[np.argmax(f[deg < 45])]
    assert 35.0 <= peak < 37.0
    trough = deg[deg > peak][np.argmin(f[deg > peak])]
    assert 39.0 <= trough <= 41.0
    assert f[deg == trough] < 0.5 * f.max()
    assert f[-1] > f[deg == trough]  # compaction rise


def test_failure_drop_is_continuous_in_value_and_slope() -> None:
    law = law_of(CHAIN_318)
    for edge in (35.0, 40.0):
        left, right = force(law, edge - 1e-7), force(law, edge + 1e-7)
        assert left == pytest.approx(right, abs=1e-8)
        slope_l = (force(law, edge - 1e-7) - force(law, edge - 1e-4)) / (1e-4 - 1e-7)
        slope_r = (force(law, edge + 1e-4) - force(law, edge + 1e-7)) / (1e-4 - 1e-7)
        assert slope_l == pytest.approx(slope_r, rel=1e-3, abs=1e-6)


def test_pre_failure_branch_is_the_given_polynomial() -> None:
    law = law_of(CHAIN_318)
    assert force(law, 20.0) == pytest.approx(4e-3 * 20 + 9e-5 * 400)
    assert force(law, 50.0) == pytest.approx(0.03 + 1e-6 * 50**3)
    assert force(law, -30.0) == pytest.approx(-(3e-4 * 30 + 1e-5 * 900))


@pytest.mark.parametrize("block", [TRICOT_936, CHAIN_318])
def test_energy_is_the_integral_of_the_torque(block: dict[str, Any]) -> None:
    law = law_of(block)
    for deg in (-50.0, 20.0, 37.0, 55.0, 75.0):
        expected, _ = quad(
            lambda g: float(law.torque(g)), 0, deg * RAD, points=[35 * RAD, 40 * RAD], limit=200
        )
        assert law.energy(deg * RAD) == pytest.approx(abs(expected), rel=1e-9)


def test_beyond_range_never_negative() -> None:
    falling = law_of(
        CHAIN_318, post_failure_force_coefficients_N_per_mm=[0.3, -4e-3], beyond_range="linear"
    )
    deg = np.linspace(0, 89.5, 180)
    assert np.all(force(falling, deg) >= 0.0)
    assert force(falling, 80.0) == 0.0
    assert np.all(np.diff(falling.energy(np.radians(deg))) >= -1e-12)


def test_law_pickles_and_without_failure_is_plain_polynomials() -> None:
    law = law_of(TRICOT_936)
    assert law.failure_angle is None and law.locking_angle is None
    clone = pickle.loads(pickle.dumps(law))
    g = np.radians([-40.0, 40.0])
    np.testing.assert_array_equal(clone.energy(g), law.energy(g))
    assert force(law, 40.0) == pytest.approx(2e-3 * 40 + 4e-5 * 1600)


@pytest.mark.parametrize(
    "changes",
    [
        {"failure_angle_deg": 58.0},  # drop ends past the fitted range
        {"post_failure_force_coefficients_N_per_mm": None},
        {"failure_angle_deg": None},
        {"parallel_force_coefficients_N_per_mm": []},
        {"stitch_gauge": 5},
    ],
)
def test_invalid_blocks_are_rejected(changes: dict[str, Any]) -> None:
    with pytest.raises(ValidationError):
        StitchPolynomialParams.model_validate({**CHAIN_318, **changes})
