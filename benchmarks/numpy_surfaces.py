"""The analytic tools' numpy closest points, normals and plate placement as they were before
the compiled queries (issue 15), frozen: the vectorised path that ``bench_kernels.py`` times
against the compiled fill, and the second implementation ``tests/drape/test_tool_queries.py``
compares the compiled queries with. The classes have no ``compiled_queries``, so a drape of
them takes the Python front loop with these numpy methods between the compiled per-node steps.

Copied from ``plugins/surfaces/basic.py`` (Plane, Cylinder) and ``plugins/surfaces/domes.py``
at commit 18913e6; not to be edited (it is the baseline).
"""

# ruff: noqa

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from preform.drape.engine.result import NodeStatus

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
StatusArray = NDArray[np.int8]
IntArray = NDArray[np.int64]
Bounds = tuple[tuple[float, float, float], tuple[float, float, float]]

#: Points this fraction of the node spacing outside a trimmed surface still count as on it, so
#: rounding never turns a node lying exactly on an edge (a hemisphere's rim) into OFF_TOOL.
_EDGE_TOLERANCE = 1e-9


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...i,...i->...", a, b)


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    # Written out: np.cross has a large fixed cost on the small arrays of one wavefront.
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def _unit(a: FloatArray) -> FloatArray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / np.sqrt(_dot(a, a))[..., None]


