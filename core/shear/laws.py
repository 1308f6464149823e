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

import functools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

from pydantic import BaseModel, Field, model_validator
from pydantic_core import InitErrorDetails, PydanticCustomError, ValidationError

from preform.material import ParamsModel, Plausible, size_limit
from preform.shear.energy import DOMAIN_END, Branch, PiecewiseBranch
from preform.shear.law import ShearLaw

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

    FloatArray = NDArray[np.float64]


#: N/mm of picture-frame force per unit length → N/m, the unit of torque per area.
N_PER_MM_TO_N_PER_M = 1000.0

BeyondRange = Literal["hold", "linear", "extrapolate"]

#: Largest plausible normalised picture-frame force F_s/L [N/mm] and the matching torque per
#: area C = 1000·F_s/L·cos γ [N·m/m²]. Measured curves stay below ≈ 10 N/mm up to 70°; 100 N/mm
#: on a 150 mm frame is 15 kN of shear force, past what picture-frame rigs apply.
MAX_FORCE_N_PER_MM = 100.0
MAX_TORQUE_N_PER_M = MAX_FORCE_N_PER_MM * N_PER_MM_TO_N_PER_M

_FORCE_REASON = "measured picture-frame curves stay below ≈ 10 N/mm up to 70°"


def _angle_rule(what: str, low: float, high: float, reason: str) -> Plausible:
    return Plausible(
        low, high, "deg", what, f"below {low:g}° a value is most likely radians; {reason}"
    )


#: Ranges of the angles a shear law is given; reasons in docs/ranges.md.
FIT_END = _angle_rule("the end of a fitted range", 2.0, 90.0, "picture-frame tests run to 40–70°")
LOCKING_ANGLE = _angle_rule(
    "a locking angle", 2.0, 90.0, "woven fabrics lock at ≈ 25–60°, acos(Tw0/Ts)"
)
FAILURE_ANGLE = _angle_rule(
    "a stitch-failure angle", 2.0, 90.0, "chain stitches fail near 35° (paper)"
)
TABLE_END = Plausible(
    FIT_END.low,
    FIT_END.high,
    "deg",
    "the last angle of a table (the end of its measured range)",
    FIT_END.reason,
    measure=lambda angles, _model: max(angles) if angles else None,
)
FORCE_POINT = Plausible(
    0.0, MAX_FORCE_N_PER_MM, "N/mm", "a picture-frame shear force F_s/L", _FORCE_REASON
)
TORQUE_POINT = Plausible(
    0.0,
    MAX_TORQUE_N_PER_M,
    "N·m/m²",
    "a shear torque per area C",
    f"C = 1000·F_s/L·cos γ with F_s/L ≤ {MAX_FORCE_N_PER_MM:g} N/mm",
)


#: Points of the grid ``polynomial_extremes`` evaluates a polynomial and its slope on.
EXTREMES_GRID = 513


def polynomial_extremes(
    coefficients_per_deg: ArrayLike, start_deg: float, end_deg: float
) -> tuple[float, float, float]:
    """(smallest value, the angle [deg] where it is, largest value) of Σ a_k·(γ/deg)^k over
    [start_deg, end_deg]: from the interval ends, a dense grid, and the roots of the
    derivative inside it (each sign change of the slope between grid points, bisected to
    full precision).

    Plain Python, no numpy: the library's validation calls it for every polynomial law, and a
    listing of the library must not pay for importing numpy (issue 15). Two roots of the slope
    closer than one grid step (a wiggle of the size of the grid's own error) are bounded by
    the grid values."""
    return _extremes(tuple(_float_list(coefficients_per_deg)), start_deg, end_deg)


