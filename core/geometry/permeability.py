"""In-plane permeability of a fabric for liquid moulding: Gebart's fibre bed, two fibre families.

Gebart, "Permeability of unidirectional reinforcements for RTM", J. Compos. Mater. 26 (1992)
1100 [L], closed forms for an aligned bed of fibres of radius r at fibre fraction V:

    along the fibres   K∥ = (8 r² / c) · (1 − V)³ / V²
    across the fibres  K⊥ = C₁ · (√(V_max / V) − 1)^(5/2) · r²

with, for a quadratic arrangement, c = 57, C₁ = 16/(9π√2), V_max = π/4, and for a hexagonal
one c = 53, C₁ = 16/(9π√6), V_max = π/(2√3).

The fabric [C] (docs/physics.md, "Permeability of the draped preform"): each fibre family is an
aligned Gebart bed at the fabric's fibre fraction V (the fibres and the gaps between the tows
homogenised into one bed, a single-scale model that ignores the faster flow in the gaps), and the
families lie in parallel layers whose shares of the thickness are their shares of the fibre
volume; Darcy flows through parallel layers add, so

    K = Σ_f φ_f [K∥(V) d_f d_fᵀ + K⊥(V) (P − d_f d_fᵀ)],

d_f the unit fibre direction of family f and P the projector onto the fabric's plane. Under
shear the families rotate (K's principal directions follow them) and V rises as the sheared
cell says, so both principal values fall. SI units: m, m².
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from preform.base.arrays import FloatArray

Arrangement = Literal["hexagonal", "quadratic"]


@dataclass(frozen=True)
class GebartBed:
    """Gebart's constants for one fibre arrangement."""

    #: Shape factor c of the along-fibre form [-].
    c: float
    #: C₁ of the across-fibre form [-].
    c1: float
    #: Fibre fraction at which the bed closes across the fibres [-].
    max_fraction: float


GEBART: dict[str, GebartBed] = {
    "quadratic": GebartBed(57.0, 16.0 / (9.0 * math.pi * math.sqrt(2.0)), math.pi / 4.0),
    "hexagonal": GebartBed(
        53.0, 16.0 / (9.0 * math.pi * math.sqrt(6.0)), math.pi / (2.0 * math.sqrt(3.0))
    ),
}


def gebart_along(fraction: ArrayLike, radius: float, arrangement: Arrangement) -> FloatArray:
    """K∥ [m²] of an aligned bed at fibre fraction V [-], fibre radius r [m]."""
    v = np.asarray(fraction, dtype=float)
    bed = GEBART[arrangement]
    return np.asarray(8.0 * radius**2 / bed.c * (1.0 - v) ** 3 / v**2, dtype=float)


def gebart_across(fraction: ArrayLike, radius: float, arrangement: Arrangement) -> FloatArray:
    """K⊥ [m²] of an aligned bed at fibre fraction V [-], fibre radius r [m]; 0 at V_max."""
    v = np.asarray(fraction, dtype=float)
    bed = GEBART[arrangement]
    gap = np.maximum(np.sqrt(bed.max_fraction / v) - 1.0, 0.0)
    return np.asarray(bed.c1 * gap**2.5 * radius**2, dtype=float)


def fabric_permeability(
    fraction: ArrayLike,
    directions: tuple[FloatArray, ...],
    shares: tuple[float, ...],
    normal: FloatArray,
    radius: float,
    arrangement: Arrangement = "hexagonal",
) -> FloatArray:
    """In-plane permeability tensors (..., 3, 3) [m²] (module docstring).

    ``fraction`` (...) the fabric's fibre fraction; ``directions`` one unit fibre direction
    array (..., 3) per family; ``shares`` their fibre volume shares (summing to 1); ``normal``
    (..., 3) the unit normal of the fabric's plane.
    """
    v = np.asarray(fraction, dtype=float)
    along = gebart_along(v, radius, arrangement)[..., None, None]
    across = gebart_across(v, radius, arrangement)[..., None, None]
    n = np.asarray(normal, dtype=float)
    plane = np.eye(3) - n[..., :, None] * n[..., None, :]
    k = np.zeros((*v.shape, 3, 3))
    for d, share in zip(directions, shares, strict=True):
        dd = np.asarray(d, dtype=float)
        outer = dd[..., :, None] * dd[..., None, :]
        k = k + share * (along * outer + across * (plane - outer))
    return k
