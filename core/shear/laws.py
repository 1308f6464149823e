"""Generic shear laws: two-sense composition, ``polynomial`` and ``tabulated`` (not fabric-specific).

Every law here is a ``SignedShearLaw``: one branch (``preform.shear.energy``) per sense of shear,
torque C(γ) = +M₊(γ) for γ ≥ 0 and −M₋(|γ|) for γ < 0, energy W(γ) = ∫_0^γ C ≥ 0. A law given
one branch only is symmetric, C(−γ) = −C(γ).

Both data-driven laws are written in the shear angle in **degrees** (as measured curves are) and
in either normalised picture-frame force F_s/L [N/mm] or torque per area C [N·m/m²]; a force is
turned into torque with C = 1000·(F_s/L)·cos γ (picture-frame power balance). Beyond the fitted
range the law follows ``beyond_range``: ``hold`` keeps the measured quantity at its value at the
end of the range, ``linear`` continues along the tangent there, ``extrapolate`` (polynomial only)
evaluates the polynomial as it is. In every case a torque that would come out negative is set to
zero (a fabric does not drive its own shear), and the energy is integrated exactly over the
clipped curve.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Literal, Self

import numpy as np
from numpy.polynomial import polynomial as npoly
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator
from scipy.interpolate import PchipInterpolator

from preform.shear.energy import DOMAIN_END, Branch, PiecewiseBranch
from preform.shear.law import ShearLaw

FloatArray = NDArray[np.float64]

#: N/mm of picture-frame force per unit length → N/m, the unit of torque per area.
N_PER_MM_TO_N_PER_M = 1000.0

BeyondRange = Literal["hold", "linear", "extrapolate"]


class SignedShearLaw:
    """A ``ShearLaw`` from a positive-sense branch and an optional negative-sense branch.

    ``positive`` gives the torque magnitude for γ > 0 (parallel to the reference direction /
    stitch), ``negative`` for γ < 0; without ``negative`` the law is symmetric. Angles [rad],
    torque [N·m/m²], energy [J/m²].
    """

    def __init__(
        self,
        positive: Branch,
        negative: Branch | None = None,
        locking_angle: float | None = None,
        failure_angle: float | None = None,
    ) -> None:
        self.positive = positive
        self.negative = negative if negative is not None else positive
        self.symmetric = negative is None
        self.locking_angle = locking_angle
        self.failure_angle = failure_angle

    def torque(self, gamma: ArrayLike) -> FloatArray:
        """Torque per unit undeformed area C(γ) [N·m/m²] at signed shear angles γ [rad]."""
        g = np.asarray(gamma, dtype=float)
        u = np.abs(g)
        if self.symmetric:
            return np.asarray(np.sign(g) * self.positive.magnitude(u), dtype=float)
        # At γ = 0 exactly the torque is 0 in both cases (a friction law steps from −C0 to +C0);
        # 0·γ rather than 0 so that a NaN angle gives a NaN torque, as the symmetric law does.
        return np.where(
            g > 0.0,
            self.positive.magnitude(u),
            np.where(g < 0.0, -self.negative.magnitude(u), 0.0 * g),
        )

    def energy(self, gamma: ArrayLike) -> FloatArray:
        """Strain energy per unit undeformed area W(γ) = ∫_0^γ C [J/m²], W ≥ 0."""
        g = np.asarray(gamma, dtype=float)
        u = np.abs(g)
        if self.symmetric:
            return np.asarray(self.positive.energy(u), dtype=float)
        return np.where(g >= 0.0, self.positive.energy(u), self.negative.energy(u))


# -- polynomial -------------------------------------------------------------------------------


def degree_polynomial_to_radians(coefficients_per_deg: ArrayLike) -> FloatArray:
    """Ascending coefficients a_k of a polynomial in γ [deg] → the same polynomial in γ [rad]."""
    a = np.atleast_1d(np.asarray(coefficients_per_deg, dtype=float))
    return np.asarray(a * (180.0 / math.pi) ** np.arange(a.size), dtype=float)


def polynomial_branch(
    coefficients_per_deg: ArrayLike,
    max_angle_deg: float,
    beyond_range: BeyondRange,
    quantity: Literal["force", "torque"],
) -> PiecewiseBranch:
    """One sense of a polynomial law, exact energy.

    ``coefficients_per_deg``: ascending powers of the shear-angle magnitude in degrees; the value
    is F_s/L [N/mm] for ``quantity="force"`` or C [N·m/m²] for ``"torque"``. ``max_angle_deg``:
    end of the fitted range [deg].
    """
    p = degree_polynomial_to_radians(coefficients_per_deg)
    if quantity == "force":
        p = p * N_PER_MM_TO_N_PER_M
    end = math.radians(max_angle_deg)
    if beyond_range == "extrapolate" or end >= DOMAIN_END:
        pieces: list[FloatArray] = [p]
        breaks = [0.0]
    else:
        value = float(npoly.polyval(end, p))
        if beyond_range == "hold":
            tail = np.array([value])
        else:
            tail = np.array([value, float(npoly.polyval(end, npoly.polyder(p)))])
        pieces, breaks = [p, tail], [0.0, end]
    return PiecewiseBranch(breaks, pieces, weight="cos" if quantity == "force" else "one")


def _check_coefficients(values: list[float] | None, name: str) -> None:
    if values is not None and (not values or not all(math.isfinite(v) for v in values)):
        raise ValueError(f"{name}: give at least one finite coefficient")


class PolynomialParams(BaseModel):
    """Parameters of the ``polynomial`` shear law (YAML ``shear_law`` block)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    law: Literal["polynomial"] = Field(description="Selects the polynomial shear law.")
    force_coefficients_N_per_mm: list[float] | None = Field(
        default=None,
        description=(
            "F_s/L [N/mm] = Σ a_k·(γ/deg)^k, ascending powers from k = 0, for γ ≥ 0 (and for "
            "γ < 0 at |γ| unless a negative-sense polynomial is given). a_k in N/mm/deg^k."
        ),
    )
    torque_coefficients_N_per_m: list[float] | None = Field(
        default=None,
        description=(
            "Alternative to the force polynomial: torque per area C [N·m/m²] = Σ a_k·(γ/deg)^k."
        ),
    )
    force_coefficients_negative_N_per_mm: list[float] | None = Field(
        default=None,
        description="F_s/L [N/mm] for γ < 0 as a polynomial in |γ| [deg]; makes the law asymmetric.",
    )
    torque_coefficients_negative_N_per_m: list[float] | None = Field(
        default=None,
        description="C [N·m/m²] for γ < 0 as a polynomial in |γ| [deg]; makes the law asymmetric.",
    )
    max_angle_deg: float = Field(
        gt=0.0, le=90.0, description="End of the fitted range for γ ≥ 0 [deg]."
    )
    max_angle_negative_deg: float | None = Field(
        default=None, gt=0.0, le=90.0, description="End of the fitted range for γ < 0 [deg]."
    )
    beyond_range: BeyondRange = Field(
        default="hold",
        description="Past the fitted range: hold the value, continue the tangent, or extrapolate.",
    )
    locking_angle_deg: float | None = Field(
        default=None, gt=0.0, lt=90.0, description="Locking (wrinkling) angle [deg], if known."
    )
    failure_angle_deg: float | None = Field(
        default=None, gt=0.0, lt=90.0, description="Stitch-failure angle, γ > 0 [deg], if any."
    )

    @model_validator(mode="after")
    def _one_quantity(self) -> Self:
        force = (self.force_coefficients_N_per_mm, self.force_coefficients_negative_N_per_mm)
        torque = (self.torque_coefficients_N_per_m, self.torque_coefficients_negative_N_per_m)
        if (force[0] is None) == (torque[0] is None):
            raise ValueError(
                "give exactly one of force_coefficients_N_per_mm, torque_coefficients_N_per_m"
            )
        if (force[0] is None and force[1] is not None) or (
            torque[0] is None and torque[1] is not None
        ):
            raise ValueError("the negative-sense polynomial must use the same quantity")
        for name in type(self).model_fields:
            if "coefficients" in name:
                _check_coefficients(getattr(self, name), name)
        return self


