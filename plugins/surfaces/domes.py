"""Analytic dome-shaped tool surfaces standing on the plane z = 0 with their axis along +z.

* ``FlangedHemisphere``: a hemisphere on a flat flange, joined to it by a concave toroidal fillet.
* ``Cone``: a (possibly truncated) cone, apex up.
* ``EllipsoidDome``: the upper half of an ellipsoid.
* ``ParaboloidDome``: z = h (1 − r²/R²) for r ≤ R.

All lengths are in metres. Every class implements the ``preform.drape.engine.surface.Surface``
protocol with closed-form or iterative closest points, compiled (``compiled_queries``: the
queries are in ``preform.drape.kernels.surface_kernels``, imported when first asked, and a drape of the
tool runs the compiled fill in one loop), so it answers for any query point, including points
beyond the rim (the answer then lies on the rim or the flange edge).
``point_at_plan`` answers the single point of the tool above a plan position (these tools are
height fields); off the tool the mask is false and the returned point lies on the base plane
z = 0, so no NaN ever leaves this module.

The axisymmetric tools are handled in their meridian half-plane (r = √(x² + y²), z): the closest
point of a surface of revolution lies in the meridian plane of the query point, because for
profile points with r' ≥ 0 the distance grows with the azimuth difference.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.compiled_surface import (
    CONE,
    ELLIPSOID_DOME,
    FLANGED_HEMISPHERE,
    PARABOLOID_DOME,
    CompiledTool,
)

Bounds = tuple[tuple[float, float, float], tuple[float, float, float]]

__all__ = ["Cone", "EllipsoidDome", "FlangedHemisphere", "ParaboloidDome"]


def _as_points(points: FloatArray, width: int) -> FloatArray:
    array = np.asarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != width:
        raise ValueError(f"expected an (n, {width}) array of positions [m], got {array.shape}")
    return array


def _positive_length(name: str, value: float) -> float:
    length = float(value)
    if not np.isfinite(length) or length <= 0.0:
        raise ValueError(f"{name} must be a positive length in metres, got {value!r}")
    return length


class _Dome(CompiledTool):
    """A dome's queries take (n, 3) arrays of points and nothing else."""

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        return super().closest_point(_as_points(points, 3))

    def normal(self, points: FloatArray) -> FloatArray:
        return super().normal(_as_points(points, 3))


# --- flanged hemisphere ----------------------------------------------------------------------