class Plane:
    """A flat rectangular plate, horizontal, of plan size ``size_m`` = (Lx, Ly) [m] centred at
    ``centre_m`` [m]; its outward normal is +z."""

    def __init__(
        self, size_m: tuple[float, float], *, centre_m: ArrayLike = (0.0, 0.0, 0.0)
    ) -> None:
        self.half = 0.5 * np.asarray(size_m, dtype=float)
        if self.half.shape != (2,) or not np.all(self.half > 0):
            raise ValueError(f"plane size must be two positive lengths, got {size_m!r} m")
        self.centre = np.asarray(centre_m, dtype=float)
        lo, hi = self.centre[:2] - self.half, self.centre[:2] + self.half
        z = float(self.centre[2])
        self.bounds = ((float(lo[0]), float(lo[1]), z), (float(hi[0]), float(hi[1]), z))
        self.size = float(2.0 * np.hypot(*self.half))

    def __repr__(self) -> str:
        return f"Plane(size_m={tuple(2 * self.half)}, centre_m={tuple(self.centre)})"

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest points on the plate [m] and distances (n,) [m] to points (n, 3) [m]."""
        p = np.asarray(points, dtype=float)
        q = np.empty_like(p)
        q[:, :2] = np.clip(p[:, :2], self.centre[:2] - self.half, self.centre[:2] + self.half)
        q[:, 2] = self.centre[2]
        return q, np.sqrt(_dot(p - q, p - q))

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3): +z everywhere."""
        n = np.zeros((len(points), 3))
        n[:, 2] = 1.0
        return n

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Plate points over plan positions (n, 2) [m], and which positions are over the plate."""
        xy = np.asarray(xy, dtype=float)
        mask = np.all(np.abs(xy - self.centre[:2]) <= self.half, axis=1)
        pts = np.column_stack([xy, np.full(len(xy), self.centre[2])])
        pts[~mask] = np.nan
        return pts, mask

    def _on_plate(self, p: FloatArray, spacing: float) -> BoolArray:
        slack = _EDGE_TOLERANCE * spacing
        return np.all(np.abs(p[..., :2] - self.centre[:2]) <= self.half + slack, axis=-1)

    def place_nodes(
        self, a: FloatArray, b: FloatArray, opposite: FloatArray, spacing: float
    ) -> tuple[FloatArray, StatusArray]:
        """Net nodes (m, 3) [m] at distance ``spacing`` [m] from ``a`` and ``b`` (m, 3) on the
        side away from ``opposite``, with NodeStatus codes (m,)."""
        mid = 0.5 * (a + b)
        chord = b - a
        half2 = 0.25 * _dot(chord, chord)
        radius2 = spacing * spacing - half2
        ok = radius2 > 0
        e = _unit(chord)
        side = _unit(np.column_stack([-e[:, 1], e[:, 0], np.zeros(len(e))]))
        away = np.where(_dot(opposite - mid, side) > 0, -1.0, 1.0)
        p = mid + (away * np.sqrt(np.where(ok, radius2, 0.0)))[:, None] * side
        p[:, 2] = self.centre[2]
        status = np.where(ok, NodeStatus.PLACED, NodeStatus.NO_INTERSECTION).astype(np.int8)
        status[ok & ~self._on_plate(p, spacing)] = NodeStatus.OFF_TOOL
        p[status != NodeStatus.PLACED] = np.nan
        return p, status

    def geodesic_nodes(
        self, start: FloatArray, direction: FloatArray, spacing: float, count: int
    ) -> tuple[FloatArray, StatusArray]:
        """``count`` nodes (m, count, 3) [m] along the straight lines from ``start`` (m, 3) in
        ``direction`` (m, 3), spacing [m] apart, with NodeStatus codes (m, count)."""
        t = direction.copy()
        t[:, 2] = 0.0
        t = _unit(t)
        k = np.arange(1, count + 1, dtype=float)
        p = start[:, None, :] + spacing * k[None, :, None] * t[:, None, :]
        on = self._on_plate(p, spacing)
        status = np.where(on, NodeStatus.PLACED, NodeStatus.OFF_TOOL).astype(np.int8)
        return p, status


class Cylinder:
    """The lateral surface of a circular cylinder with a horizontal ``axis`` ("x" or "y"),
    radius ``radius_m`` [m] and length ``length_m`` [m], centred at ``centre_m`` [m]."""

    def __init__(
        self,
        radius_m: float,
        length_m: float,
        axis: Literal["x", "y"] = "x",
        *,
        centre_m: ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        if axis not in ("x", "y"):
            # A vertical cylinder has no top seen from above, so point_at_plan is undefined.
            raise ValueError(f"cylinder axis must be 'x' or 'y' (horizontal), got {axis!r}")
        self.radius, self.length = float(radius_m), float(length_m)
        if not (self.radius > 0 and self.length > 0):
            raise ValueError("cylinder radius and length must be positive")
        self.axis = axis
        self._ax, self._across = (0, 1) if axis == "x" else (1, 0)
        self.centre = np.asarray(centre_m, dtype=float)
        lo = self.centre - self.radius
        hi = self.centre + self.radius
        lo[self._ax] = self.centre[self._ax] - 0.5 * self.length
        hi[self._ax] = self.centre[self._ax] + 0.5 * self.length
        self.bounds = (
            (float(lo[0]), float(lo[1]), float(lo[2])),
            (float(hi[0]), float(hi[1]), float(hi[2])),
        )
        self.size = float(np.hypot(2.0 * self.radius, self.length))

    def __repr__(self) -> str:
        return (
            f"Cylinder(radius_m={self.radius}, length_m={self.length}, axis={self.axis!r}, "
            f"centre_m={tuple(self.centre)})"
        )

    def _radial(self, p: FloatArray) -> FloatArray:
        """Unit direction from the axis, in the cross-section plane (+z for points on it)."""
        rel = p - self.centre
        rel[:, self._ax] = 0.0
        length = np.sqrt(_dot(rel, rel))
        on_axis = length == 0
        if on_axis.any():
            rel[on_axis] = (0.0, 0.0, 1.0)
            length[on_axis] = 1.0
        rel /= length[:, None]
        return rel

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest points on the lateral surface [m] and distances (n,) [m]."""
        p = np.asarray(points, dtype=float)
        q = self.centre + self.radius * self._radial(p)
        half = 0.5 * self.length
        c = self.centre[self._ax]
        q[:, self._ax] = np.clip(p[:, self._ax], c - half, c + half)
        return q, np.sqrt(_dot(p - q, p - q))

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward (radial) normals (n, 3) at surface points (n, 3) [m]."""
        return self._radial(np.asarray(points, dtype=float))

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """The top of the cylinder over plan positions (n, 2) [m], and which lie over it."""
        xy = np.asarray(xy, dtype=float)
        across = xy[:, self._across] - self.centre[self._across]
        along = xy[:, self._ax] - self.centre[self._ax]
        height2 = self.radius**2 - across**2
        mask = (height2 >= 0) & (np.abs(along) <= 0.5 * self.length)
        pts = np.column_stack([xy, self.centre[2] + np.sqrt(np.where(mask, height2, 0.0))])
        pts[~mask] = np.nan
        return pts, mask


# --- domes.py ---


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


# --- meridian half-plane helpers -------------------------------------------------------------


def _to_meridian(points: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Radial distance r, height z and the azimuth (cos, sin) of each point."""
    r = np.hypot(points[:, 0], points[:, 1])
    # Scale by the larger plan coordinate first so the azimuth stays a unit vector even for
    # subnormal coordinates; on the axis every meridian is equally good and +x is taken.
    largest = np.maximum(np.abs(points[:, 0]), np.abs(points[:, 1]))
    on_axis = largest == 0.0
    safe = np.where(on_axis, 1.0, largest)
    x, y = points[:, 0] / safe, points[:, 1] / safe
    unit = np.where(on_axis, 1.0, np.hypot(x, y))
    cos_az = np.where(on_axis, 1.0, x / unit)
    sin_az = np.where(on_axis, 0.0, y / unit)
    return r, points[:, 2], cos_az, sin_az