@functools.lru_cache(maxsize=256)
def _extremes(
    coefficients: tuple[float, ...], start_deg: float, end_deg: float
) -> tuple[float, float, float]:
    # Cached: a law's validator and its plausible-range check ask for the same polynomial
    # over the same range.
    c = list(coefficients)
    while c and c[-1] == 0.0:
        c.pop()
    if not c:
        return 0.0, start_deg, 0.0
    last = EXTREMES_GRID - 1
    step = (end_deg - start_deg) / last
    grid = [k * step + start_deg for k in range(last)] + [end_deg]
    angles = [float(start_deg), float(end_deg), *grid]
    top = c[-1]
    lower = c[-2::-1]  # the other coefficients, highest power first (Horner's order)
    values: list[float] = []
    slopes: list[float] = []
    for x in angles:  # value and slope by Horner's scheme, inlined: 515 points per call
        value, slope = top, 0.0
        for a in lower:
            slope = slope * x + value
            value = value * x + a
        values.append(value)
        slopes.append(slope)
    slopes = slopes[2:]  # the grid's
    for k in range(last):
        # signs compared, not multiplied: the product of two tiny slopes underflows to 0
        left, right = slopes[k], slopes[k + 1]
        # A slope exactly 0 at a grid point (a critical point there, e.g. γ = 0 of a law
        # without a linear term) has the sign the slope takes just inside the interval, the
        # curvature's: without it a hump between that point and the next was missed.
        if left == 0.0:
            left = _curvature(c, grid[k])
        if right == 0.0:
            right = -_curvature(c, grid[k + 1])
        if (left < 0.0 < right) or (right < 0.0 < left):
            root = _slope_root(c, grid[k], grid[k + 1], left)
            if start_deg < root < end_deg:
                angles.append(root)
                values.append(_value_and_slope(c, root)[0])
    if any(v != v for v in values):  # NaN (overflow): reported as such, like numpy's argmin
        k = next(i for i, v in enumerate(values) if v != v)
        return math.nan, angles[k], math.nan
    k = min(range(len(values)), key=values.__getitem__)
    return values[k], angles[k], max(values)


def _float_list(values: ArrayLike) -> list[float]:
    """A coefficient sequence (list, tuple, 1-D array) or a single number as a list of floats."""
    try:
        return [float(v) for v in values]  # type: ignore[union-attr, arg-type]
    except TypeError:  # a single number
        return [float(values)]  # type: ignore[arg-type]


def polynomial_value(coefficients: list[float], x: float) -> float:
    """Σ c_k·x^k at x by Horner's scheme, in the order of operations of
    ``numpy.polynomial.polynomial.polyval`` (so the same float), without numpy."""
    return _value_and_slope(coefficients, x)[0] if coefficients else 0.0


def _value_and_slope(c: list[float], x: float) -> tuple[float, float]:
    """Σ c_k·x^k and its derivative at x, by Horner's scheme (the value in the same order of
    operations as ``numpy.polynomial.polynomial.polyval``)."""
    value = c[-1]
    slope = 0.0
    for a in reversed(c[:-1]):
        slope = slope * x + value
        value = value * x + a
    return value, slope


def _curvature(c: list[float], x: float) -> float:
    """Σ k(k−1)·c_k·x^(k−2), the second derivative at x (plain Python, Horner's scheme)."""
    second = [k * (k - 1) * a for k, a in enumerate(c)][2:]
    value = 0.0
    for a in reversed(second):
        value = value * x + a
    return value


def _slope_root(c: list[float], lo: float, hi: float, slope_lo: float) -> float:
    """The root of the derivative between lo and hi, where it changes sign, by bisection until
    the bracket cannot shrink."""
    while True:
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            return mid
        slope = _value_and_slope(c, mid)[1]
        if slope == 0.0:
            return mid
        if (slope < 0.0) == (slope_lo < 0.0):
            lo, slope_lo = mid, slope
        else:
            hi = mid