class FlangedHemisphere(_Dome):
    """A hemisphere of radius ``radius_m`` [m] centred at the origin, standing on the flange
    plane z = 0 and joined to it by a concave toroidal fillet of radius ``fillet_radius_m`` [m].

    The fillet is tangent to both the sphere and the plane, so the surface is tangent-continuous
    (C¹) everywhere. In the meridian plane its circle has centre (r_f, ρ) with
    r_f = √(R² + 2Rρ) (the *fillet foot radius*, where it meets the flange) and meets the sphere
    at elevation β = asin(ρ / (R + ρ)). The flange extends to ``flange_half_width_m`` [m]: a
    square |x|, |y| ≤ W (default) or a disc r ≤ W (``flange_shape="circle"``). The tool ends at
    the flange edge; ``size`` is the sphere radius.

    A point's closest point is the nearest of the cap's, the fillet's (both in the meridian
    plane) and the flange's (in plan: clamped into its outline, out of the fillet foot disc);
    past the flange edge, a point of the edge. Normals: radial on the cap, towards the fillet
    circle's centre on the fillet (it is concave), +z on the flange.
    """

    def __init__(
        self,
        radius_m: float,
        fillet_radius_m: float,
        flange_half_width_m: float,
        *,
        flange_shape: str = "square",
    ) -> None:
        self.radius_m = _positive_length("radius_m", radius_m)
        self.fillet_radius_m = _positive_length("fillet_radius_m", fillet_radius_m)
        if self.fillet_radius_m >= self.radius_m:
            raise ValueError(
                f"fillet_radius_m ({self.fillet_radius_m} m) must be smaller than "
                f"radius_m ({self.radius_m} m)"
            )
        radius, fillet = self.radius_m, self.fillet_radius_m
        #: Radius [m] at which the fillet meets the flange plane.
        self.fillet_foot_radius_m = float(np.sqrt(radius * radius + 2.0 * radius * fillet))
        self.flange_half_width_m = _positive_length("flange_half_width_m", flange_half_width_m)
        if self.flange_half_width_m <= self.fillet_foot_radius_m:
            raise ValueError(
                f"flange_half_width_m ({self.flange_half_width_m} m) must exceed the fillet foot "
                f"radius √(R² + 2Rρ) = {self.fillet_foot_radius_m} m"
            )
        if flange_shape not in ("square", "circle"):
            raise ValueError(f"flange_shape must be 'square' or 'circle', got {flange_shape!r}")
        self.flange_shape = flange_shape
        self._seam_elevation = float(np.arcsin(fillet / (radius + fillet)))
        #: Radius [m] of the seam circle where the sphere hands over to the fillet.
        self.seam_radius_m = radius * float(np.cos(self._seam_elevation))
        width = self.flange_half_width_m
        self.bounds: Bounds = ((-width, -width, 0.0), (width, width, radius))
        self.size = radius

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The tool for the compiled kernels: (FLANGED_HEMISPHERE, (R, ρ, fillet foot radius,
        flange half width [m], seam elevation [rad], 1 for a square flange or 0 for a disc))."""
        return FLANGED_HEMISPHERE, np.array(
            [
                self.radius_m,
                self.fillet_radius_m,
                self.fillet_foot_radius_m,
                self.flange_half_width_m,
                self._seam_elevation,
                1.0 if self.flange_shape == "square" else 0.0,
            ]
        )

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Surface points (n, 3) [m] above plan positions ``xy`` (n, 2) [m] and whether each
        position lies over the tool (inside the flange outline). Off the tool z = 0."""
        plan = _as_points(xy, 2)
        r = np.hypot(plan[:, 0], plan[:, 1])
        radius, fillet, foot = self.radius_m, self.fillet_radius_m, self.fillet_foot_radius_m
        on_cap = r <= self.seam_radius_m
        on_fillet = ~on_cap & (r < foot)
        z = np.zeros_like(r)
        z[on_cap] = np.sqrt(radius * radius - r[on_cap] ** 2)
        z[on_fillet] = fillet - np.sqrt(
            np.maximum(fillet * fillet - (r[on_fillet] - foot) ** 2, 0.0)
        )
        width = self.flange_half_width_m
        if self.flange_shape == "square":
            over_tool = (np.abs(plan[:, 0]) <= width) & (np.abs(plan[:, 1]) <= width)
        else:
            over_tool = r <= width
        return np.column_stack((plan, z)), over_tool


# --- cone ------------------------------------------------------------------------------------


class Cone(_Dome):
    """A cone, apex up, base circle of radius ``base_radius_m`` [m] on z = 0, height
    ``height_m`` [m]; with ``top_radius_m`` > 0 it is truncated by a flat top disc at z = height.

    The tool is the lateral surface plus the top disc; it ends at the base circle (no flange).
    ``size`` is the base radius. At the (sharp) apex the normal is taken as +z, as on the top
    disc. A point's closest point is the nearer of the lateral segment's and the top disc's in
    the meridian plane; past the base circle, a point of it.
    """

    def __init__(self, base_radius_m: float, height_m: float, *, top_radius_m: float = 0.0) -> None:
        self.base_radius_m = _positive_length("base_radius_m", base_radius_m)
        self.height_m = _positive_length("height_m", height_m)
        self.top_radius_m = float(top_radius_m)
        if not (0.0 <= self.top_radius_m < self.base_radius_m):
            raise ValueError(
                f"top_radius_m must lie in [0, base_radius_m = {self.base_radius_m}) m, "
                f"got {top_radius_m!r}"
            )
        radius = self.base_radius_m
        self.bounds: Bounds = ((-radius, -radius, 0.0), (radius, radius, self.height_m))
        self.size = radius
        slant = np.hypot(self.height_m, radius - self.top_radius_m)
        self._lateral_normal = (self.height_m / slant, (radius - self.top_radius_m) / slant)

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The cone for the compiled kernels: (CONE, (base radius, height, top radius [m],
        lateral outward normal: radial and vertical part))."""
        return CONE, np.array(
            [self.base_radius_m, self.height_m, self.top_radius_m, *self._lateral_normal]
        )

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Surface points (n, 3) [m] above plan positions ``xy`` (n, 2) [m] and whether each
        lies over the tool (r ≤ base radius). Off the tool z = 0."""
        plan = _as_points(xy, 2)
        r = np.hypot(plan[:, 0], plan[:, 1])
        over_tool = r <= self.base_radius_m
        slope_run = self.base_radius_m - self.top_radius_m
        z = self.height_m * np.clip((self.base_radius_m - r) / slope_run, 0.0, 1.0)
        return np.column_stack((plan, np.where(over_tool, z, 0.0))), over_tool


