"""Analytic dome surfaces checked against truths written independently here: each surface's
implicit equation, a dense sampling of it from its own parametrisation (a closest point can be
no farther than any surface sample), finite-difference tangents, and the fillet's tangency."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from preform.drape.engine.surface import Surface
from preform.plugins.surfaces.domes import Cone, EllipsoidDome, FlangedHemisphere, ParaboloidDome

R, RHO, W = 0.1, 0.02, 0.2  # flanged hemisphere [m]
FOOT = np.sqrt(R**2 + 2 * R * RHO)  # where the fillet meets the flange
BETA = np.arcsin(RHO / (R + RHO))  # elevation of the sphere/fillet seam
ABC = (0.12, 0.08, 0.05)  # ellipsoid semi-axes [m]
TOL = 1e-12 * R

Param = Callable[[np.ndarray, np.ndarray], np.ndarray]


def revolve(r: np.ndarray, z: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    return np.column_stack((r * np.cos(azimuth), r * np.sin(azimuth), z))


# Each surface as pieces parametrised over (u, v) in [0, 1]², independent of the code under test.
def flanged_pieces(shape: str) -> list[Param]:
    def cap(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        elevation = BETA + u * (np.pi / 2 - BETA)
        return revolve(R * np.cos(elevation), R * np.sin(elevation), 2 * np.pi * v)

    def fillet(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        t = np.pi + BETA + u * (np.pi / 2 - BETA)
        return revolve(FOOT + RHO * np.cos(t), RHO + RHO * np.sin(t), 2 * np.pi * v)

    def flange(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        # Polar over the annulus out to the square's corner; the sampler drops points outside.
        r = FOOT + u * (W * np.sqrt(2) - FOOT) if shape == "square" else FOOT + u * (W - FOOT)
        return revolve(r, np.zeros_like(r), 2 * np.pi * v)

    return [cap, fillet, flange]


def cone_pieces(radius: float, height: float, top: float) -> list[Param]:
    def lateral(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return revolve(radius - u * (radius - top), u * height, 2 * np.pi * v)

    def top_disc(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return revolve(u * top, np.full_like(u, height), 2 * np.pi * v)

    return [lateral, top_disc] if top > 0 else [lateral]


def ellipsoid_pieces(a: float, b: float, c: float) -> list[Param]:
    def dome(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        polar, azimuth = u * np.pi / 2, 2 * np.pi * v
        return np.column_stack(
            (
                a * np.sin(polar) * np.cos(azimuth),
                b * np.sin(polar) * np.sin(azimuth),
                c * np.cos(polar),
            )
        )

    return [dome]


def paraboloid_pieces(radius: float, height: float) -> list[Param]:
    def dome(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return revolve(radius * u, height * (1 - u**2), 2 * np.pi * v)

    return [dome]


def flanged_residual(q: np.ndarray, shape: str) -> np.ndarray:
    """Distance-like residual of q from the implicit equation of the piece whose domain holds it."""
    r, z = np.hypot(q[:, 0], q[:, 1]), q[:, 2]
    slack = 1e-9 * R
    seam_z = R * np.sin(BETA)
    cap = np.where(z >= seam_z - slack, np.abs(np.linalg.norm(q, axis=1) - R), np.inf)
    torus = np.abs(np.hypot(r - FOOT, z - RHO) - RHO)
    fillet = np.where((z <= seam_z + slack) & (r <= FOOT + slack), torus, np.inf)
    if shape == "square":
        inside = np.max(np.abs(q[:, :2]), axis=1) <= W + slack
    else:
        inside = r <= W + slack
    flange = np.where((r >= FOOT - slack) & inside, np.abs(z), np.inf)
    return np.minimum(np.minimum(cap, fillet), flange)


def cone_residual(q: np.ndarray, radius: float, height: float, top: float) -> np.ndarray:
    r, z = np.hypot(q[:, 0], q[:, 1]), q[:, 2]
    slack = 1e-9 * radius
    # Distance from the lateral line, measured perpendicular to it.
    lateral = np.abs((z - height * (radius - r) / (radius - top)) * (radius - top)) / np.hypot(
        height, radius - top
    )
    lateral = np.where((z >= -slack) & (z <= height + slack), lateral, np.inf)
    top_disc = np.where(r <= top + slack, np.abs(z - height), np.inf)
    return np.minimum(lateral, top_disc)


SHAPES: dict[str, tuple[Surface, list[Param], Callable[[np.ndarray], np.ndarray]]] = {
    "flanged_square": (
        FlangedHemisphere(R, RHO, W),
        flanged_pieces("square"),
        lambda q: flanged_residual(q, "square"),
    ),
    "flanged_circle": (
        FlangedHemisphere(R, RHO, W, flange_shape="circle"),
        flanged_pieces("circle"),
        lambda q: flanged_residual(q, "circle"),
    ),
    "cone": (
        Cone(0.1, 0.08),
        cone_pieces(0.1, 0.08, 0.0),
        lambda q: cone_residual(q, 0.1, 0.08, 0.0),
    ),
    "truncated_cone": (
        Cone(0.1, 0.08, top_radius_m=0.04),
        cone_pieces(0.1, 0.08, 0.04),
        lambda q: cone_residual(q, 0.1, 0.08, 0.04),
    ),
    "ellipsoid": (
        EllipsoidDome(ABC),
        ellipsoid_pieces(*ABC),
        lambda q: np.where(
            q[:, 2] >= 0, np.abs(np.sum((q / np.array(ABC)) ** 2, axis=1) - 1) * min(ABC), np.inf
        ),
    ),
    "paraboloid": (
        ParaboloidDome(0.1, 0.07),
        paraboloid_pieces(0.1, 0.07),
        lambda q: np.where(
            np.hypot(q[:, 0], q[:, 1]) <= 0.1 * (1 + 1e-12),
            np.abs(q[:, 2] - 0.07 * (1 - (q[:, 0] ** 2 + q[:, 1] ** 2) / 0.01)),
            np.inf,
        ),
    ),
}


def sample(surface: Surface, pieces: list[Param], n: int = 400) -> np.ndarray:
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n, endpoint=False))
    points = np.concatenate([piece(u.ravel(), v.ravel()) for piece in pieces])
    low, high = np.array(surface.bounds[0]), np.array(surface.bounds[1])
    return points[np.all((points >= low - 1e-12) & (points <= high + 1e-12), axis=1)]


SAMPLE_TREES = {name: cKDTree(sample(s, pieces)) for name, (s, pieces, _) in SHAPES.items()}

coordinate = st.one_of(
    st.just(0.0), st.floats(-0.3, 0.3, allow_nan=False), st.floats(-1e-9, 1e-9, allow_nan=False)
)


def check_closest(name: str, points: np.ndarray) -> None:
    surface, _, residual = SHAPES[name]
    closest, distance = surface.closest_point(points)
    assert closest.shape == points.shape and distance.shape == (points.shape[0],)
    np.testing.assert_allclose(distance, np.linalg.norm(closest - points, axis=1), atol=1e-15)
    # On the surface: the implicit equation of some piece holds to round-off.
    assert np.all(residual(closest) <= TOL)
    # Closest: no sampled surface point is nearer.
    sample_distance, _ = SAMPLE_TREES[name].query(points)
    assert np.all(distance <= sample_distance + 1e-13)


@pytest.mark.parametrize("name", list(SHAPES))
@settings(max_examples=60, deadline=None)
@given(x=coordinate, y=coordinate, z=coordinate)
def test_closest_point_is_on_the_surface_and_nearest(
    name: str, x: float, y: float, z: float
) -> None:
    if name == "ellipsoid":
        z = abs(z)  # exact only above the base plane (documented); below: see the next test
    check_closest(name, np.array([[x, y, z]]))


@pytest.mark.parametrize("name", list(SHAPES))
def test_closest_point_batch(name: str) -> None:
    rng = np.random.default_rng(7)
    points = rng.uniform(-0.3, 0.3, (3000, 3))
    if name == "ellipsoid":
        points[:, 2] = np.abs(points[:, 2])
    # Points just off the surface, where the drape engine asks most.
    surface, pieces, _ = SHAPES[name]
    on = sample(surface, pieces, 60)
    near = on + rng.normal(scale=1e-3, size=on.shape)
    if name == "ellipsoid":
        near[:, 2] = np.abs(near[:, 2])
    check_closest(name, np.concatenate((points, near)))


def test_ellipsoid_below_base_answers_a_surface_point() -> None:
    surface, _, residual = SHAPES["ellipsoid"]
    points = np.random.default_rng(3).uniform(-0.3, 0.3, (2000, 3))
    points[:, 2] = -np.abs(points[:, 2])
    closest, _ = surface.closest_point(points)
    assert np.all(residual(closest) <= TOL)


def test_ellipsoid_degenerate_queries() -> None:
    a, _, c = ABC
    dome = EllipsoidDome(ABC)
    # The centre: nearest is the end of the shortest (z) semi-axis.
    closest, distance = dome.closest_point(np.zeros((1, 3)))
    np.testing.assert_allclose(closest, [[0, 0, c]], atol=1e-15)
    assert distance[0] == pytest.approx(c)
    # On the long axis inside beyond its evolute point (a − c²/a from the centre): the foot is
    # the axis end; nearer the centre it leaves the axis.
    closest, distance = dome.closest_point(np.array([[a - 0.5 * c * c / a, 0.0, 0.0]]))
    np.testing.assert_allclose(closest, [[a, 0, 0]], atol=1e-14)
    # A sphere is the special case a = b = c with the closed form R p / |p|.
    sphere = EllipsoidDome((R, R, R))
    points = np.random.default_rng(1).uniform(-0.3, 0.3, (500, 3))
    points[:, 2] = np.abs(points[:, 2])
    closest, _ = sphere.closest_point(points)
    np.testing.assert_allclose(
        closest, R * points / np.linalg.norm(points, axis=1, keepdims=True), atol=1e-15
    )


@pytest.mark.parametrize("name", list(SHAPES))
def test_normals_are_unit_outward_and_orthogonal_to_tangents(name: str) -> None:
    surface, pieces, _ = SHAPES[name]
    grid_u, grid_v = np.meshgrid(
        np.linspace(0.02, 0.98, 25), np.linspace(0.0, 1.0, 24, endpoint=False)
    )
    u, v = grid_u.ravel(), grid_v.ravel()
    step = 1e-6
    for piece in pieces:
        points = piece(u, v)
        keep = np.all(points[:, :2] <= surface.bounds[1][:2], axis=1)
        keep &= np.all(points[:, :2] >= surface.bounds[0][:2], axis=1)
        normals = surface.normal(points[keep])
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-14)
        assert np.all(normals[:, 2] >= -1e-15)  # dome tools face up or sideways, never down
        for du, dv in ((step, 0.0), (0.0, step)):
            tangent = (piece(u + du, v + dv) - piece(u - du, v - dv))[keep]
            length = np.linalg.norm(tangent, axis=1)
            moving = length > 1e-12  # the azimuth tangent vanishes on the axis
            cosine = np.abs(np.sum(normals * tangent, axis=1))[moving] / length[moving]
            assert np.all(cosine < 1e-7)


def test_flanged_hemisphere_is_tangent_continuous_across_its_seams() -> None:
    surface = FlangedHemisphere(R, RHO, W)
    azimuth = np.linspace(0, 2 * np.pi, 13)
    delta = 1e-7  # arc length [m] either side of a seam
    seam = revolve(
        np.full_like(azimuth, R * np.cos(BETA)), np.full_like(azimuth, R * np.sin(BETA)), azimuth
    )
    # Step along the meridian tangent at the seam (perpendicular to the shared normal).
    tangent = revolve(
        np.full_like(azimuth, -np.sin(BETA)), np.full_like(azimuth, np.cos(BETA)), azimuth
    )
    foot = revolve(np.full_like(azimuth, FOOT), np.zeros_like(azimuth), azimuth)
    radial = revolve(np.ones_like(azimuth), np.zeros_like(azimuth), azimuth)
    for point, direction in ((seam, tangent), (foot, radial)):
        before = surface.normal(point - delta * direction)
        after = surface.normal(point + delta * direction)
        # A kink would give an O(1) jump; curvature alone gives at most δ(1/R + 1/ρ).
        assert np.max(np.linalg.norm(after - before, axis=1)) <= 1.01 * delta * (1 / R + 1 / RHO)
    # Heights and slopes from above are continuous too (C¹ height field).
    r = np.array([R * np.cos(BETA), FOOT])
    h = 1e-9
    heights = {
        s: surface.point_at_plan(np.column_stack((r + s * h, np.zeros(2))))[0][:, 2]
        for s in (-2, -1, 1, 2)
    }
    slope_in = (heights[-1] - heights[-2]) / h
    slope_out = (heights[2] - heights[1]) / h
    np.testing.assert_allclose(heights[1], heights[-1] + 2 * h * slope_in, atol=1e-13)
    np.testing.assert_allclose(slope_in, slope_out, atol=1e-4)
    assert slope_in[0] == pytest.approx(-1 / np.tan(BETA), rel=1e-4)  # the sphere's own slope


@pytest.mark.parametrize("name", list(SHAPES))
def test_point_at_plan_gives_surface_points_and_masks_off_tool(name: str) -> None:
    surface, _, residual = SHAPES[name]
    plan = np.random.default_rng(5).uniform(-0.3, 0.3, (4000, 2))
    points, over_tool = surface.point_at_plan(plan)
    np.testing.assert_array_equal(points[:, :2], plan)
    assert np.all(residual(points[over_tool]) <= 1e-11 * R)
    assert np.all(points[~over_tool, 2] == 0.0)
    _, distance = surface.closest_point(points[over_tool])
    assert np.all(distance <= 1e-11 * R)
    low, high = surface.bounds[0], surface.bounds[1]
    outside_box = np.any((plan < low[:2]) | (plan > high[:2]), axis=1)
    assert not np.any(over_tool & outside_box)
    assert np.any(over_tool) and np.any(~over_tool)


def test_point_at_plan_heights_match_the_formulas() -> None:
    r = np.linspace(0, 0.099, 50)
    plan = np.column_stack((r, np.zeros_like(r)))
    np.testing.assert_allclose(
        Cone(0.1, 0.08).point_at_plan(plan)[0][:, 2], 0.8 * (0.1 - r), atol=1e-15
    )
    np.testing.assert_allclose(
        ParaboloidDome(0.1, 0.07).point_at_plan(plan)[0][:, 2], 0.07 * (1 - r**2 / 0.01), atol=1e-15
    )
    cap = r <= R * np.cos(BETA)
    height = FlangedHemisphere(R, RHO, W).point_at_plan(plan)[0][:, 2]
    np.testing.assert_allclose(height[cap], np.sqrt(R**2 - r[cap] ** 2), atol=1e-15)
    assert FlangedHemisphere(R, RHO, W).point_at_plan(np.array([[0.19, 0.19]]))[1][0]
    assert not FlangedHemisphere(R, RHO, W, flange_shape="circle").point_at_plan(
        np.array([[0.19, 0.19]])
    )[1][0]


@pytest.mark.parametrize(
    ("build", "argument"),
    [
        (lambda: FlangedHemisphere(-0.1, 0.01, 0.2), "radius_m"),
        (lambda: FlangedHemisphere(0.1, 0.0, 0.2), "fillet_radius_m"),
        (lambda: FlangedHemisphere(0.1, 0.1, 0.3), "fillet_radius_m"),
        (lambda: FlangedHemisphere(0.1, 0.02, 0.11), "flange_half_width_m"),
        (lambda: FlangedHemisphere(0.1, 0.02, 0.2, flange_shape="hex"), "flange_shape"),
        (lambda: Cone(0.0, 0.1), "base_radius_m"),
        (lambda: Cone(0.1, float("nan")), "height_m"),
        (lambda: Cone(0.1, 0.1, top_radius_m=0.1), "top_radius_m"),
        (lambda: EllipsoidDome((0.1, 0.1)), "semi_axes_m"),
        (lambda: EllipsoidDome((0.1, -0.1, 0.1)), r"semi_axes_m\[1\]"),
        (lambda: ParaboloidDome(0.1, 0.0), "height_m"),
    ],
)
def test_invalid_arguments_are_named(build: Callable[[], object], argument: str) -> None:
    with pytest.raises(ValueError, match=argument):
        build()


def test_surfaces_satisfy_the_protocol() -> None:
    for surface, _, _ in SHAPES.values():
        assert isinstance(surface, Surface)
        assert surface.size > 0