def negative_stretch(
    coefficients_per_deg: ArrayLike, start_deg: float, end_deg: float
) -> tuple[float, float] | None:
    """(value, angle [deg]) where a polynomial is most negative on [start, end], or None when
    it is non-negative there (to 1e-9 of its largest value: rounding is not a negative force)."""
    low, at, high = polynomial_extremes(coefficients_per_deg, start_deg, end_deg)
    return (low, at) if low < -1e-9 * max(abs(high), abs(low)) else None


def negative_law_error(
    field: str,
    coefficients: list[float],
    quantity: Literal["force", "torque"],
    stretch: tuple[float, float],
    start_deg: float,
    end_deg: float,
) -> InitErrorDetails:
    """The located error for a polynomial that comes out negative inside its fitted range."""
    value, angle = stretch
    unit = "N/mm" if quantity == "force" else "N·m/m²"
    return InitErrorDetails(
        type=PydanticCustomError(
            "negative_shear_law",
            "the {quantity} comes out negative ({value} {unit} at {angle}°) inside the "
            "fitted range {start}–{end}°; a fabric does not drive its own shear. Refit (a lower "
            "degree, or a tabulated law) or shorten the fitted range",
            {
                "field": field,
                "quantity": "force F_s/L" if quantity == "force" else "torque C",
                "value": f"{value:.3g}",
                "unit": unit,
                "angle": f"{angle:.3g}",
                "start": f"{start_deg:g}",
                "end": f"{end_deg:g}",
            },
        ),
        loc=(field,),
        input=coefficients,
    )


def raise_located(model: str, errors: list[InitErrorDetails]) -> None:
    """Raise pydantic errors located at the fields they name (from a model validator)."""
    if errors:
        raise ValidationError.from_exception_data(model, errors)


def peak_over_range(range_field: str, fallback_field: str | None = None) -> Any:
    """A ``Plausible.measure``: the largest value of a coefficient list's polynomial over
    [0, the model's ``range_field``] (or ``fallback_field`` when that is None) [deg]."""

    def measure(coefficients: list[float], model: Any) -> float | None:
        end = getattr(model, range_field, None)
        if end is None and fallback_field is not None:
            end = getattr(model, fallback_field, None)
        if end is None or not coefficients:
            return None
        return polynomial_extremes(coefficients, 0.0, float(end))[2]

    return measure


def force_peak(range_field: str, fallback_field: str | None = None) -> Plausible:
    """Plausible range of the peak F_s/L of a force polynomial over its fitted range."""
    return Plausible(
        0.0,
        MAX_FORCE_N_PER_MM,
        "N/mm",
        "the peak picture-frame shear force F_s/L over the fitted range",
        _FORCE_REASON,
        measure=peak_over_range(range_field, fallback_field),
    )


def torque_peak(range_field: str, fallback_field: str | None = None) -> Plausible:
    """Plausible range of the peak C of a torque polynomial over its fitted range."""
    return Plausible(
        0.0,
        MAX_TORQUE_N_PER_M,
        "N·m/m²",
        "the peak shear torque per area C over the fitted range",
        f"C = 1000·F_s/L·cos γ with F_s/L ≤ {MAX_FORCE_N_PER_MM:g} N/mm",
        measure=peak_over_range(range_field, fallback_field),
    )


#: Coefficients of one polynomial (size-limited: a long list only fits noise).
Coefficients = Annotated[list[float], size_limit("polynomial_terms")]
#: One column of a tabulated curve.
TableColumn = Annotated[list[float], size_limit("table_points")]


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
        import numpy as np

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
        import numpy as np

        g = np.asarray(gamma, dtype=float)
        u = np.abs(g)
        if self.symmetric:
            return np.asarray(self.positive.energy(u), dtype=float)
        return np.where(g >= 0.0, self.positive.energy(u), self.negative.energy(u))


# -- polynomial -------------------------------------------------------------------------------


def degree_polynomial_to_radians(coefficients_per_deg: ArrayLike) -> FloatArray:
    """Ascending coefficients a_k of a polynomial in γ [deg] → the same polynomial in γ [rad]."""
    import numpy as np

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
    import numpy as np
    from numpy.polynomial import polynomial as npoly

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


