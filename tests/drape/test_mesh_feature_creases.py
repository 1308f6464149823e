"""Fibres crossing a sharp crease at an angle: the net is spaced by the length along the surface.

Truth used: a plate folded along a straight sharp crease is developable, and a tow lying on it
is inextensible along its own path, which bends over the crease. So the draped net, unfolded
back into the plane (the far flank turned about the crease into the near flank's plane), must
be the flat net itself: node (i, j) at start + i·d·e_u + j·d·e_v, whatever the fold angle, the
fibre angle α and the crease's angle to the fibres. That checks every node's placement, every
length and every angle at once (zero shear everywhere). The chord model fails it (the knob at
180° turns the surface-length rule off), so the test can fail.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from preform.drape import PlyOutline, drape
from preform.drape.engine.result import NodeStatus
from preform.plugins.surfaces.mesh import TriangleMesh, read_obj

HAT = Path(__file__).resolve().parents[2] / "materials" / "tools" / "hat_mould.obj"

D = 0.01  # node spacing [m]
FEATURE = 20.0  # the feature angle [°] recommended for tools with sharp creases (physics.md)


def folded_plate(fold_deg: float, feature_angle_deg: float = FEATURE) -> TriangleMesh:
    """The plate z = 0, x < 0, folded at the crease x = z = 0 (along y) by ``fold_deg``: the
    far flank leaves the crease along (cos θ, 0, −sin θ); θ > 0 convex (bends down), θ < 0
    concave (bends up). Grid vertices 2.5 cm apart, so many facets meet the crease."""
    theta = math.radians(fold_deg)
    far = np.array([math.cos(theta), 0.0, -math.sin(theta)])
    n = 13
    s = np.linspace(0.0, 0.3, n)
    y = np.linspace(-0.3, 0.3, 2 * n - 1)
    near = [np.array([-a, b, 0.0]) for a in s[::-1] for b in y]
    beyond = [a * far + np.array([0.0, b, 0.0]) for a in s[1:] for b in y]
    vertices = np.array(near + beyond)
    rows, cols = 2 * n - 1, len(y)
    faces = []
    for i in range(rows - 1):
        for j in range(cols - 1):
            k = i * cols + j
            # x (then along the far flank) × y: normal +z on the near flank
            faces += [[k, k + cols, k + cols + 1], [k, k + cols + 1, k + 1]]
    return TriangleMesh(vertices, np.array(faces), feature_angle_deg=feature_angle_deg)


def unfolded(nodes: np.ndarray, fold_deg: float) -> np.ndarray:
    """Plan positions (…, 2) [m] of nodes on :func:`folded_plate` with its far flank turned
    back into the plane z = 0 about the crease: the flat pattern of the draped net."""
    theta = math.radians(fold_deg)
    far = np.array([math.cos(theta), 0.0, -math.sin(theta)])
    on_near = np.abs(nodes[..., 2]) <= 1e-12
    along = nodes @ far
    flat_x = np.where(on_near, nodes[..., 0], along)
    return np.stack([flat_x, nodes[..., 1]], axis=-1)


def drape_across(
    fold_deg: float,
    alpha_deg: float,
    crease_to_u_deg: float,
    feature_angle_deg: float = FEATURE,
):
    """Drape with the first fibre at ``crease_to_u_deg`` to the crease, started 2.5 d before
    it; returns the result and the flat net's node positions (…, 2) [m]."""
    alpha = math.radians(alpha_deg)
    # The crease runs along +y; u at crease_to_u_deg clockwise from it points across, to +x.
    orientation = 0.5 * math.pi - math.radians(crease_to_u_deg)
    start = np.array([-2.5 * D, 0.0])
    result = drape(
        folded_plate(fold_deg, feature_angle_deg),
        node_spacing_m=D,
        ply=PlyOutline.rectangle((0.12, 0.12)),
        start_xy_m=start,
        orientation_rad=orientation,
        generator_angle_rad=alpha,
    )
    e_u = np.array([math.cos(orientation), math.sin(orientation)])
    e_v = np.array([math.cos(orientation + alpha), math.sin(orientation + alpha)])
    i, j = np.indices(result.status.shape)
    i0, j0 = result.start_index
    flat = start + D * ((i - i0)[..., None] * e_u + (j - j0)[..., None] * e_v)
    return result, flat