def _radians_or_none(deg: float | None) -> float | None:
    return None if deg is None else math.radians(deg)


def build_polynomial(params: PolynomialParams, fabric: Any = None) -> ShearLaw:
    """Build a ``polynomial`` law (``fabric`` unused)."""
    if params.force_coefficients_N_per_mm is not None:
        quantity: Literal["force", "torque"] = "force"
        pos, neg = params.force_coefficients_N_per_mm, params.force_coefficients_negative_N_per_mm
    else:
        quantity = "torque"
        pos = params.torque_coefficients_N_per_m or [0.0]
        neg = params.torque_coefficients_negative_N_per_m
    positive = polynomial_branch(pos, params.max_angle_deg, params.beyond_range, quantity)
    negative = None
    if neg is not None:
        end = params.max_angle_negative_deg or params.max_angle_deg
        negative = polynomial_branch(neg, end, params.beyond_range, quantity)
    return SignedShearLaw(
        positive,
        negative,
        locking_angle=_radians_or_none(params.locking_angle_deg),
        failure_angle=_radians_or_none(params.failure_angle_deg),
    )


# -- tabulated --------------------------------------------------------------------------------


def tabulated_branch(
    angle_deg: ArrayLike,
    values: ArrayLike,
    beyond_range: Literal["hold", "linear"],
    quantity: Literal["force", "torque"],
) -> PiecewiseBranch:
    """One sense of a tabulated law: PCHIP through (angle [deg], F_s/L [N/mm] or C [N·m/m²]).

    PCHIP is shape preserving (no overshoot between points, monotone data stay monotone), so
    non-negative data give a non-negative curve. A point (0, 0) is added when the first angle is
    above zero: the fabric is unloaded in its undeformed state.
    """
    a = np.asarray(angle_deg, dtype=float)
    v = np.asarray(values, dtype=float)
    if a[0] > 0.0:
        a, v = np.concatenate([[0.0], a]), np.concatenate([[0.0], v])
    scale = N_PER_MM_TO_N_PER_M if quantity == "force" else 1.0
    radians = np.radians(a)
    interpolant = PchipInterpolator(radians, v * scale, extrapolate=False)
    # scipy stores each cubic piece with descending powers in the local variable.
    pieces: list[FloatArray] = [np.asarray(c[::-1], dtype=float) for c in interpolant.c.T]
    breaks = list(radians[:-1])
    end = float(radians[-1])
    if end < DOMAIN_END:
        last = float(v[-1] * scale)
        if beyond_range == "hold":
            pieces.append(np.array([last]))
        else:
            pieces.append(np.array([last, float(interpolant.derivative()(end - 1e-12))]))
        breaks.append(end)
    return PiecewiseBranch(breaks, pieces, weight="cos" if quantity == "force" else "one")