def _from_meridian(
    r: FloatArray, z: FloatArray, cos_az: FloatArray, sin_az: FloatArray
) -> FloatArray:
    return np.column_stack((r * cos_az, r * sin_az, z))


def _closest_on_segment(
    r: FloatArray, z: FloatArray, start: tuple[float, float], end: tuple[float, float]
) -> tuple[FloatArray, FloatArray]:
    dr, dz = end[0] - start[0], end[1] - start[1]
    length_sq = dr * dr + dz * dz
    if length_sq == 0.0:
        return np.full_like(r, start[0]), np.full_like(z, start[1])
    t = np.clip(((r - start[0]) * dr + (z - start[1]) * dz) / length_sq, 0.0, 1.0)
    return start[0] + t * dr, start[1] + t * dz


def _closest_on_arc(
    r: FloatArray,
    z: FloatArray,
    centre: tuple[float, float],
    radius: float,
    angle_start: float,
    angle_end: float,
) -> tuple[FloatArray, FloatArray]:
    """Closest points on the circular arc running anticlockwise from ``angle_start`` to
    ``angle_end`` [rad] (angles measured from +r towards +z)."""
    angle = np.arctan2(z - centre[1], r - centre[0])
    on_arc = np.mod(angle - angle_start, 2.0 * np.pi) <= angle_end - angle_start
    proj_r = centre[0] + radius * np.cos(angle)
    proj_z = centre[1] + radius * np.sin(angle)
    start_r, start_z = (
        centre[0] + radius * np.cos(angle_start),
        centre[1] + radius * np.sin(angle_start),
    )
    end_r, end_z = centre[0] + radius * np.cos(angle_end), centre[1] + radius * np.sin(angle_end)
    to_start = (r - start_r) ** 2 + (z - start_z) ** 2
    to_end = (r - end_r) ** 2 + (z - end_z) ** 2
    nearer_start = to_start <= to_end
    out_r = np.where(on_arc, proj_r, np.where(nearer_start, start_r, end_r))
    out_z = np.where(on_arc, proj_z, np.where(nearer_start, start_z, end_z))
    return out_r, out_z


def _pick_nearest(
    points: FloatArray, candidates: FloatArray
) -> tuple[FloatArray, FloatArray, IntArray]:
    """From candidates (k, n, 3) pick the nearest to each point: (closest, distance, which)."""
    distances = np.linalg.norm(candidates - points[None, :, :], axis=2)
    which = np.argmin(distances, axis=0)
    index = np.arange(points.shape[0])
    return candidates[which, index], distances[which, index], which


# --- flanged hemisphere ----------------------------------------------------------------------

_CAP, _FILLET, _FLANGE = 0, 1, 2


