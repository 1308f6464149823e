"""A tabulated surrogate of any shear law: the cheap evaluation a drape search wants.

Mechanistic laws (crossover friction + tow compaction) cost tens of milliseconds per net; a
search evaluates the energy of dozens of nets. The surrogate tabulates, once per sense of
shear, the exact strain energy W and its exact slope (the torque magnitude) on a grid of
angle magnitudes, and interpolates W between nodes with the cubic Hermite polynomial through
both. The grid always contains the law's locking, failure and jamming angles (where the torque's
slope may jump), is eight times finer over the 3° before the jamming angle (where compaction
stiffens W steeply), and each sense is tabulated separately (a friction law's torque steps at γ = 0).

Accuracy: for W with a bounded fourth derivative on each interval of width h the Hermite error
is at most h⁴/384 · max|W''''|. `max_relative_error` measures it against the exact law over
|γ| ≤ 60°, the range drapes use. Measured for the bundled laws at the default step of 0.25°: at
most 3e-7 of the largest W (woven laws, where compaction stiffens W; stitch polynomials about
1e-11), falling as h⁴; an energy evaluation then costs about what a polynomial law's does, a
tenth of the mechanistic law's (tests/shear/test_surrogate.py).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from preform.base.arrays import FloatArray
from preform.shear.law import ShearLaw

#: Width [rad] before a law's jamming angle over which the table is eight times finer.
_JAM_REFINED = math.radians(3.0)

#: Largest tabulated magnitude [rad]: the fibre families are parallel at 90°.
_DOMAIN_END = math.pi / 2
#: Offset [rad] at which the torque next to γ = 0 is read (a friction law steps there).
_NEXT_TO_ZERO = 1e-12


class _SenseTable:
    """W(u) and W'(u) = M(u) of one sense on a grid of magnitudes u [rad]."""

    def __init__(self, law: ShearLaw, nodes: FloatArray, sign: float) -> None:
        self.nodes = nodes
        self.energy = np.asarray(law.energy(sign * nodes), dtype=float)
        probe = np.where(nodes > 0, nodes, _NEXT_TO_ZERO)
        slope = np.abs(np.asarray(law.torque(sign * probe), dtype=float))
        # Per interval, the slopes at its two ends. Where W climbs by orders of magnitude
        # within one interval (compaction near 90°) exact slopes can make the cubic overshoot;
        # there the Fritsch–Carlson limit scales them so W stays monotone, as the law's is.
        secant = np.diff(self.energy) / np.diff(nodes)
        left, right = slope[:-1].copy(), slope[1:].copy()
        with np.errstate(divide="ignore", invalid="ignore"):
            a, b = left / secant, right / secant
            radius = np.hypot(a, b)
            limit = np.where((secant > 0) & (radius > 3.0), 3.0 / radius, 1.0)
        self.slope_left, self.slope_right = left * limit, right * limit

    def _locate(self, u: FloatArray) -> tuple[NDArray[np.intp], FloatArray, FloatArray]:
        u = np.clip(u, 0.0, self.nodes[-1])
        k = np.clip(np.searchsorted(self.nodes, u, side="right") - 1, 0, len(self.nodes) - 2)
        h = self.nodes[k + 1] - self.nodes[k]
        return k, (u - self.nodes[k]) / h, h

    def tables(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(W at the nodes [J/m²], limited slope at each interval's left and right end)."""
        return self.energy, self.slope_left, self.slope_right

    def slope(self, u: FloatArray) -> FloatArray:
        """dW/du [N·m/m²] of the interpolant (consistent with ``__call__``, for gradients)."""
        k, t, h = self._locate(u)
        t2 = t * t
        d00, d10 = 6 * t2 - 6 * t, 3 * t2 - 4 * t + 1
        d01, d11 = -6 * t2 + 6 * t, 3 * t2 - 2 * t
        dw = (
            d00 * self.energy[k]
            + d10 * h * self.slope_left[k]
            + d01 * self.energy[k + 1]
            + d11 * h * self.slope_right[k]
        ) / h
        beyond = np.abs(u) > self.nodes[-1]
        return np.where(beyond, 0.0, np.maximum(dw, 0.0))


class TabulatedSurrogate:
    """A ``ShearLaw`` that evaluates ``law``'s energy (and its slope, the torque) from tables.

    ``step_rad`` is the table spacing [rad]; the grid runs from 0 to 90° and also holds the
    law's locking, failure and jamming (``packing_angle``) angles.
    """

    def __init__(self, law: ShearLaw, step_rad: float = math.radians(0.25)) -> None:
        if not (0 < step_rad <= math.radians(10)):
            raise ValueError(f"table step must be in (0, 10°], got {math.degrees(step_rad)}°")
        self.law = law
        self.step_rad = float(step_rad)
        self.locking_angle = law.locking_angle
        self.failure_angle = law.failure_angle
        # a stitch that also breaks shearing the other way (stitch_yarn): the energy field
        # flags it from the law in hand, so the table must carry it
        self.failure_angle_negative = getattr(law, "failure_angle_negative", None)
        # and where the fabric wrinkles (preform.drape.judging.wrinkling): jammed, or the law's own
        self.packing_angle = getattr(law, "packing_angle", None)
        self.wrinkle_limits = tuple(getattr(law, "wrinkle_limits", None) or ())
        count = math.ceil(_DOMAIN_END / step_rad)
        grid = np.linspace(0.0, _DOMAIN_END, count + 1)
        special = [
            a
            # the jamming (packing) angle too: the torque is held from there, a kink
            for a in (
                law.locking_angle,
                law.failure_angle,
                self.failure_angle_negative,
                getattr(law, "packing_angle", None),
            )
            if a is not None and 0 < a < _DOMAIN_END
        ]
        # A law's further kinks (``kink_angles`` [rad]: e.g. where a woven law's tows reach
        # their own compaction limit and the lateral stress stops rising) are nodes too.
        kinks = [
            float(a)
            for a in getattr(law, "kink_angles", ())
            if a is not None and 0 < a < _DOMAIN_END
        ]
        special.extend(kinks)
        jam = getattr(law, "packing_angle", None)
        steep = kinks + ([jam] if jam is not None and 0 < jam < _DOMAIN_END else [])
        for end in steep:
            # Compaction stiffens W steeply just before the jam (or a kink where the stress
            # stops rising): 8× finer over the 3° before it, or from the locking angle where
            # compaction starts when that is earlier (measured, tests/shear/test_surrogate.py).
            width = _JAM_REFINED
            if law.locking_angle is not None and 0 < law.locking_angle < end:
                width = max(width, end - law.locking_angle)
            count = math.ceil(width / (step_rad / 8.0))
            fine = end - step_rad / 8.0 * np.arange(1, count + 1)
            special.extend(float(a) for a in fine if a > 0)
        # A friction law whose torque is mobilised over γ_m (``mobilisation_angle`` [rad],
        # the woven law's Dahl ramp) rises from zero within a few γ_m: nodes every γ_m/4 to
        # 6·γ_m when that layer is thinner than a few table steps.
        layer = float(getattr(law, "mobilisation_angle", 0.0) or 0.0)
        if 0.0 < layer < 4.0 * step_rad:
            special.extend(float(a) for a in np.linspace(0.0, 6.0 * layer, 25)[1:])
        nodes = np.unique(np.concatenate([grid, special]))
        # a special angle right next to a grid node would make a needle-thin interval
        keep = np.concatenate([[True], np.diff(nodes) > 1e-3 * step_rad])
        nodes = nodes[keep]
        self._positive = _SenseTable(law, nodes, 1.0)
        self._negative = _SenseTable(law, nodes, -1.0)

    @property
    def finite(self) -> bool:
        """Whether every tabulated energy and slope is finite (a law returning NaN or inf
        somewhere cannot be interpolated: use the law itself, which says where)."""
        return all(
            bool(np.isfinite(values).all())
            for table in (self._positive, self._negative)
            for values in (table.energy, table.slope_left, table.slope_right)
        )

    def torque(self, gamma: ArrayLike) -> FloatArray:
        """Torque per unit undeformed area [N·m/m²]: dW/dγ of the tabulated energy, so that
        gradient-based solvers see the energy they minimise (equal to the law's torque at the
        nodes, and to its accuracy between them)."""
        g = np.asarray(gamma, dtype=float)
        u = np.abs(g)
        return np.where(
            g > 0, self._positive.slope(u), np.where(g < 0, -self._negative.slope(u), 0.0 * g)
        )

    def energy(self, gamma: ArrayLike) -> FloatArray:
        """Strain energy per unit area [J/m²] from the tables, at signed angles γ [rad]: the
        cubic Hermite interpolant of the sense γ shears in (compiled:
        ``preform.shear.surrogate_kernels``)."""
        from preform.shear import surrogate_kernels

        g = np.asarray(gamma, dtype=float)
        flat = np.ascontiguousarray(g).reshape(-1)
        values = np.empty(flat.shape)
        surrogate_kernels.signed_energy(
            self._positive.nodes, self._positive.tables(), self._negative.tables(), flat, values
        )
        return values.reshape(g.shape)

    def max_relative_error(
        self, max_angle_rad: float = math.radians(60), samples: int = 20001
    ) -> float:
        """Largest |W_table − W_exact| / max W_exact over both senses for |γ| up to
        ``max_angle_rad`` [rad] (the range drapes use), on a dense grid."""
        g = np.linspace(-max_angle_rad, max_angle_rad, samples)
        exact = np.asarray(self.law.energy(g), dtype=float)
        scale = max(float(np.max(np.abs(exact))), 1e-300)
        return float(np.max(np.abs(self.energy(g) - exact)) / scale)


def surrogate(law: ShearLaw, step_deg: float | None) -> Any:
    """``law`` itself when ``step_deg`` is None, else its tabulated surrogate."""
    return law if step_deg is None else TabulatedSurrogate(law, math.radians(step_deg))
