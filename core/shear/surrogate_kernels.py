"""Compiled evaluation of the tabulated shear-law surrogate (``preform.shear.surrogate``).

One pass over the angles, no temporaries: the cubic Hermite interpolant of W through the
tabulated energies and slopes of the sense each angle shears in. The only implementation of
that interpolant's value; imported when a surrogate is evaluated, so numba stays out of
start-up.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from preform.base.kernel_cache import cache_by_content

#: No other preform module is compiled into these kernels; the key they are cached under
#: is this file's (``preform.base.kernel_cache``).
COMPILED_IN: tuple[str, ...] = ()
cache_by_content(__name__)

FloatArray = NDArray[np.float64]

_jit = numba.njit(cache=True, error_model="numpy")
# inlined into the loop (numba's own inlining): arrays handed to a function that is not inlined
# are reference counted at every call, which cost more than the interpolation
_per_angle = numba.njit(cache=True, error_model="numpy", inline="always")


@_per_angle
def _hermite(
    nodes: FloatArray, energy: FloatArray, left: FloatArray, right: FloatArray, u: float
) -> float:
    """W(u) [J/m²] on one sense's table: magnitudes u [rad] clamped to the table, the cubic
    Hermite polynomial through W and its (limited) slopes at the interval's ends, never below
    the smaller end value (a non-negative law's W does not decrease)."""
    if math.isnan(u):
        return np.nan
    last = nodes.shape[0] - 1
    u = min(max(u, 0.0), nodes[last])
    # the interval k with nodes[k] <= u < nodes[k + 1] (the last one for u at the end), by
    # bisection: the grid is refined near a jamming angle, so it is not uniform
    lo, hi = 0, last
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if nodes[mid] <= u:
            lo = mid
        else:
            hi = mid
    k = lo
    h = nodes[k + 1] - nodes[k]
    t = (u - nodes[k]) / h
    t2, t3 = t * t, t * t * t
    w = (
        (2 * t3 - 3 * t2 + 1) * energy[k]
        + (t3 - 2 * t2 + t) * h * left[k]
        + (-2 * t3 + 3 * t2) * energy[k + 1]
        + (t3 - t2) * h * right[k]
    )
    return max(w, min(energy[k], energy[k + 1]))


@_jit
def signed_energy(
    nodes: FloatArray,
    positive: tuple[FloatArray, FloatArray, FloatArray],
    negative: tuple[FloatArray, FloatArray, FloatArray],
    gamma: FloatArray,
    out: FloatArray,
) -> None:
    """W(γ) [J/m²] at signed angles γ [rad] (flat): the positive sense's table (energies, left
    and right slopes) for γ ≥ 0, the negative sense's for γ < 0; written to ``out``."""
    pos_energy, pos_left, pos_right = positive
    neg_energy, neg_left, neg_right = negative
    for i in range(gamma.shape[0]):
        g = gamma[i]
        if g >= 0.0:
            out[i] = _hermite(nodes, pos_energy, pos_left, pos_right, g)
        else:
            out[i] = _hermite(nodes, neg_energy, neg_left, neg_right, -g)
