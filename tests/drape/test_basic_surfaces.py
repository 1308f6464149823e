"""The analytic surfaces: the Surface contract and their closed forms, against geometry."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape.engine.generators import ClosedFormGeodesics
from preform.drape.engine.net import ClosedFormPlacement
from preform.drape.engine.result import NodeStatus
from preform.drape.engine.surface import Surface
from preform.plugins.surfaces.basic import Cylinder, Hemisphere, Plane, Sphere

RNG = np.random.default_rng(7)
SURFACES = [
    Plane((2.0, 1.0), centre_m=(0.1, -0.2, 0.3)),
    Sphere(0.4, centre_m=(0.1, 0.0, -0.05)),
    Hemisphere(0.5),
    Cylinder(0.3, 1.2, "x", centre_m=(0.0, 0.1, 0.0)),
    Cylinder(0.3, 1.2, "y"),
]


@pytest.mark.parametrize("surface", SURFACES, ids=repr)
def test_contract(surface: Surface) -> None:
    assert isinstance(surface, Surface)
    (lo, hi) = np.array(surface.bounds)
    points = lo + (hi - lo) * RNG.uniform(-0.5, 1.5, size=(500, 3))
    foot, dist = surface.closest_point(points)
    # The closest point is on the surface (projecting again does not move it) and no other
    # sampled surface point is closer.
    again, dist0 = surface.closest_point(foot)
    np.testing.assert_allclose(again, foot, atol=1e-12 * surface.size)
    assert np.all(dist0 <= 1e-12 * surface.size)
    np.testing.assert_allclose(dist, np.linalg.norm(points - foot, axis=1), rtol=1e-12)
    sample, _ = surface.closest_point(lo + (hi - lo) * RNG.uniform(size=(4000, 3)))
    brute = np.min(np.linalg.norm(points[:, None, :] - sample[None, :, :], axis=2), axis=1)
    assert np.all(dist <= brute + 1e-12)
    assert np.all(foot >= lo - 1e-12) and np.all(foot <= hi + 1e-12)
    normals = surface.normal(foot)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, rtol=1e-12)


@pytest.mark.parametrize("surface", SURFACES, ids=repr)
def test_point_at_plan_is_the_top_of_the_surface(surface: Surface) -> None:
    (lo, hi) = np.array(surface.bounds)
    xy = lo[:2] + (hi[:2] - lo[:2]) * RNG.uniform(-0.2, 1.2, size=(400, 2))
    pts, mask = surface.point_at_plan(xy)
    assert mask.any() and (~mask).any()
    assert np.all(np.isnan(pts[~mask]))
    np.testing.assert_allclose(pts[mask, :2], xy[mask])
    _, dist = surface.closest_point(pts[mask])
    assert np.all(dist <= 1e-12 * surface.size)
    # Topmost: the normal there points up (or sideways at a silhouette).
    assert np.all(surface.normal(pts[mask])[:, 2] >= -1e-12)
    # Off the tool in plan: no point of the surface lies above those positions.
    top, _ = surface.closest_point(np.column_stack([xy[~mask], np.full((~mask).sum(), hi[2])]))
    assert np.all(np.linalg.norm(top[:, :2] - xy[~mask], axis=1) > 1e-9)


def test_sphere_normals_are_radial_and_outward() -> None:
    s = Sphere(2.0, centre_m=(1.0, 2.0, 3.0))
    p = s.centre + 2.0 * np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.6, 0.0, -0.8]])
    np.testing.assert_allclose(s.normal(p), (p - s.centre) / 2.0)


def test_hemisphere_projects_points_below_the_rim_onto_the_rim() -> None:
    h = Hemisphere(1.0)
    foot, dist = h.closest_point(np.array([[2.0, 0.0, -1.0], [0.0, 0.5, -0.1]]))
    np.testing.assert_allclose(foot, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], atol=1e-15)
    np.testing.assert_allclose(dist, [np.sqrt(2.0), np.hypot(0.5, 0.1)])
    assert h.bounds[0][2] == 0.0


def test_cylinder_rejects_a_vertical_axis() -> None:
    with pytest.raises(ValueError, match="horizontal"):
        Cylinder(1.0, 1.0, "z")


unit = st.floats(-1.0, 1.0)


@settings(max_examples=60, deadline=None)
@given(
    theta=st.floats(0.0, 1.4),
    phi=st.floats(-np.pi, np.pi),
    gamma=st.floats(0.3, 2.8),
    d=st.floats(0.01, 0.5),
)
def test_sphere_place_nodes_solves_the_two_distance_constraints(
    theta: float, phi: float, gamma: float, d: float
) -> None:
    """The closed form lies on the sphere at chord d from a and b, on the far side from c."""
    s = Sphere(1.3, centre_m=(0.2, -0.1, 0.4))
    r = s.radius
    # A rhombus-like configuration: c, then a and b at chord d from c with angle gamma at c.
    c_dir = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    c = s.centre + r * c_dir
    e1 = np.cross(c_dir, [0.3, 0.5, 0.8])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(c_dir, e1)
    step = 2.0 * np.arcsin(d / (2.0 * r))

    def along(direction: np.ndarray) -> np.ndarray:
        return s.centre + r * (np.cos(step) * c_dir + np.sin(step) * direction)

    a = along(e1)
    b = along(np.cos(gamma) * e1 + np.sin(gamma) * e2)
    p, status = s.place_nodes(a[None], b[None], c[None], d)
    assert status[0] == NodeStatus.PLACED
    p = p[0]
    assert abs(np.linalg.norm(p - s.centre) - r) <= 1e-12 * r
    assert abs(np.linalg.norm(p - a) - d) <= 1e-12 * r
    assert abs(np.linalg.norm(p - b) - d) <= 1e-12 * r
    # Away from c: the other root is c itself, so p is the mirror of c through plane (0, a, b).
    n = np.cross(a - s.centre, b - s.centre)
    n /= np.linalg.norm(n)
    mirror = c - 2.0 * np.dot(c - s.centre, n) * n
    np.testing.assert_allclose(p, mirror, atol=1e-10 * r)


def test_place_nodes_reports_no_intersection_and_off_tool() -> None:
    h = Hemisphere(1.0)
    d = 0.1
    a = np.array([[0.0, 0.0, 1.0]])
    far = np.array([[np.sin(0.3), 0.0, np.cos(0.3)]])  # chord ≈ 0.3 > 2d
    _, status = h.place_nodes(a, far, a, d)
    assert status[0] == NodeStatus.NO_INTERSECTION
    # Near the rim, the far-side root lies below the equator.
    step = 2 * np.arcsin(d / 2)
    c = np.array([[np.cos(0.02), 0.0, np.sin(0.02)]])
    a = np.array([[np.cos(0.02) * np.cos(step), np.cos(0.02) * np.sin(step), np.sin(0.02)]])
    b = np.array([[np.cos(0.02 - step), 0.0, np.sin(0.02 - step)]])
    p, status = h.place_nodes(a, b, c, d)
    assert status[0] == NodeStatus.OFF_TOOL and np.all(np.isnan(p))
    # The full sphere accepts the same node.
    _, status = Sphere(1.0).place_nodes(a, b, c, d)
    assert status[0] == NodeStatus.PLACED


@pytest.mark.parametrize("surface", [Plane((3.0, 3.0)), Sphere(0.7), Hemisphere(0.7)], ids=repr)
def test_closed_form_geodesics_have_chord_d_and_stay_in_one_plane(surface: Surface) -> None:
    assert isinstance(surface, ClosedFormGeodesics)
    assert isinstance(surface, ClosedFormPlacement)
    start, _ = surface.point_at_plan(np.array([[0.1, 0.05]]))
    n = surface.normal(start)[0]
    t = np.cross(n, [0.0, 1.0, 0.0])
    t /= np.linalg.norm(t)
    d = 0.05
    pts, status = surface.geodesic_nodes(start, t[None], d, 30)
    ok = status[0] == NodeStatus.PLACED
    chain = np.vstack([start, pts[0][ok]])
    np.testing.assert_allclose(np.linalg.norm(np.diff(chain, axis=0), axis=1), d, rtol=1e-12)
    # A great circle / straight line: every node in the plane through the start spanned by the
    # normal and the direction (it contains the sphere's centre).
    plane_normal = np.cross(n, t)
    assert np.all(np.abs((chain - start) @ plane_normal) <= 1e-12)
    if isinstance(surface, Hemisphere):
        # Past the rim: one OFF_TOOL, nothing placed after it.
        assert (~ok).any()
        assert np.all(chain[:, 2] >= -1e-12)
