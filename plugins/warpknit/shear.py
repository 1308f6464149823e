"""The warp-knit ``stitch_polynomial`` shear law: one polynomial per sense, stitch failure [P].

Paper §"Energy approach": ±45° warp-knits need much more force to shear *parallel* to the stitch
(fabric lengthens along the stitch, stitch in tension: γ > 0 in preform's convention) than
*perpendicular* (stitch slack: γ < 0); the chain-stitched fabric's parallel curve peaks when the
stitching thread fails, falls, then rises again with inter-tow compaction. The paper fitted a
polynomial to each measured curve; this law does the same.

Shape and policy [C]:

* Each sense is a polynomial in F_s/L [N/mm] of the shear-angle magnitude in degrees, turned
  into torque with C = 1000·(F_s/L)·cos γ, so the energy is integrated exactly.
* Stitch failure (parallel sense only): from ``failure_angle_deg`` the force passes over
  ``failure_width_deg`` from the pre-failure polynomial P₁ to a post-failure polynomial P₂ along
  a cubic smoothstep s (value and slope continuous): F = P₁ + s·(P₂ − P₁). The force therefore
  keeps rising for a fraction of a degree after the failure angle before it falls; the
  post-failure polynomial carries the later rise from inter-tow compaction.
* Beyond the fitted range the last polynomial follows ``beyond_range`` (hold, tangent or the
  polynomial itself) and a force that would come out negative is set to zero.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Literal, Self

import numpy as np
from numpy.polynomial import polynomial as npoly
from pydantic import BaseModel, ConfigDict, Field, model_validator

from preform.shear.energy import DOMAIN_END, PiecewiseBranch
from preform.shear.law import ShearLaw
from preform.shear.laws import (
    N_PER_MM_TO_N_PER_M,
    BeyondRange,
    SignedShearLaw,
    degree_polynomial_to_radians,
    polynomial_branch,
)

_COEFFICIENTS = "ascending powers of the shear-angle magnitude in degrees; a_k in N/mm/deg^k"


class StitchPolynomialParams(BaseModel):
    """Parameters of the warp-knit ``stitch_polynomial`` law (YAML ``shear_law`` block)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    law: Literal["stitch_polynomial"] = Field(description="Selects this law.")
    parallel_force_coefficients_N_per_mm: list[float] = Field(
        min_length=1,
        description=f"F_s/L [N/mm] shearing parallel to the stitch (γ > 0), {_COEFFICIENTS}.",
    )
    perpendicular_force_coefficients_N_per_mm: list[float] = Field(
        min_length=1,
        description=f"F_s/L [N/mm] shearing perpendicular to the stitch (γ < 0), {_COEFFICIENTS}.",
    )
    max_angle_deg: float = Field(
        gt=0.0, le=90.0, description="End of the fitted range, parallel sense [deg]."
    )
    max_angle_perpendicular_deg: float | None = Field(
        default=None,
        gt=0.0,
        le=90.0,
        description="End of the fitted range, perpendicular sense [deg]; default max_angle_deg.",
    )
    failure_angle_deg: float | None = Field(
        default=None, gt=0.0, lt=90.0, description="Stitch-failure angle, parallel sense [deg]."
    )
    failure_width_deg: float = Field(
        default=5.0,
        gt=0.0,
        description="Angular width [deg] over which the force falls to the post-failure branch.",
    )
    post_failure_force_coefficients_N_per_mm: list[float] | None = Field(
        default=None,
        description=f"F_s/L [N/mm] after stitch failure (parallel sense), {_COEFFICIENTS}.",
    )
    beyond_range: BeyondRange = Field(
        default="hold",
        description="Past the fitted range: hold the force, continue its tangent, or extrapolate.",
    )
    locking_angle_deg: float | None = Field(
        default=None, gt=0.0, lt=90.0, description="Locking (wrinkling) angle [deg], if known."
    )

    @model_validator(mode="after")
    def _failure_consistent(self) -> Self:
        has_failure = self.failure_angle_deg is not None
        if has_failure != (self.post_failure_force_coefficients_N_per_mm is not None):
            raise ValueError(
                "give failure_angle_deg and post_failure_force_coefficients_N_per_mm together"
            )
        if self.failure_angle_deg is not None:
            if self.failure_angle_deg + self.failure_width_deg > self.max_angle_deg:
                raise ValueError("the failure drop must end inside the fitted range")
        coefficient_lists = (
            self.parallel_force_coefficients_N_per_mm,
            self.perpendicular_force_coefficients_N_per_mm,
            self.post_failure_force_coefficients_N_per_mm or [0.0],
        )
        if not all(math.isfinite(c) for cs in coefficient_lists for c in cs):
            raise ValueError("coefficients must be finite")
        return self


