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
* A polynomial that comes out negative *inside* its fitted range is refused when the
  parameters are validated (parallel on [0, failure or end], post-failure on [failure, end],
  perpendicular on [0, its end], the failure drop itself): that is a bad fit, not a fabric.
* The drop is handed to the energy integration as sub-pieces, each expanded about its own start
  (``DROP_PIECES``). As one piece over the whole drop, a steep P₁ (extrapolated past the failure
  angle) and the blend towards P₂ give large high-order coefficients that cancel, and every value
  computed from them carries that cancellation's rounding. (It made W fall at the end of the drop
  while the energy was the closed form p − p″ + p⁗ − … against sin and cos; the energy's series
  form in ``preform.shear.energy`` no longer cancels, and the sub-pieces keep each piece's
  coefficients near the size of the force itself.)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

from pydantic import BaseModel, Field, model_validator

from preform.material import ParamsModel, Plausible
from preform.shear.energy import DOMAIN_END, PiecewiseBranch, shifted_polynomial
from preform.shear.law import ShearLaw
from preform.shear.laws import (
    EXTREMES_GRID,
    FAILURE_ANGLE,
    FIT_END,
    LOCKING_ANGLE,
    N_PER_MM_TO_N_PER_M,
    BeyondRange,
    Coefficients,
    SignedShearLaw,
    degree_polynomial_to_radians,
    force_peak,
    negative_law_error,
    negative_stretch,
    polynomial_branch,
    polynomial_extremes,
    polynomial_value,
    raise_located,
)

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np

_COEFFICIENTS = "ascending powers of the shear-angle magnitude in degrees; a_k in N/mm/deg^k"

#: Sub-pieces the failure drop is integrated in (module docstring): each spans 1/8 of the drop,
#: so a term of degree k of its local expansion is 8^k times smaller than over the whole drop.
DROP_PIECES = 8

FAILURE_WIDTH = Plausible(
    0.01,
    45.0,
    "deg",
    "the width of the stitch-failure drop",
    "a stitch gives way over 1–10°; narrower than 0.01° is a step no test resolves, wider than "
    "45° is no drop",
)


def _parallel_peak(coefficients: list[float], model: Any) -> float:
    """Largest F_s/L [N/mm] of the pre-failure polynomial over the range it is used on."""
    end = model.failure_angle_deg if model.failure_angle_deg is not None else model.max_angle_deg
    return polynomial_extremes(coefficients, 0.0, end)[2]


def _post_failure_peak(coefficients: list[float], model: Any) -> float | None:
    """Largest F_s/L [N/mm] of the post-failure polynomial from the failure angle to the end."""
    if model.failure_angle_deg is None:
        return None
    return polynomial_extremes(coefficients, model.failure_angle_deg, model.max_angle_deg)[2]


def _force_rule(measure: Any, where: str) -> Plausible:
    base = force_peak("max_angle_deg")
    return Plausible(
        base.low, base.high, base.unit, f"{base.what} {where}", base.reason, measure=measure
    )