class PolynomialParams(ParamsModel):
    """Parameters of the ``polynomial`` shear law (YAML ``shear_law`` block)."""

    law: Literal["polynomial"] = Field(description="Selects the polynomial shear law.")
    force_coefficients_N_per_mm: Annotated[Coefficients | None, force_peak("max_angle_deg")] = (
        Field(
            default=None,
            description=(
                "F_s/L [N/mm] = Σ a_k·(γ/deg)^k, ascending powers from k = 0, for γ ≥ 0 (and for "
                "γ < 0 at |γ| unless a negative-sense polynomial is given). a_k in N/mm/deg^k."
            ),
        )
    )
    torque_coefficients_N_per_m: Annotated[Coefficients | None, torque_peak("max_angle_deg")] = (
        Field(
            default=None,
            description=(
                "Alternative to the force polynomial: torque per area C [N·m/m²] = Σ a_k·(γ/deg)^k."
            ),
        )
    )
    force_coefficients_negative_N_per_mm: Annotated[
        Coefficients | None, force_peak("max_angle_negative_deg", "max_angle_deg")
    ] = Field(
        default=None,
        description="F_s/L [N/mm] for γ < 0 as a polynomial in |γ| [deg]; makes the law asymmetric.",
    )
    torque_coefficients_negative_N_per_m: Annotated[
        Coefficients | None, torque_peak("max_angle_negative_deg", "max_angle_deg")
    ] = Field(
        default=None,
        description="C [N·m/m²] for γ < 0 as a polynomial in |γ| [deg]; makes the law asymmetric.",
    )
    max_angle_deg: Annotated[float, FIT_END] = Field(
        gt=0.0, le=90.0, description="End of the fitted range for γ ≥ 0 [deg]."
    )
    max_angle_negative_deg: Annotated[float | None, FIT_END] = Field(
        default=None, gt=0.0, le=90.0, description="End of the fitted range for γ < 0 [deg]."
    )
    beyond_range: BeyondRange = Field(
        default="hold",
        description="Past the fitted range: hold the value, continue the tangent, or extrapolate.",
    )
    locking_angle_deg: Annotated[float | None, LOCKING_ANGLE] = Field(
        default=None, gt=0.0, lt=90.0, description="Locking (wrinkling) angle [deg], if known."
    )
    failure_angle_deg: Annotated[float | None, FAILURE_ANGLE] = Field(
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
        quantity: Literal["force", "torque"] = "force" if force[0] is not None else "torque"
        end_negative = self.max_angle_negative_deg or self.max_angle_deg
        errors = []
        for name, coefficients, end in (
            (
                f"{quantity}_coefficients_{self._unit(quantity)}",
                self._senses()[0],
                self.max_angle_deg,
            ),
            (
                f"{quantity}_coefficients_negative_{self._unit(quantity)}",
                self._senses()[1],
                end_negative,
            ),
        ):
            if coefficients is None:
                continue
            stretch = negative_stretch(coefficients, 0.0, end)
            if stretch is not None:
                errors.append(negative_law_error(name, coefficients, quantity, stretch, 0.0, end))
        raise_located(type(self).__name__, errors)
        return self

    @staticmethod
    def _unit(quantity: str) -> str:
        return "N_per_mm" if quantity == "force" else "N_per_m"

    def _senses(self) -> tuple[list[float] | None, list[float] | None]:
        if self.force_coefficients_N_per_mm is not None:
            return self.force_coefficients_N_per_mm, self.force_coefficients_negative_N_per_mm
        return self.torque_coefficients_N_per_m, self.torque_coefficients_negative_N_per_m


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
    import numpy as np

    a = np.asarray(angle_deg, dtype=float)
    v = np.asarray(values, dtype=float)
    if a[0] > 0.0:
        a, v = np.concatenate([[0.0], a]), np.concatenate([[0.0], v])
    scale = N_PER_MM_TO_N_PER_M if quantity == "force" else 1.0
    radians = np.radians(a)
    from scipy.interpolate import PchipInterpolator  # only tabulated laws need scipy

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


class TabulatedParams(ParamsModel):
    """Parameters of the ``tabulated`` shear law (YAML ``shear_law`` block)."""

    law: Literal["tabulated"] = Field(description="Selects the tabulated shear law.")
    angle_deg: Annotated[TableColumn, TABLE_END] = Field(
        min_length=2, description="Shear angles [deg], strictly ascending, 0 ≤ γ ≤ 90, γ ≥ 0."
    )
    force_N_per_mm: Annotated[TableColumn | None, FORCE_POINT] = Field(
        default=None, description="Normalised picture-frame force F_s/L [N/mm] at angle_deg."
    )
    torque_N_per_m: Annotated[TableColumn | None, TORQUE_POINT] = Field(
        default=None, description="Alternatively, torque per area C [N·m/m²] at angle_deg."
    )
    angle_negative_deg: Annotated[TableColumn | None, TABLE_END] = Field(
        default=None,
        description="Shear-angle magnitudes [deg] of a separate table for γ < 0 (asymmetric law).",
    )
    force_negative_N_per_mm: Annotated[TableColumn | None, FORCE_POINT] = Field(
        default=None, description="F_s/L [N/mm] for γ < 0 at angle_negative_deg."
    )
    torque_negative_N_per_m: Annotated[TableColumn | None, TORQUE_POINT] = Field(
        default=None, description="C [N·m/m²] for γ < 0 at angle_negative_deg."
    )
    beyond_range: Literal["hold", "linear"] = Field(
        default="hold", description="Past the last point: hold its value or continue its tangent."
    )
    locking_angle_deg: Annotated[float | None, LOCKING_ANGLE] = Field(
        default=None, gt=0.0, lt=90.0, description="Locking (wrinkling) angle [deg], if known."
    )
    failure_angle_deg: Annotated[float | None, FAILURE_ANGLE] = Field(
        default=None, gt=0.0, lt=90.0, description="Stitch-failure angle, γ > 0 [deg], if any."
    )

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        if (self.force_N_per_mm is None) == (self.torque_N_per_m is None):
            raise ValueError("give exactly one of force_N_per_mm, torque_N_per_m")
        values_field = "force_N_per_mm" if self.force_N_per_mm is not None else "torque_N_per_m"
        _check_table(self, "angle_deg", values_field)
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
            negative_field = values_field.replace("_N_per", "_negative_N_per")
            _check_table(self, "angle_negative_deg", negative_field)
        return self


def _check_table(params: BaseModel, angles_field: str, values_field: str) -> None:
    """One value per angle, angles strictly ascending in [0, 90]°, values ≥ 0; each error
    located at the list (or the item) at fault."""
    import numpy as np

    angles: list[float] = getattr(params, angles_field)
    values: list[float] = getattr(params, values_field)
    model = type(params).__name__

    def fail(loc: tuple[str | int, ...], message: str, value: Any) -> None:
        raise_located(
            model,
            [InitErrorDetails(type=PydanticCustomError("table", message), loc=loc, input=value)],
        )

    if len(values) != len(angles):
        fail(
            (values_field,),
            f"{len(values)} value(s) for {len(angles)} angle(s) in {angles_field}: "
            "give one value per angle",
            values,
        )
    a = np.asarray(angles, dtype=float)
    if a[0] < 0.0 or a[-1] > 90.0 or np.any(np.diff(a) <= 0.0):
        fail((angles_field,), "angles must be strictly ascending within [0, 90] deg", angles)
    for i, value in enumerate(values):
        if value < 0.0:
            fail(
                (values_field, i),
                f"{value:g} < 0: forces and torques are magnitudes in their sense, ≥ 0",
                value,
            )


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