def _shifted(coef_rad: np.ndarray, origin: float) -> np.ndarray:
    """Coefficients of p(x + origin), ascending powers."""
    out = np.zeros(1)
    for c in coef_rad[::-1]:
        out = npoly.polyadd(npoly.polymul(out, [origin, 1.0]), [c])
    return np.asarray(out, dtype=float)


def parallel_branch(params: StitchPolynomialParams) -> PiecewiseBranch:
    """The parallel-sense (γ > 0) branch: pre-failure, smoothstep drop, post-failure, tail."""
    if params.failure_angle_deg is None or params.post_failure_force_coefficients_N_per_mm is None:
        return polynomial_branch(
            params.parallel_force_coefficients_N_per_mm,
            params.max_angle_deg,
            params.beyond_range,
            "force",
        )
    scale = N_PER_MM_TO_N_PER_M
    before = degree_polynomial_to_radians(params.parallel_force_coefficients_N_per_mm) * scale
    after = degree_polynomial_to_radians(params.post_failure_force_coefficients_N_per_mm) * scale
    start = math.radians(params.failure_angle_deg)
    width = math.radians(params.failure_width_deg)
    end_drop = start + width
    end_fit = math.radians(params.max_angle_deg)
    # Smoothstep s(x) = 3(x/w)² − 2(x/w)³ on the drop, x measured from the failure angle.
    step = np.array([0.0, 0.0, 3.0 / width**2, -2.0 / width**3])
    p1, p2 = _shifted(before, start), _shifted(after, start)
    drop = npoly.polyadd(p1, npoly.polymul(step, npoly.polysub(p2, p1)))
    pieces: list[np.ndarray] = [before, np.asarray(drop, dtype=float)]
    breaks = [0.0, start]
    if params.beyond_range == "extrapolate" or end_fit >= DOMAIN_END:
        pieces.append(_shifted(after, end_drop))
        breaks.append(end_drop)
    else:
        if end_fit > end_drop:
            pieces.append(_shifted(after, end_drop))
            breaks.append(end_drop)
        value = float(npoly.polyval(end_fit, after))
        slope = float(npoly.polyval(end_fit, npoly.polyder(after)))
        tail = np.array([value]) if params.beyond_range == "hold" else np.array([value, slope])
        pieces.append(tail)
        breaks.append(end_fit)
    return PiecewiseBranch(breaks, pieces, weight="cos")


def build_stitch_polynomial(params: StitchPolynomialParams, fabric: Any = None) -> SignedShearLaw:
    """Build the asymmetric warp-knit law (``fabric`` unused)."""
    perpendicular = polynomial_branch(
        params.perpendicular_force_coefficients_N_per_mm,
        params.max_angle_perpendicular_deg or params.max_angle_deg,
        params.beyond_range,
        "force",
    )
    return SignedShearLaw(
        parallel_branch(params),
        perpendicular,
        locking_angle=None
        if params.locking_angle_deg is None
        else math.radians(params.locking_angle_deg),
        failure_angle=None
        if params.failure_angle_deg is None
        else math.radians(params.failure_angle_deg),
    )


#: (law name, params model, builder) for the registry.
SHEAR_LAWS: list[tuple[str, type[BaseModel], Callable[[Any, Any], ShearLaw]]] = [
    ("stitch_polynomial", StitchPolynomialParams, build_stitch_polynomial)
]