class FlangedHemisphere:
    """A hemisphere of radius ``radius_m`` [m] centred at the origin, standing on the flange
    plane z = 0 and joined to it by a concave toroidal fillet of radius ``fillet_radius_m`` [m].

    The fillet is tangent to both the sphere and the plane, so the surface is tangent-continuous
    (C¹) everywhere. In the meridian plane its circle has centre (r_f, ρ) with
    r_f = √(R² + 2Rρ) (the *fillet foot radius*, where it meets the flange) and meets the sphere
    at elevation β = asin(ρ / (R + ρ)). The flange extends to ``flange_half_width_m`` [m]: a
    square |x|, |y| ≤ W (default) or a disc r ≤ W (``flange_shape="circle"``). The tool ends at
    the flange edge; ``size`` is the sphere radius.
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

    def _closest(self, points: FloatArray) -> tuple[FloatArray, FloatArray, IntArray]:
        r, z, cos_az, sin_az = _to_meridian(points)
        radius, fillet, foot = self.radius_m, self.fillet_radius_m, self.fillet_foot_radius_m
        beta = self._seam_elevation
        cap = _from_meridian(
            *_closest_on_arc(r, z, (0.0, 0.0), radius, beta, 0.5 * np.pi), cos_az, sin_az
        )
        fillet_pts = _from_meridian(
            *_closest_on_arc(r, z, (foot, fillet), fillet, np.pi + beta, 1.5 * np.pi),
            cos_az,
            sin_az,
        )
        # The flange is not axisymmetric when square, so it is handled in plan: clamp into the
        # flange outline, then push out of the fillet foot disc (the part of the plane the
        # fillet and dome cover), which is the nearest point of the annulus for inner points.
        width = self.flange_half_width_m
        if self.flange_shape == "square":
            plan = np.clip(points[:, :2], -width, width)
            plan_r = np.hypot(plan[:, 0], plan[:, 1])
            inside_foot = plan_r < foot
            plan[inside_foot] = foot * np.column_stack((cos_az, sin_az))[inside_foot]
        else:
            plan_r = np.clip(r, foot, width)
            plan = np.column_stack((plan_r * cos_az, plan_r * sin_az))
        flange = np.column_stack((plan, np.zeros(points.shape[0])))
        return _pick_nearest(points, np.stack((cap, fillet_pts, flange)))

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest surface points (n, 3) [m] to ``points`` (n, 3) [m] and distances (n,) [m]."""
        closest, distance, _ = self._closest(_as_points(points, 3))
        return closest, distance

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at surface points (n, 3) [m]; a point off the surface gets
        the normal at its closest surface point."""
        closest, _, region = self._closest(_as_points(points, 3))
        r, z, cos_az, sin_az = _to_meridian(closest)
        # Cap: radial. Fillet: towards the fillet circle's centre (it is concave). Flange: +z.
        normal_r = np.where(region == _CAP, r / self.radius_m, 0.0)
        normal_z = np.where(region == _CAP, z / self.radius_m, 1.0)
        is_fillet = region == _FILLET
        normal_r = np.where(
            is_fillet, (self.fillet_foot_radius_m - r) / self.fillet_radius_m, normal_r
        )
        normal_z = np.where(is_fillet, (self.fillet_radius_m - z) / self.fillet_radius_m, normal_z)
        normals = _from_meridian(normal_r, normal_z, cos_az, sin_az)
        return normals / np.linalg.norm(normals, axis=1, keepdims=True)

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

_LATERAL, _TOP = 0, 1


class Cone:
    """A cone, apex up, base circle of radius ``base_radius_m`` [m] on z = 0, height
    ``height_m`` [m]; with ``top_radius_m`` > 0 it is truncated by a flat top disc at z = height.

    The tool is the lateral surface plus the top disc; it ends at the base circle (no flange).
    ``size`` is the base radius. At the (sharp) apex the normal is taken as +z.
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

    def _closest(self, points: FloatArray) -> tuple[FloatArray, FloatArray, IntArray]:
        r, z, cos_az, sin_az = _to_meridian(points)
        rim = (self.base_radius_m, 0.0)
        top_edge = (self.top_radius_m, self.height_m)
        lateral = _from_meridian(*_closest_on_segment(r, z, rim, top_edge), cos_az, sin_az)
        top = _from_meridian(
            *_closest_on_segment(r, z, (0.0, self.height_m), top_edge), cos_az, sin_az
        )
        return _pick_nearest(points, np.stack((lateral, top)))

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest surface points (n, 3) [m] to ``points`` (n, 3) [m] and distances (n,) [m]."""
        closest, distance, _ = self._closest(_as_points(points, 3))
        return closest, distance

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at surface points (n, 3) [m] (the normal of the closest
        surface point for points off the surface)."""
        closest, _, region = self._closest(_as_points(points, 3))
        r, _, cos_az, sin_az = _to_meridian(closest)
        use_top = (region == _TOP) | (r == 0.0)
        normal_r = np.where(use_top, 0.0, self._lateral_normal[0])
        normal_z = np.where(use_top, 1.0, self._lateral_normal[1])
        return _from_meridian(normal_r, normal_z, cos_az, sin_az)

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


