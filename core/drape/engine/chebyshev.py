"""The continuum limit of a pin-jointed net on a sphere: an independent oracle for the engine.

A Chebyshev net (PHYSICS §6) with u, v arc lengths along the two fibre families and ω the angle
between them obeys ∂²ω/∂u∂v = −K sin ω. On a sphere of radius R (K = 1/R²) with geodesic
generators through the start, ω depends only on s = u·v/R² and f(s) = ω solves

    s f″ + f′ + sin f = 0,   f(0) = α,   f′(0) = −sin α.

s = 0 is a regular singular point, so the solution starts from its power series
f = Σ a_k s^k (k² a_k = −[sin f]_{k−1}), summed where it converges fast (|s| ≤ 0.05), and is
continued with an 8th-order Runge–Kutta method to both signs of s. u and v are signed: in the
quadrants where u·v > 0 the fibres close up (ω < α), where u·v < 0 they open.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from preform.base.arrays import FloatArray

#: The series is used for |s| up to here; its terms fall like s^k / (k!)².
_SERIES_LIMIT = 0.05
_SERIES_TERMS = 30


def series_coefficients(alpha: float, terms: int = _SERIES_TERMS) -> FloatArray:
    """Power-series coefficients a_0..a_{terms−1} of f(s) for generator angle α [rad].

    sin f and cos f are expanded alongside f: with S = sin f, C = cos f, S′ = C f′ and
    C′ = −S f′ give k S_k = Σ m a_m C_{k−m}, k C_k = −Σ m a_m S_{k−m} (m = 1..k).
    """
    a = np.zeros(terms)
    s_coef = np.zeros(terms)
    c_coef = np.zeros(terms)
    a[0] = alpha
    s_coef[0], c_coef[0] = math.sin(alpha), math.cos(alpha)
    if terms > 1:
        a[1] = -s_coef[0]
    for k in range(1, terms - 1):
        m = np.arange(1, k + 1)
        s_coef[k] = np.sum(m * a[m] * c_coef[k - m]) / k
        c_coef[k] = -np.sum(m * a[m] * s_coef[k - m]) / k
        a[k + 1] = -s_coef[k] / (k + 1) ** 2
    return a


def _series(a: FloatArray, s: FloatArray) -> tuple[FloatArray, FloatArray]:
    """f and f′ from the series at s."""
    f = np.asarray(np.polynomial.polynomial.polyval(s, a), dtype=float)
    df = np.asarray(np.polynomial.polynomial.polyval(s, a[1:] * np.arange(1, len(a))), dtype=float)
    return f, df


def chebyshev_shear_profile(s: ArrayLike, alpha: float) -> FloatArray:
    """f(s) = ω [rad] at s = u·v/R² [-] for generator angle α [rad] (see module docstring)."""
    s_arr = np.asarray(s, dtype=float)
    flat = s_arr.ravel()
    out = np.empty_like(flat)
    a = series_coefficients(float(alpha))
    near = np.abs(flat) <= _SERIES_LIMIT
    out[near] = _series(a, flat[near])[0]
    for sign in (1.0, -1.0):
        far = ~near & (np.sign(flat) == sign)
        if not far.any():
            continue
        s0 = sign * _SERIES_LIMIT
        f0, df0 = _series(a, np.array([s0]))

        def rhs(x: float, y: FloatArray) -> list[float]:
            return [y[1], -(y[1] + math.sin(y[0])) / x]

        targets = flat[far]
        end = float(targets.max() if sign > 0 else targets.min())
        from scipy.integrate import solve_ivp  # only the far field needs scipy

        sol = solve_ivp(
            rhs,
            (s0, end),
            [float(f0[0]), float(df0[0])],
            method="DOP853",
            rtol=1e-13,
            atol=1e-14,
            dense_output=True,
        )
        if not sol.success:  # pragma: no cover - the ODE is regular away from s = 0
            raise RuntimeError(f"Chebyshev ODE failed: {sol.message}")
        out[far] = sol.sol(targets)[0]
    return out.reshape(s_arr.shape)


def chebyshev_angle(u: ArrayLike, v: ArrayLike, radius: float, alpha: float) -> FloatArray:
    """Fibre angle ω [rad] of the continuum net on a sphere at signed arc lengths ``u``, ``v``
    [m] from the start along the generators, sphere radius ``radius`` [m], generator angle
    ``alpha`` [rad]. The shear of the preform convention is ω − π/2."""
    u_arr, v_arr = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    return chebyshev_shear_profile(u_arr * v_arr / radius**2, alpha)
