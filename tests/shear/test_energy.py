"""Energy integration: exact piecewise polynomials and cumulative Gauss–Legendre quadrature."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from preform.shear.energy import DOMAIN_END, PiecewiseBranch, QuadratureBranch

ANGLES = np.linspace(0.0, DOMAIN_END, 37)


def test_polynomial_energy_is_the_exact_antiderivative() -> None:
    branch = PiecewiseBranch([0.0], [[1.0, 2.0, 3.0]])
    u = ANGLES
    np.testing.assert_allclose(branch.energy(u), u + u**2 + u**3, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(branch.magnitude(u), 1 + 2 * u + 3 * u**2)


def test_cos_weighted_energy_matches_closed_form() -> None:
    # ∫ (2 + u²) cos u du = (2 + u²) sin u + 2u cos u − 2 sin u = u² sin u + 2u cos u
    branch = PiecewiseBranch([0.0], [[2.0, 0.0, 1.0]], weight="cos")
    u = ANGLES
    np.testing.assert_allclose(branch.energy(u), u**2 * np.sin(u) + 2 * u * np.cos(u), atol=1e-13)


def test_negative_stretches_are_clipped_and_integrated_exactly() -> None:
    # p(u) = (u − 0.3)(u − 0.9) is negative between its roots: torque there is zero.
    coef = [0.27, -1.2, 1.0]
    branch = PiecewiseBranch([0.0], [coef])
    assert np.all(branch.magnitude(ANGLES) >= 0.0)
    for u in (0.2, 0.5, 0.9, 1.2, DOMAIN_END):
        expected, _ = quad(
            lambda x: max(0.0, np.polyval(coef[::-1], x)), 0, u, points=[0.3, 0.9], epsabs=1e-13
        )
        assert branch.energy(u) == pytest.approx(expected, rel=1e-10, abs=1e-13)
    assert branch.energy(0.5) == pytest.approx(branch.energy(0.9), abs=1e-14)


def test_piecewise_energy_accumulates_over_pieces() -> None:
    branch = PiecewiseBranch([0.0, 0.5], [[0.0, 1.0], [0.5]])  # ramp, then hold
    assert branch.energy(0.5) == pytest.approx(0.125)
    assert branch.energy(1.0) == pytest.approx(0.125 + 0.25)


def test_angles_beyond_ninety_degrees_are_clamped() -> None:
    branch = PiecewiseBranch([0.0], [[1.0]])
    assert branch.energy(3.0) == pytest.approx(DOMAIN_END)
    assert branch.energy(-0.4) == pytest.approx(0.4)  # magnitudes


def test_invalid_breaks_are_rejected() -> None:
    with pytest.raises(ValueError):
        PiecewiseBranch([0.1], [[1.0]])
    with pytest.raises(ValueError):
        PiecewiseBranch([0.0, 0.0], [[1.0], [2.0]])


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(-5.0, 5.0), min_size=1, max_size=5),
    st.floats(0.0, 1.5),
    st.sampled_from(["one", "cos"]),
)
def test_exact_energy_matches_quadrature_of_the_clipped_torque(
    coef: list[float], u: float, weight: str
) -> None:
    branch = PiecewiseBranch([0.0], [coef], weight="cos" if weight == "cos" else "one")

    def torque(x: float) -> float:
        value = np.polyval(coef[::-1], x) * (math.cos(x) if weight == "cos" else 1.0)
        return max(0.0, float(value))

    # The kinks of the clipped torque are the real roots; tell the adaptive rule about them.
    significant = np.trim_zeros(np.where(np.abs(coef) > 1e-12, coef, 0.0), "b")
    roots = np.roots(significant[::-1]) if significant.size > 1 else np.array([])
    kinks = [r.real for r in roots if abs(r.imag) < 1e-9 and 0 < r.real < u]
    expected, _ = quad(torque, 0.0, u, points=kinks or None, limit=200, epsabs=1e-13)
    assert branch.energy(u) == pytest.approx(expected, rel=1e-8, abs=1e-9)
    grid = np.linspace(0.0, u, 20)
    assert np.all(np.diff(branch.energy(grid)) >= -1e-12)  # W non-decreasing


def test_quadrature_branch_error_is_below_stated_bound() -> None:
    # Smooth law with a closed-form integral: M = sinh(3u), W = (cosh(3u) − 1)/3.
    branch = QuadratureBranch(lambda u: np.sinh(3 * u))
    u = np.linspace(0.0, 1.5, 301)
    exact = (np.cosh(3 * u) - 1) / 3
    np.testing.assert_allclose(branch.energy(u), exact, rtol=1e-10, atol=1e-14)


def test_quadrature_branch_handles_a_kink_at_a_breakpoint() -> None:
    kink = math.radians(39.19)
    branch = QuadratureBranch(lambda u: 1.0 + 50.0 * np.maximum(u - kink, 0.0) ** 2, [kink])
    u = np.array([0.3, kink, 0.9, 1.4])
    exact = u + 50.0 * np.maximum(u - kink, 0.0) ** 3 / 3.0
    np.testing.assert_allclose(branch.energy(u), exact, rtol=1e-12)


def test_quadrature_branch_vectorises_over_any_shape_and_pickles() -> None:
    branch = QuadratureBranch(np.cos)
    u = np.linspace(0, 1, 12).reshape(3, 4)
    assert branch.energy(u).shape == (3, 4)
    np.testing.assert_allclose(branch.energy(u), np.sin(u), atol=1e-14)
    clone = pickle.loads(pickle.dumps(branch))
    np.testing.assert_allclose(clone.energy(u), branch.energy(u))