class StitchPolynomialParams(ParamsModel):
    """Parameters of the warp-knit ``stitch_polynomial`` law (YAML ``shear_law`` block)."""

    law: Literal["stitch_polynomial"] = Field(description="Selects this law.")
    parallel_force_coefficients_N_per_mm: Annotated[
        Coefficients, _force_rule(_parallel_peak, "(parallel, up to stitch failure)")
    ] = Field(
        min_length=1,
        description=f"F_s/L [N/mm] shearing parallel to the stitch (γ > 0), {_COEFFICIENTS}.",
    )
    perpendicular_force_coefficients_N_per_mm: Annotated[
        Coefficients, force_peak("max_angle_perpendicular_deg", "max_angle_deg")
    ] = Field(
        min_length=1,
        description=f"F_s/L [N/mm] shearing perpendicular to the stitch (γ < 0), {_COEFFICIENTS}.",
    )
    max_angle_deg: Annotated[float, FIT_END] = Field(
        gt=0.0, le=90.0, description="End of the fitted range, parallel sense [deg]."
    )
    max_angle_perpendicular_deg: Annotated[float | None, FIT_END] = Field(
        default=None,
        gt=0.0,
        le=90.0,
        description="End of the fitted range, perpendicular sense [deg]; default max_angle_deg.",
    )
    failure_angle_deg: Annotated[float | None, FAILURE_ANGLE] = Field(
        default=None, gt=0.0, lt=90.0, description="Stitch-failure angle, parallel sense [deg]."
    )
    failure_width_deg: Annotated[float, FAILURE_WIDTH] = Field(
        default=5.0,
        gt=0.0,
        description="Angular width [deg] over which the force falls to the post-failure branch.",
    )
    post_failure_force_coefficients_N_per_mm: Annotated[
        Coefficients | None, _force_rule(_post_failure_peak, "(after stitch failure)")
    ] = Field(
        default=None,
        description=f"F_s/L [N/mm] after stitch failure (parallel sense), {_COEFFICIENTS}.",
    )
    beyond_range: BeyondRange = Field(
        default="hold",
        description="Past the fitted range: hold the force, continue its tangent, or extrapolate.",
    )
    locking_angle_deg: Annotated[float | None, LOCKING_ANGLE] = Field(
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
        raise_located(type(self).__name__, self._negative_stretches())
        return self

    def _negative_stretches(self) -> list[Any]:
        """A located error per polynomial that is negative inside the range where it is used."""
        end = self.max_angle_deg
        failure = self.failure_angle_deg
        post = self.post_failure_force_coefficients_N_per_mm
        checks: list[tuple[str, list[float], float, float]] = [
            (
                "parallel_force_coefficients_N_per_mm",
                self.parallel_force_coefficients_N_per_mm,
                0.0,
                failure if failure is not None else end,
            ),
            (
                "perpendicular_force_coefficients_N_per_mm",
                self.perpendicular_force_coefficients_N_per_mm,
                0.0,
                self.max_angle_perpendicular_deg or end,
            ),
        ]
        if failure is not None and post is not None:
            checks.append(("post_failure_force_coefficients_N_per_mm", post, failure, end))
        errors = []
        for name, coefficients, start, stop in checks:
            stretch = negative_stretch(coefficients, start, stop)
            if stretch is not None:
                errors.append(negative_law_error(name, coefficients, "force", stretch, start, stop))
        if not errors and failure is not None and post is not None:
            stretch = self._negative_drop()
            if stretch is not None:
                errors.append(
                    negative_law_error(
                        "failure_width_deg",
                        [self.failure_width_deg],
                        "force",
                        stretch,
                        failure,
                        failure + self.failure_width_deg,
                    )
                )
        return errors

    def _negative_drop(self) -> tuple[float, float] | None:
        """Where the drop F = P₁ + s·(P₂ − P₁) is most negative [N/mm, deg], if it is: P₁
        extrapolated past the failure angle may turn negative inside the drop."""
        assert self.failure_angle_deg is not None
        assert self.post_failure_force_coefficients_N_per_mm is not None
        # Plain Python (validation runs when a library is listed, without numpy): the same
        # 513-point grid and the same operations as numpy's linspace and polyval.
        start, width = self.failure_angle_deg, self.failure_width_deg
        last = EXTREMES_GRID - 1
        fractions = [k * (1.0 / last) for k in range(last)] + [1.0]
        angles = [start + width * f for f in fractions]
        force = []
        for angle in angles:
            t = (angle - start) / width
            smooth = t * t * (3.0 - 2.0 * t)
            p1 = polynomial_value(self.parallel_force_coefficients_N_per_mm, angle)
            p2 = polynomial_value(self.post_failure_force_coefficients_N_per_mm, angle)
            force.append(p1 + smooth * (p2 - p1))
        k = min(range(len(force)), key=force.__getitem__)
        scale = max(abs(f) for f in force)
        return (force[k], angles[k]) if force[k] < -1e-9 * scale else None


def parallel_branch(params: StitchPolynomialParams) -> PiecewiseBranch:
    """The parallel-sense (γ > 0) branch: pre-failure, smoothstep drop, post-failure, tail."""
    import numpy as np
    from numpy.polynomial import polynomial as npoly

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
    pieces: list[np.ndarray] = [before]
    breaks = [0.0]
    for k in range(DROP_PIECES):
        # Each sub-piece is built from P₁, P₂ and s expanded about its own start, never by
        # shifting an expansion of the whole drop (which would carry its cancellation along).
        offset = width * k / DROP_PIECES
        p1, p2 = (
            shifted_polynomial(before, start + offset),
            shifted_polynomial(after, start + offset),
        )
        s = shifted_polynomial(step, offset)
        piece = npoly.polyadd(p1, npoly.polymul(s, npoly.polysub(p2, p1)))
        pieces.append(np.asarray(piece, dtype=float))
        breaks.append(start + offset)
    if params.beyond_range == "extrapolate" or end_fit >= DOMAIN_END:
        pieces.append(shifted_polynomial(after, end_drop))
        breaks.append(end_drop)
    else:
        if end_fit > end_drop:
            pieces.append(shifted_polynomial(after, end_drop))
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
