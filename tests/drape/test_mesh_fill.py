"""The mesh's compiled fill (``TriangleMesh.fill_fronts``, one compiled loop over the net)
against the front-by-front loop over its vectorised walking placement, the same node step;
``use_closed_form=False`` on a mesh keeps the walk; the walk's prune of triangles far from
the constraint circle keeps every root on a plane of slivers (a net on a plane is the flat
rhombus lattice); and ``corner_reach`` against the sine of half the corner angle."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape import PlyOutline, drape
from preform.drape.engine.net import WalkingFill, WalkingPlacement
from preform.drape.engine.result import NodeStatus
from preform.plugins.surfaces.mesh import TriangleMesh, read_obj, tessellate_hemisphere
from preform.plugins.surfaces.mesh_topology import build_topology

HAT = Path(__file__).resolve().parents[2] / "materials" / "tools" / "hat_mould.obj"


class FrontByFront:
    """A mesh without its compiled fill: the drape takes the front loop over
    ``place_nodes_from_faces`` (the vectorised kernel over each front)."""

    def __init__(self, mesh: TriangleMesh) -> None:
        self.mesh = mesh

    def __getattr__(self, name: str) -> Any:
        if name == "fill_fronts":
            raise AttributeError(name)
        return getattr(self.mesh, name)


def nets(surface: Any, **kwargs: Any) -> Any:
    return drape(surface, **kwargs), drape(FrontByFront(surface), **kwargs)


def assert_same_net(one: Any, other: Any) -> None:
    np.testing.assert_array_equal(one.status, other.status)
    np.testing.assert_array_equal(one.nodes, other.nodes)
    np.testing.assert_array_equal(one.residual, other.residual)
    assert one.info["fronts"] == other.info["fronts"]


def test_the_wrapper_takes_the_front_loop() -> None:
    mesh = tessellate_hemisphere(0.1, 8)
    assert isinstance(mesh, WalkingFill)
    assert not isinstance(FrontByFront(mesh), WalkingFill)
    assert isinstance(FrontByFront(mesh), WalkingPlacement)


@pytest.mark.parametrize("alpha_deg", [90.0, 60.0])
@pytest.mark.parametrize("feature_angle_deg", [180.0, 30.0])
def test_the_compiled_fill_is_the_front_loop_on_the_hat_mould(
    alpha_deg: float, feature_angle_deg: float
) -> None:
    """Vertical walls, creases (over a feature or by the chord) and folds at the block
    corners: the same statuses, nodes, residuals and fronts, to the bit."""
    hat = read_obj(HAT, feature_angle_deg=feature_angle_deg)
    compiled, front_loop = nets(
        hat,
        node_spacing_m=5e-3,
        ply=PlyOutline.rectangle((0.36, 0.36)),
        start_xy_m=(0.004, 0.003),
        generator_angle_rad=math.radians(alpha_deg),
    )
    assert {NodeStatus.PLACED, NodeStatus.FOLDED} <= set(np.unique(compiled.status))
    assert_same_net(compiled, front_loop)


@settings(max_examples=10, deadline=None)
@given(
    start=st.tuples(st.floats(-0.05, 0.05), st.floats(-0.05, 0.05)),
    orientation=st.floats(0.0, math.pi),
    alpha=st.floats(0.6, math.pi - 0.6),
    nodes_across=st.integers(8, 60),
)
def test_the_compiled_fill_is_the_front_loop_on_a_hemisphere(
    start: tuple[float, float], orientation: float, alpha: float, nodes_across: int
) -> None:
    """Any start, orientation and angle, nets running off the rim (OFF_TOOL) included."""
    compiled, front_loop = nets(
        tessellate_hemisphere(0.1, 20),
        node_spacing_m=0.24 / nodes_across,
        ply=PlyOutline.rectangle((0.24, 0.24)),
        start_xy_m=start,
        orientation_rad=orientation,
        generator_angle_rad=alpha,
    )
    assert NodeStatus.OFF_TOOL in compiled.status
    assert_same_net(compiled, front_loop)


def test_use_closed_form_false_keeps_the_walk_on_a_mesh() -> None:
    """A mesh has no closed form to leave: the flag changes nothing, and the result says so."""
    kwargs: dict[str, Any] = dict(
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.24, 0.24)),
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=math.radians(80.0),
    )
    mesh = tessellate_hemisphere(0.1, 20)
    walked = drape(mesh, **kwargs)
    asked = drape(mesh, use_closed_form=False, **kwargs)
    assert asked.info["placement"] == "walking exact"
    assert_same_net(walked, asked)


def sliver_strip(steps: int, width: float, depth: float) -> TriangleMesh:
    """The plane z = 0, x in [0, width], y in [0, depth], cut into 2·steps triangles each
    width/steps wide and depth tall: corner angles of about width/(steps·depth) rad."""
    x = np.linspace(0.0, width, steps + 1)
    bottom = np.column_stack((x, np.zeros_like(x), np.zeros_like(x)))
    top = np.column_stack((x, np.full_like(x, depth), np.zeros_like(x)))
    i = np.arange(steps)
    b, t = i, i + steps + 1
    faces = np.concatenate((np.column_stack((b, b + 1, t)), np.column_stack((b + 1, t + 1, t))))
    return TriangleMesh(np.vstack((bottom, top)), faces)


@pytest.mark.parametrize("steps", [200, 2000])
def test_a_net_on_a_plane_of_slivers_is_the_flat_lattice(steps: int) -> None:
    """Triangles 1 m tall and 5 mm or 0.5 mm wide (corner angles of 5e-3 and 5e-4 rad, where
    the inside test's tolerance reaches farthest past a corner): every node of the ply is
    placed, at start + i·d·u + j·d·v, the flat net's closed form."""
    mesh = sliver_strip(steps, 1.0, 1.0)
    d, alpha, theta = 0.02, math.radians(70.0), 0.3
    net = drape(
        mesh,
        node_spacing_m=d,
        ply=PlyOutline.rectangle((0.6, 0.6)),
        start_xy_m=(0.5, 0.5),
        orientation_rad=theta,
        generator_angle_rad=alpha,
    )
    assert np.all(net.status == NodeStatus.PLACED)
    i0, j0 = net.start_index
    i, j = np.meshgrid(
        np.arange(net.status.shape[0]) - i0, np.arange(net.status.shape[1]) - j0, indexing="ij"
    )
    u = np.array([math.cos(theta), math.sin(theta), 0.0])
    v = np.array([math.cos(theta + alpha), math.sin(theta + alpha), 0.0])
    lattice = np.array([0.5, 0.5, 0.0]) + d * (i[..., None] * u + j[..., None] * v)
    assert np.max(np.abs(net.nodes - lattice)) < 1e-12


def test_corner_reach_is_one_over_the_sine_of_half_the_sharpest_corner() -> None:
    """An equilateral triangle (60° corners: 1/sin 30° = 2), a right isosceles one (45°:
    1/sin 22.5°) and a sliver of corner angle ε (about 2/ε)."""
    eps = 1e-4
    vertices = np.array(
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, math.sqrt(3.0) / 2.0, 0.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [4.0, 0.0, 0.0],
            [5.0, 0.0, 0.0],
            [4.0, eps, 0.0],
        ]
    )
    faces = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8]])
    normals = np.tile([0.0, 0.0, 1.0], (3, 1))
    reach = build_topology(vertices, faces, normals).corner_reach
    sliver = math.atan(eps)  # the angle at (5, 0)
    np.testing.assert_allclose(
        reach, [2.0, 1.0 / math.sin(math.pi / 8.0), 1.0 / math.sin(sliver / 2.0)], rtol=1e-9
    )