class TabulatedParams(BaseModel):
    """Parameters of the ``tabulated`` shear law (YAML ``shear_law`` block)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    law: Literal["tabulated"] = Field(description="Selects the tabulated shear law.")
    angle_deg: list[float] = Field(
        min_length=2, description="Shear angles [deg], strictly ascending, 0 ≤ γ ≤ 90, γ ≥ 0."
    )
    force_N_per_mm: list[float] | None = Field(
        default=None, description="Normalised picture-frame force F_s/L [N/mm] at angle_deg."
    )
    torque_N_per_m: list[float] | None = Field(
        default=None, description="Alternatively, torque per area C [N·m/m²] at angle_deg."
    )
    angle_negative_deg: list[float] | None = Field(
        default=None,
        description="Shear-angle magnitudes [deg] of a separate table for γ < 0 (asymmetric law).",
    )
    force_negative_N_per_mm: list[float] | None = Field(
        default=None, description="F_s/L [N/mm] for γ < 0 at angle_negative_deg."
    )
    torque_negative_N_per_m: list[float] | None = Field(
        default=None, description="C [N·m/m²] for γ < 0 at angle_negative_deg."
    )
    beyond_range: Literal["hold", "linear"] = Field(
        default="hold", description="Past the last point: hold its value or continue its tangent."
    )
    locking_angle_deg: float | None = Field(
        default=None, gt=0.0, lt=90.0, description="Locking (wrinkling) angle [deg], if known."
    )
    failure_angle_deg: float | None = Field(
        default=None, gt=0.0, lt=90.0, description="Stitch-failure angle, γ > 0 [deg], if any."
    )

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        if (self.force_N_per_mm is None) == (self.torque_N_per_m is None):
            raise ValueError("give exactly one of force_N_per_mm, torque_N_per_m")
        _check_table(self.angle_deg, self.force_N_per_mm or self.torque_N_per_m, "angle_deg")
        neg_values = (
            self.force_negative_N_per_mm
            if self.force_N_per_mm is not None
            else self.torque_negative_N_per_m
        )
        other = (
            self.torque_negative_N_per_m
            if self.force_N_per_mm is not None
            else self.force_negative_N_per_mm
        )
        if other is not None:
            raise ValueError("the negative-sense table must use the same quantity")
        if (self.angle_negative_deg is None) != (neg_values is None):
            raise ValueError("give angle_negative_deg together with its values")
        if self.angle_negative_deg is not None and neg_values is not None:
            _check_table(self.angle_negative_deg, neg_values, "angle_negative_deg")
        return self


def _check_table(angles: list[float], values: list[float] | None, name: str) -> None:
    if values is None or len(values) != len(angles):
        raise ValueError(f"{name}: one value per angle")
    a = np.asarray(angles)
    if not np.all(np.isfinite(a)) or not np.all(np.isfinite(values)):
        raise ValueError(f"{name}: values must be finite")
    if a[0] < 0.0 or a[-1] > 90.0 or np.any(np.diff(a) <= 0.0):
        raise ValueError(f"{name}: angles must be strictly ascending within [0, 90] deg")
    if min(values) < 0.0:
        raise ValueError(f"{name}: forces/torques are magnitudes in their sense, ≥ 0")


def build_tabulated(params: TabulatedParams, fabric: Any = None) -> ShearLaw:
    """Build a ``tabulated`` law (``fabric`` unused)."""
    quantity: Literal["force", "torque"] = "force" if params.force_N_per_mm else "torque"
    values = params.force_N_per_mm or params.torque_N_per_m or []
    positive = tabulated_branch(params.angle_deg, values, params.beyond_range, quantity)
    negative = None
    neg_values = params.force_negative_N_per_mm or params.torque_negative_N_per_m
    if params.angle_negative_deg is not None and neg_values is not None:
        negative = tabulated_branch(
            params.angle_negative_deg, neg_values, params.beyond_range, quantity
        )
    return SignedShearLaw(
        positive,
        negative,
        locking_angle=_radians_or_none(params.locking_angle_deg),
        failure_angle=_radians_or_none(params.failure_angle_deg),
    )


#: (law name, params model, builder) for the registry.
SHEAR_LAWS: list[tuple[str, type[BaseModel], Callable[[Any, Any], ShearLaw]]] = [
    ("polynomial", PolynomialParams, build_polynomial),
    ("tabulated", TabulatedParams, build_tabulated),
]
