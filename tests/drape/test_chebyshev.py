"""The Chebyshev-net oracle against the PDE it comes from, solved independently."""

from __future__ import annotations

import numpy as np
import pytest

from preform.drape.engine.chebyshev import (
    chebyshev_angle,
    chebyshev_shear_profile,
    series_coefficients,
)


@pytest.mark.parametrize("alpha", [np.pi / 2, 1.0, 2.2])
def test_profile_solves_the_ode_across_the_series_switch(alpha: float) -> None:
    """s f'' + f' + sin f = 0 by finite differences on both sides of s = 0 and across the
    switch from series to Runge–Kutta at |s| = 0.05."""
    h = 1e-3
    s = np.concatenate([np.linspace(-2.0, -0.002, 60), np.linspace(0.002, 2.5, 60), [0.05, -0.05]])
    f = chebyshev_shear_profile(s, alpha)
    fp = chebyshev_shear_profile(s + h, alpha)
    fm = chebyshev_shear_profile(s - h, alpha)
    d1 = (fp - fm) / (2 * h)
    d2 = (fp - 2 * f + fm) / h**2
    assert np.max(np.abs(s * d2 + d1 + np.sin(f))) < 1e-5
    assert chebyshev_shear_profile(0.0, alpha) == pytest.approx(alpha, abs=1e-15)
    slope = (chebyshev_shear_profile(1e-7, alpha) - chebyshev_shear_profile(-1e-7, alpha)) / 2e-7
    assert slope == pytest.approx(-np.sin(alpha), rel=1e-6)


def test_series_matches_hand_expansion() -> None:
    a = series_coefficients(0.7, terms=4)
    # By hand from k² a_k = −[sin f]_{k−1}: a1 = −S, a2 = S·C/4, and
    # [sin f]_2 = C·a2 − S·a1²/2 = S·C²/4 − S³/2, so a3 = S·(2S² − C²)/36.
    s, c = np.sin(0.7), np.cos(0.7)
    np.testing.assert_allclose(a[:3], [0.7, -s, s * c / 4], rtol=1e-14)
    assert a[3] == pytest.approx(s * (2 * s**2 - c**2) / 36, rel=1e-12)


def test_right_angle_profile_is_odd_about_90_degrees() -> None:
    """At α = 90° the shear ω − 90° is odd in s (derived from the ODE: −g(−s) solves the same
    problem as g), which is why a symmetric fabric on a hemisphere prefers α = 90°."""
    s = np.linspace(0.0, 2.4, 50)
    up = chebyshev_shear_profile(s, np.pi / 2) - np.pi / 2
    down = chebyshev_shear_profile(-s, np.pi / 2) - np.pi / 2
    np.testing.assert_allclose(up, -down, atol=1e-11)


def _goursat(alpha: float, radius: float, n: int, length: float) -> np.ndarray:
    """∂²ω/∂u∂v = −sin ω / R² on [0, L]², ω = α on both axes, by a second-order box
    scheme with the forcing at the cell centre (implicit, solved by fixed-point)."""
    h = length / n
    w = np.full((n + 1, n + 1), alpha)
    for i in range(n):
        for j in range(n):
            guess = w[i + 1, j] + w[i, j + 1] - w[i, j]
            for _ in range(6):
                centre = 0.25 * (w[i, j] + w[i + 1, j] + w[i, j + 1] + guess)
                guess = w[i + 1, j] + w[i, j + 1] - w[i, j] - h * h * np.sin(centre) / radius**2
            w[i + 1, j + 1] = guess
    return w


@pytest.mark.parametrize("alpha", [np.pi / 2, 1.1])
def test_oracle_matches_a_direct_solution_of_the_pde(alpha: float) -> None:
    """The reduction to s = uv/R² is checked against the Goursat problem itself."""
    radius, length = 0.8, 1.0
    errors = []
    for n in (20, 40):
        w = _goursat(alpha, radius, n, length)
        u = np.linspace(0.0, length, n + 1)
        exact = chebyshev_angle(u[:, None], u[None, :], radius, alpha)
        errors.append(np.max(np.abs(w - exact)))
    assert errors[1] < 1e-4
    assert errors[0] / errors[1] > 3.0  # second order


def test_quadrant_signs() -> None:
    """Signed arc lengths: u·v > 0 closes the fibres (ω < α), u·v < 0 opens them."""
    alpha = 1.2
    closes = chebyshev_angle(np.array([0.3, -0.3]), np.array([0.2, -0.2]), 1.0, alpha)
    opens = chebyshev_angle(np.array([0.3, -0.3]), np.array([-0.2, 0.2]), 1.0, alpha)
    assert np.all(closes < alpha) and np.all(opens > alpha)
    np.testing.assert_allclose(chebyshev_angle(0.0, np.array([-1.0, 2.0]), 1.0, alpha), alpha)