class EllipsoidDome:
    """The upper half (z ≥ 0) of the ellipsoid (x/a)² + (y/b)² + (z/c)² = 1, semi-axes
    ``semi_axes_m = (a, b, c)`` [m]. The tool ends at the base ellipse on z = 0 (no flange);
    ``size`` is the largest semi-axis.

    Closest points are exact for every query point with z ≥ 0 (the side the fabric is on): the
    nearest point of the whole ellipsoid then lies in the upper half. Below the base plane (under
    the tool, where no fabric goes) the answer is the nearer of the base-rim foot and the foot of
    the query mirrored in z = 0: always a surface point, not guaranteed to be the nearest.
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

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest surface points (n, 3) [m] to ``points`` (n, 3) [m] and distances (n,) [m]."""
        p = _as_points(points, 3)
        sign = np.where(p < 0.0, -1.0, 1.0)
        foot = _ellipsoid_foot(np.abs(p), self.semi_axes_m)
        closest = foot * sign
        below = p[:, 2] < 0.0
        if np.any(below):
            q = p[below]
            mirrored = foot[below] * np.column_stack((sign[below, :2], np.ones(q.shape[0])))
            rim_plan = _ellipsoid_foot(np.abs(q[:, :2]), self.semi_axes_m[:2]) * sign[below, :2]
            rim = np.column_stack((rim_plan, np.zeros(q.shape[0])))
            closest[below] = _pick_nearest(q, np.stack((mirrored, rim)))[0]
        return closest, np.linalg.norm(closest - p, axis=1)

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at surface points (n, 3) [m] (the gradient of the
        implicit function at the closest surface point)."""
        closest, _ = self.closest_point(points)
        gradient = closest / self.semi_axes_m**2
        return gradient / np.linalg.norm(gradient, axis=1, keepdims=True)

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Surface points (n, 3) [m] above plan positions ``xy`` (n, 2) [m] and whether each
        lies over the tool (inside the base ellipse). Off the tool z = 0."""
        plan = _as_points(xy, 2)
        a, b, c = self.semi_axes_m
        height_sq = 1.0 - (plan[:, 0] / a) ** 2 - (plan[:, 1] / b) ** 2
        over_tool = height_sq >= 0.0
        return np.column_stack((plan, c * np.sqrt(np.maximum(height_sq, 0.0)))), over_tool


# --- paraboloid ------------------------------------------------------------------------------


class ParaboloidDome:
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

    def _meridian_root(self, r_p: FloatArray, z_p: FloatArray) -> FloatArray:
        k = self._curvature
        cubic = 2.0 * k * k
        linear = 1.0 - 2.0 * k * (self.height_m - z_p)
        # Start right of the root: at r_a = √(max(−linear, 0)/cubic) the cubic part vanishes and
        # adding ∛(r_p/cubic) makes f ≥ 0 (see the class docstring for the convexity argument).
        r = np.sqrt(np.maximum(-linear, 0.0) / cubic) + np.cbrt(r_p / cubic)
        for _ in range(100):
            f = cubic * r**3 + linear * r - r_p
            slope = 3.0 * cubic * r * r + linear
            step = np.where(slope > 0.0, f / np.where(slope > 0.0, slope, 1.0), 0.0)
            r = np.maximum(r - step, 0.0)
            if np.all(np.abs(step) <= 4.0 * np.finfo(float).eps * np.maximum(r, self.radius_m)):
                break
        return np.clip(r, 0.0, self.radius_m)

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest surface points (n, 3) [m] to ``points`` (n, 3) [m] and distances (n,) [m]."""
        p = _as_points(points, 3)
        r_p, z_p, cos_az, sin_az = _to_meridian(p)
        r = self._meridian_root(r_p, z_p)
        closest = _from_meridian(r, self.height_m - self._curvature * r * r, cos_az, sin_az)
        return closest, np.linalg.norm(closest - p, axis=1)

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at surface points (n, 3) [m] (at the closest surface
        point for points off the surface)."""
        closest, _ = self.closest_point(points)
        r, _, cos_az, sin_az = _to_meridian(closest)
        normals = _from_meridian(2.0 * self._curvature * r, np.ones_like(r), cos_az, sin_az)
        return normals / np.linalg.norm(normals, axis=1, keepdims=True)

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Surface points (n, 3) [m] above plan positions ``xy`` (n, 2) [m] and whether each
        lies over the tool (r ≤ R). Off the tool z = 0."""
        plan = _as_points(xy, 2)
        r_sq = plan[:, 0] ** 2 + plan[:, 1] ** 2
        over_tool = r_sq <= self.radius_m**2
        z = np.where(over_tool, self.height_m * (1.0 - r_sq / self.radius_m**2), 0.0)
        return np.column_stack((plan, z)), over_tool