@pytest.mark.parametrize("fold_deg", [90.0, 45.0, 135.0, -90.0])
@pytest.mark.parametrize("alpha_deg", [90.0, 70.0])
@pytest.mark.parametrize("crease_to_u_deg", [30.0, 60.0])
def test_a_plate_folded_across_the_fibres_drapes_to_its_flat_pattern(
    fold_deg: float, alpha_deg: float, crease_to_u_deg: float
) -> None:
    result, flat = drape_across(fold_deg, alpha_deg, crease_to_u_deg)
    inside = result.status != NodeStatus.OUTSIDE_PLY
    assert np.all(result.status[inside] == NodeStatus.PLACED)
    nodes = result.nodes[inside]
    beyond = np.abs(nodes[:, 2]) > 1e-12
    assert beyond.sum() > 20 and (~beyond).sum() > 20  # the net is on both flanks
    np.testing.assert_allclose(unfolded(nodes, fold_deg), flat[inside], atol=1e-9)
    # and the residual reported says so: each spacing is d under the surface-length rule
    assert np.all(result.residual[inside] <= 1e-9 * D)
    # so every cell keeps the flat net's angle α (zero shear), as result.shear measures it on
    # the cells lying wholly on one flank
    near = np.abs(result.nodes[..., 2]) <= 1e-12

    def whole(mask: np.ndarray) -> np.ndarray:
        return mask[:-1, :-1] & mask[1:, :-1] & mask[:-1, 1:] & mask[1:, 1:]

    flank = result.valid & (whole(near) | whole(~near & inside))
    assert flank.sum() > 40
    np.testing.assert_allclose(result.shear[flank], math.radians(alpha_deg - 90.0), atol=1e-9)


def test_the_chord_model_shears_the_net_at_a_crease_crossed_at_an_angle() -> None:
    """The feature angle at 180° turns the surface-length rule off: the flat pattern is lost
    (the chord across the crease is shorter than the tow over it), by millimetres."""
    result, flat = drape_across(90.0, 70.0, 60.0, feature_angle_deg=180.0)
    inside = result.status == NodeStatus.PLACED
    error = np.linalg.norm(unfolded(result.nodes[inside], 90.0) - flat[inside], axis=-1)
    assert error.max() > 0.1 * D


def test_a_feature_angle_outside_0_to_180_degrees_is_refused() -> None:
    with pytest.raises(ValueError, match=r"feature_angle_deg must be an angle in \[0, 180\]"):
        folded_plate(90.0, feature_angle_deg=-1.0)


def test_a_generator_node_falling_on_a_crease_is_kept() -> None:
    """On the bundled hat mould (block 100 × 60 × 40 mm on a plate), a generator from the top's
    centre along −x at d = 10 mm has its 5th node on the block's top edge and its 9th on the
    wall's foot, each within a rounding error of the crease: every node is placed, d apart
    along the unfolded line (top, wall, plate). They once stopped at the top edge."""
    mesh = read_obj(HAT, 0.001, feature_angle_deg=FEATURE)
    start = np.array([[0.0, 0.0, 0.04]])
    points, status = mesh.geodesic_nodes(start, np.array([[-1.0, 0.0, 0.0]]), D, 12)
    assert np.all(status == NodeStatus.PLACED)
    p = points[0]
    # unfolded along the path: top (x), then down the wall (z), then out over the plate (x)
    along = np.where(p[:, 2] >= 0.04 - 1e-12, -p[:, 0], 0.05 + (0.04 - p[:, 2]))
    along = np.where(p[:, 0] < -0.05 - 1e-12, 0.09 + (-0.05 - p[:, 0]), along)
    np.testing.assert_allclose(along, D * np.arange(1, 13), atol=1e-12)
    np.testing.assert_allclose(p[:, 1], 0.0, atol=1e-12)