# --- ellipsoid -------------------------------------------------------------------------------


def _ellipsoid_foot(y: FloatArray, semi_axes: FloatArray) -> FloatArray:
    """Closest points on the ellipsoid Σ (q_i / a_i)² = 1 to points ``y`` (n, d) with y ≥ 0
    componentwise (one orthant; the caller restores signs). Works in any dimension d.

    The foot is q_i = a_i² y_i / (a_i² + t) with t the largest root of
    Σ (a_i y_i / (a_i² + t))² = 1. Scaling t = s·a_min² gives
    G(s) = Σ (r_i z_i / (s + r_i))² − 1 with r_i = (a_i / a_min)² ≥ 1 and z_i = y_i / a_i; G is
    strictly decreasing on s > −1 and brackets its root in [max z_min-axes − 1, |r ∘ z| − 1],
    so a vectorised bisection always converges. When the point lies on the plane orthogonal to
    the shortest axis deep inside, G(−1) < 0 and there is no root: the foot then leaves that
    plane, and the shortest-axis coordinate follows from the ellipsoid equation instead.
    """
    a_min = float(semi_axes.min())
    ratio = (semi_axes / a_min) ** 2
    z = y / semi_axes
    shortest = semi_axes == a_min
    rz = ratio * z

    def excess(s: FloatArray) -> FloatArray:
        denom = s[:, None] + ratio[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            term = np.where(rz == 0.0, 0.0, rz / denom)
        return np.sum(term * term, axis=1) - 1.0

    lower = np.max(z[:, shortest], axis=1) - 1.0
    upper = np.maximum(np.linalg.norm(rz, axis=1) - 1.0, lower)
    for _ in range(200):
        mid = 0.5 * (lower + upper)
        positive = excess(mid) > 0.0
        lower = np.where(positive, mid, lower)
        upper = np.where(positive, upper, mid)
        if np.all(upper - lower <= 4.0 * np.finfo(float).eps * np.maximum(1.0, np.abs(upper))):
            break
    s = upper
    with np.errstate(divide="ignore", invalid="ignore"):
        foot = np.where(y == 0.0, 0.0, ratio * y / (s[:, None] + ratio[None, :]))

    # Near s = −1 (the point near the plane orthogonal to the shortest axis, deep inside) the
    # shortest-axis coordinates y_k / (s + 1) are 0/0-like. They then follow better from the
    # ellipsoid equation, shared among tied shortest axes in proportion to y_k (the formula's own
    # ratio): that is better conditioned whenever the share left for them, 1 − Σ_others
    # (q_i/a_i)², exceeds s + 1. With no root at all (all y_k = 0, G(−1) < 0) this is the exact
    # answer: the foot leaves the plane along the last shortest axis (z for a dome).
    others = ~shortest
    remainder = np.maximum(1.0 - np.sum((foot[:, others] / semi_axes[others]) ** 2, axis=1), 0.0)
    use_equation = remainder > s + 1.0
    if np.any(use_equation):
        y_short = y[use_equation][:, shortest]
        short_norm = np.linalg.norm(y_short, axis=1)
        direction = np.zeros_like(y_short)
        direction[:, -1] = 1.0
        has_norm = short_norm > 0.0
        direction[has_norm] = y_short[has_norm] / short_norm[has_norm, None]
        replaced = foot[use_equation]
        replaced[:, shortest] = a_min * np.sqrt(remainder[use_equation])[:, None] * direction
        foot[use_equation] = replaced

    # Remove the residual of the root solve (tiny, but amplified where s + 1 is tiny) by a
    # radial rescale onto the ellipsoid; the foot moves by a second-order amount in distance.
    scale = np.sqrt(np.sum((foot / semi_axes) ** 2, axis=1))
    return foot / scale[:, None]


class EllipsoidDome(_Dome):
    """The upper half (z ≥ 0) of the ellipsoid (x/a)² + (y/b)² + (z/c)² = 1, semi-axes
    ``semi_axes_m = (a, b, c)`` [m]. The tool ends at the base ellipse on z = 0 (no flange);
    ``size`` is the largest semi-axis.

    Closest points are exact for every query point with z ≥ 0 (the side the fabric is on): the
    nearest point of the whole ellipsoid then lies in the upper half. Below the base plane (under
    the tool, where no fabric goes) the answer is the nearer of the base-rim foot and the foot of
    the query mirrored in z = 0: always a surface point, not guaranteed to be the nearest
    (the root solve is ``preform.drape.kernels.surface_kernels._ellipsoid_foot``). The normal
    is the gradient of the implicit function at the closest point.
    """

    def __init__(self, semi_axes_m: Sequence[float] = (0.1, 0.1, 0.1)) -> None:
        if len(semi_axes_m) != 3:
            raise ValueError(f"semi_axes_m must hold three lengths (a, b, c), got {semi_axes_m!r}")
        names = ("semi_axes_m[0]", "semi_axes_m[1]", "semi_axes_m[2]")
        self.semi_axes_m = np.array(
            [_positive_length(n, v) for n, v in zip(names, semi_axes_m, strict=True)]
        )
        a, b, c = (float(v) for v in self.semi_axes_m)
        self.bounds: Bounds = ((-a, -b, 0.0), (a, b, c))
        self.size = max(a, b, c)

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The dome for the compiled kernels: (ELLIPSOID_DOME, (a, b, c)) [m]."""
        return ELLIPSOID_DOME, np.array(self.semi_axes_m, dtype=float)

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Surface points (n, 3) [m] above plan positions ``xy`` (n, 2) [m] and whether each
        lies over the tool (inside the base ellipse). Off the tool z = 0."""
        plan = _as_points(xy, 2)
        a, b, c = self.semi_axes_m
        height_sq = 1.0 - (plan[:, 0] / a) ** 2 - (plan[:, 1] / b) ** 2
        over_tool = height_sq >= 0.0
        return np.column_stack((plan, c * np.sqrt(np.maximum(height_sq, 0.0)))), over_tool


# --- paraboloid ------------------------------------------------------------------------------


class ParaboloidDome(_Dome):
    """The paraboloid z = h (1 − r²/R²) for r ≤ R: radius ``radius_m`` R [m] at the base,
    height ``height_m`` h [m]. The tool ends at the base circle r = R on z = 0 (no flange);
    ``size`` is the larger of R and h.

    The closest point in the meridian plane solves d/dr of the squared distance,
    2k² r³ + (1 − 2k(h − z_p)) r − r_p = 0 with k = h/R². For r ≥ 0 that cubic is convex and
    starts at −r_p ≤ 0, so it has exactly one non-negative root and the distance is unimodal in
    r: Newton's method from a start known to lie right of the root converges monotonically, and
    clamping the root to [0, R] gives the nearest point of the bounded dome.
    """

    def __init__(self, radius_m: float, height_m: float) -> None:
        self.radius_m = _positive_length("radius_m", radius_m)
        self.height_m = _positive_length("height_m", height_m)
        radius = self.radius_m
        self.bounds: Bounds = ((-radius, -radius, 0.0), (radius, radius, self.height_m))
        self.size = max(radius, self.height_m)
        self._curvature = self.height_m / radius**2

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The dome for the compiled kernels: (PARABOLOID_DOME, (R [m], h [m], h/R² [1/m]))."""
        return PARABOLOID_DOME, np.array([self.radius_m, self.height_m, self._curvature])

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Surface points (n, 3) [m] above plan positions ``xy`` (n, 2) [m] and whether each
        lies over the tool (r ≤ R). Off the tool z = 0."""
        plan = _as_points(xy, 2)
        r_sq = plan[:, 0] ** 2 + plan[:, 1] ** 2
        over_tool = r_sq <= self.radius_m**2
        z = np.where(over_tool, self.height_m * (1.0 - r_sq / self.radius_m**2), 0.0)
        return np.column_stack((plan, z)), over_tool
