"""Transverse compaction of a fibre bundle (tow): Gutowski's law and Cai–Gutowski's bundle stress.

Gutowski (1987, J. Compos. Mater. 21:650) [L]: the fibre network carries the transverse stress

    σ(V_f) = A_s (√(V_f/V_o) − 1) / (√(V_a/V_f) − 1)^4,   A_s = 3π E_f / β⁴,

zero below V_o (a fibre network carries no tension). Cai & Gutowski (1992, J. Compos. Mater.
26:1207) [P/L] write the bundle stress at zero axial strain as σ_b = e_b·F11 / (F_bb·F11 − F_bl²).
Their compliance functions were not available to us [C]: F11 = 1/(E_f V_f), F_bb = the tangent
compliance of Gutowski's law with respect to the bundle strain, F_bl a constant (default 0). With
compliances that change with V_f the relation is read incrementally, dσ_b = |de_b|·F11 / (F_bb F11
− F_bl²), integrated from the as-woven state, so with F_bl = 0 σ_b is exactly Gutowski's stress
increase over the as-woven state. The bundle strain at constant tow height is
e_b = Tw/Tw0 − 1 = V_f0/V_f − 1 (V_f = V_f0·Tw0/Tw).

Pole guard [C]: σ has a fourth-order pole at V_f → V_a. Above the cap fraction V_c = V_a(1 − ε)
(ε = ``packing_margin``) the stress continues along its tangent at V_c (continuous value and
slope), so a torque built on it grows steeply but stays finite; with F_bl ≠ 0 the cap also stops
where the Schur-complement denominator has fallen to 10 % of its uncoupled value. The shear law
reports the shear angle at which V_c is reached.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

    FloatArray = NDArray[np.float64]


#: Square packing of round fibres, the default maximum attainable fraction V_a.
SQUARE_PACKING = math.pi / 4


@functools.cache
def _gauss_legendre() -> tuple[FloatArray, FloatArray]:
    """24-point Gauss–Legendre nodes and weights on [-1, 1] (computed on first use, so that
    importing the law's parameters does not import numpy)."""
    import numpy as np

    nodes, weights = np.polynomial.legendre.leggauss(24)
    return nodes, weights


def gutowski_coefficient(fibre_modulus: float, span_to_height: float) -> float:
    """A_s = 3π E_f / β⁴ [Pa] from the fibre modulus E_f [Pa] and fibre-wave ratio β [-]."""
    return 3.0 * math.pi * fibre_modulus / span_to_height**4


def gutowski_stress(
    volume_fraction: ArrayLike, coefficient: float, onset_fraction: float, max_fraction: float
) -> FloatArray:
    """Gutowski's transverse stress σ [Pa] (A_s = ``coefficient`` [Pa]), unguarded.

    Zero for V_f ≤ V_o; +inf for V_f ≥ V_a (the pole; use ``BundleCompaction`` for a guarded law).
    """
    import numpy as np

    v = np.asarray(volume_fraction, dtype=float)
    safe = np.clip(v, onset_fraction, max_fraction)
    with np.errstate(divide="ignore", invalid="ignore"):
        value = (
            coefficient
            * (np.sqrt(safe / onset_fraction) - 1.0)
            / (np.sqrt(max_fraction / safe) - 1.0) ** 4
        )
    return np.where(v >= max_fraction, np.inf, np.where(v <= onset_fraction, 0.0, value))


def gutowski_stiffness(
    volume_fraction: ArrayLike, coefficient: float, onset_fraction: float, max_fraction: float
) -> FloatArray:
    """dσ/dV_f [Pa] of Gutowski's law for V_o < V_f < V_a (0 below V_o)."""
    import numpy as np

    v = np.asarray(volume_fraction, dtype=float)
    safe = np.clip(v, onset_fraction, max_fraction * (1 - 1e-12))
    s = np.sqrt(safe / onset_fraction)
    t = np.sqrt(max_fraction / safe)
    value = coefficient / (2.0 * safe * (t - 1.0) ** 4) * (s + 4.0 * t * (s - 1.0) / (t - 1.0))
    return np.where(v <= onset_fraction, 0.0, value)


@dataclass(frozen=True)
class BundleCompaction:
    """Guarded Cai–Gutowski compaction of one tow family, from its as-woven fraction V_f0.

    Moduli and stresses in Pa, fractions dimensionless, ``coupling_compliance`` F_bl in 1/Pa.
    """

    fibre_modulus: float
    span_to_height: float
    initial_fraction: float
    onset_fraction: float
    max_fraction: float = SQUARE_PACKING
    coupling_compliance: float = 0.0
    packing_margin: float = 1e-3
    cap_fraction: float = field(init=False)

    def __post_init__(self) -> None:
        import numpy as np

        if not 0.0 < self.onset_fraction < self.max_fraction:
            raise ValueError("need 0 < V_o < V_a")
        if not 0.0 < self.packing_margin < 1.0:
            raise ValueError("packing_margin must lie in (0, 1)")
        cap = self.max_fraction * (1.0 - self.packing_margin)
        if not cap < self.max_fraction:
            # A margin below the float resolution puts the cap on the pole: σ and its slope
            # there are infinite, so the "guarded" torque would be inf past the cap.
            raise ValueError(
                f"packing_margin {self.packing_margin:g} is too small to keep the cap below "
                f"V_a = {self.max_fraction:g} in floating point"
            )
        if not 0.0 < self.initial_fraction < cap:
            raise ValueError(
                f"as-woven tow fraction {self.initial_fraction:.3f} must lie in (0, {cap:.3f})"
            )
        if self.coupling_compliance != 0.0:
            grid = np.linspace(self.initial_fraction, cap, 4001)
            ok = self._denominator(grid) >= 0.1
            if not np.all(ok):
                first_bad = int(np.argmin(ok))
                if first_bad == 0:
                    raise ValueError(
                        "coupling_compliance is so large that the Cai–Gutowski denominator "
                        "F_bb·F11 − F_bl² is not positive at the as-woven fraction"
                    )
                # The cap is the last fraction where the denominator is still ≥ 10 %: the
                # first grid point past it may lie beyond its zero, where σ_b's slope is
                # negative or unbounded and the torque turns to noise. Bisect the crossing.
                good, bad = float(grid[first_bad - 1]), float(grid[first_bad])
                for _ in range(60):
                    mid = 0.5 * (good + bad)
                    if self._denominator(np.asarray(mid)) >= 0.1:
                        good = mid
                    else:
                        bad = mid
                cap = good
            cap = max(cap, self.initial_fraction * (1 + 1e-9))
        object.__setattr__(self, "cap_fraction", cap)

    @property
    def coefficient(self) -> float:
        """Gutowski's A_s [Pa]."""
        return gutowski_coefficient(self.fibre_modulus, self.span_to_height)

    def _gutowski_slope(self, v: FloatArray) -> FloatArray:
        return gutowski_stiffness(v, self.coefficient, self.onset_fraction, self.max_fraction)

    def _denominator(self, v: FloatArray) -> FloatArray:
        # F_bb − F_bl²/F11, relative to F_bb: 1 − F_bl² E_f V σ'(V) V² / V_f0.
        import numpy as np

        slope = self._gutowski_slope(v)
        return np.asarray(
            1.0
            - self.coupling_compliance**2
            * self.fibre_modulus
            * v**3
            * slope
            / self.initial_fraction,
            dtype=float,
        )

    def _bundle_slope(self, v: FloatArray) -> FloatArray:
        """dσ_b/dV_f [Pa] below the cap."""
        import numpy as np

        return np.asarray(self._gutowski_slope(v) / self._denominator(v), dtype=float)

    def _uncapped(self, v: FloatArray) -> FloatArray:
        import numpy as np

        if self.coupling_compliance == 0.0:
            args = (self.coefficient, self.onset_fraction, self.max_fraction)
            return np.asarray(
                gutowski_stress(v, *args) - gutowski_stress(self.initial_fraction, *args),
                dtype=float,
            )
        lo = self.initial_fraction
        half = 0.5 * (v - lo)
        nodes, weights = _gauss_legendre()
        points = (0.5 * (v + lo))[..., None] + half[..., None] * nodes
        return np.asarray(half * (self._bundle_slope(points) @ weights), dtype=float)

    def stress(self, volume_fraction: ArrayLike) -> FloatArray:
        """Compaction stress σ_b [Pa] ≥ 0 added over the as-woven state at fraction V_f."""
        import numpy as np

        v = np.maximum(np.asarray(volume_fraction, dtype=float), self.initial_fraction)
        cap = self.cap_fraction
        inside = np.minimum(v, cap)
        at_cap = float(self._uncapped(np.asarray(cap)))
        slope_cap = float(self._bundle_slope(np.asarray(cap)))
        value = np.where(v <= cap, self._uncapped(inside), at_cap + slope_cap * (v - cap))
        return np.maximum(value, 0.0)
