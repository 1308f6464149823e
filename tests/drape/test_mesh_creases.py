"""Sharp edges on mesh tools: what a pin-jointed net covers there, against the continuum.

Truths used: a developable surface (a plate folded along a crease) takes a net with no shear
beyond the generators' own; a convex vertex of angle deficit δ changes the fibre angle by δ in
its shadow (the region behind it in both fibre directions) and nowhere else (issue 12), so with
α = 90° at a box corner (δ = 90°) the net collapses there and folds; the exact placement has no
iteration, so the generator sub-step knob cannot change the net.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from preform.drape import PlyOutline, drape
from preform.drape.engine.result import NodeStatus
from preform.drape.judging.verdict import coverage
from preform.plugins.surfaces.mesh import TriangleMesh, read_obj

HAT = Path(__file__).resolve().parents[2] / "materials" / "tools" / "hat_mould.obj"


def _panels(panels: list[tuple[tuple[float, ...], ...]], n: int) -> TriangleMesh:
    """Square panels (origin, eu, ev), normal eu × ev outward, each an n × n vertex grid."""
    verts, faces = [], []
    s = np.linspace(0.0, 1.0, n)
    for origin, eu, ev in panels:
        base = sum(len(v) for v in verts)
        o, u, v = (np.asarray(x, dtype=float) for x in (origin, eu, ev))
        verts.append(np.array([o + a * u + b * v for a in s for b in s]))
        for i in range(n - 1):
            for j in range(n - 1):
                a = base + i * n + j
                faces += [[a, a + n, a + n + 1], [a, a + n + 1, a + 1]]
    return TriangleMesh(np.vstack(verts), np.array(faces))


def folded_plate(length: float = 0.2, n: int = 9) -> TriangleMesh:
    """A plate z = 0 for x < 0 folded down at x = 0 by 90° (a sharp convex crease along y)."""
    return _panels(
        [
            ((-length, -length / 2, 0.0), (length, 0.0, 0.0), (0.0, length, 0.0)),
            ((0.0, -length / 2, -length), (0.0, length, 0.0), (0.0, 0.0, length)),
        ],
        n,
    )


def box_corner(length: float = 0.2, n: int = 9) -> TriangleMesh:
    """The corner of the solid x, y, z < 0: three square faces meeting at the origin, whose
    angle deficit is 2π − 3·π/2 = π/2."""
    return _panels(
        [
            ((-length, -length, 0.0), (length, 0.0, 0.0), (0.0, length, 0.0)),
            ((0.0, -length, -length), (0.0, length, 0.0), (0.0, 0.0, length)),
            ((-length, 0.0, -length), (0.0, 0.0, length), (length, 0.0, 0.0)),
        ],
        n,
    )


@pytest.mark.parametrize("alpha_deg", [90.0, 70.0])
def test_a_plate_folded_along_a_fibre_drapes_developably(alpha_deg: float) -> None:
    """The crease runs along the v fibres: every node is placed, and every cell off the crease
    carries exactly the generator shear α − 90°, on both flanks."""
    alpha = math.radians(alpha_deg)
    d = 0.01
    result = drape(
        folded_plate(),
        node_spacing_m=d,
        ply=PlyOutline.rectangle((0.2, 0.1)),
        start_xy_m=(-0.03, 0.0),
        # +v along the crease (+y)
        orientation_rad=0.5 * math.pi - alpha,
        generator_angle_rad=alpha,
    )
    inside = result.status != NodeStatus.OUTSIDE_PLY
    assert np.all(result.status[inside] == NodeStatus.PLACED)
    nodes = result.nodes
    top = nodes[..., 2] >= -1e-12 * d
    wall = nodes[..., 0] >= -1e-12 * d
    assert wall.sum() > 40 and top.sum() > 40  # the net goes well down the fold (6 rows)

    def whole(mask: np.ndarray) -> np.ndarray:
        return mask[:-1, :-1] & mask[1:, :-1] & mask[:-1, 1:] & mask[1:, 1:]

    flank = (whole(top) | whole(wall)) & result.valid
    assert flank.sum() > 0.8 * result.valid.sum()
    # (cells with a corner on the crease itself carry ~1e-8 rad of rounding)
    np.testing.assert_allclose(result.shear[flank], alpha - 0.5 * math.pi, atol=1e-6)


def test_a_box_corner_folds_in_its_shadow_and_nowhere_else() -> None:
    """Start on the top face, the vertex at (5.5 d, 4.5 d) from the start along the fibres:
    zero shear on every cell outside the vertex's shadow (one cell of margin to its edge);
    inside it the net closes up (shear → −90°) and folds, and the summary reports one fold zone
    behind the vertex. (The coverage still reads complete: the shadow lies past the tool's
    plan, which the verdict takes for overhang; the fold zone says what was lost.)"""
    d = 0.01
    start = (-5.5 * d, -4.5 * d)
    mesh = box_corner()
    result = drape(
        mesh,
        node_spacing_m=d,
        ply=PlyOutline.rectangle((0.28, 0.28)),
        start_xy_m=start,
        orientation_rad=0.0,
        generator_angle_rad=0.5 * math.pi,
    )
    i0, j0 = result.start_index
    iv, jv = i0 + 6, j0 + 5  # first node indices past the vertex
    ii, jj = np.indices(result.cell_status.shape)
    outside = (ii <= iv - 2) | (jj <= jv - 2)
    assert np.all(result.valid[outside])
    np.testing.assert_allclose(result.shear[outside], 0.0, atol=1e-9)
    shadow_nodes = (np.indices(result.status.shape)[0] >= iv) & (
        np.indices(result.status.shape)[1] >= jv
    )
    assert np.any(result.status[shadow_nodes] == NodeStatus.FOLDED)
    assert np.all(result.status[~shadow_nodes] != NodeStatus.FOLDED)
    shadow_cells = (ii >= iv) & (jj >= jv)
    sheared = result.valid & shadow_cells
    # where the shadow is still placed the cells have closed up by the vertex's deficit
    assert np.all(np.abs(result.shear[sheared] + 0.5 * math.pi) < math.radians(1.0))
    cover = coverage(result, mesh, start)
    ((x, y), area), *rest = cover.fold_zones
    assert not rest and x > 0 and y > 0  # behind the vertex, in plan
    assert area > 0 and area == pytest.approx(cover.summary()["fold_zone_area_m2"])
    # the coverage takes the shadow (past the tool's plan) for overhang, so a warning says it
    assert cover.complete and cover.fold_warning().startswith("the net folded")
    assert "1 fold zone(s)" in cover.fold_warning()


def rounded_box_corner(radius: float, length: float = 0.3, n: int = 81) -> TriangleMesh:
    """The box corner of :func:`box_corner` with its edges and vertex rounded to ``radius``
    [m]: the surface at distance ``radius`` from the solid x, y, z ≤ −radius (cylinders along
    the edges, a sphere octant at the vertex). Each vertex q of the sharp mesh moves to
    c + radius·(q − c)/|q − c|, c its closest point on that solid."""
    sharp = box_corner(length, n)
    c = np.minimum(sharp.vertices, -radius)
    w = sharp.vertices - c
    moved = c + radius * w / np.linalg.norm(w, axis=1, keepdims=True)
    return TriangleMesh(moved, sharp.faces)


def test_a_rounded_corner_turns_the_net_by_its_angle_deficit_whatever_its_radius() -> None:
    """Gauss–Bonnet for the Chebyshev net: ∂²ω/∂u∂v = −K sin ω integrates, over a fibre
    rectangle holding the whole rounded vertex, to a change of ω by −∫K dA = −(angle deficit)
    = −π/2, whatever the radius (the cylinders along the edges are developable). With α = 120°
    the net deep behind the corner (flat walls) carries γ = α − π/2 − π/2 = −60°."""
    d = 0.0025
    alpha = math.radians(120.0)
    start = (-0.1, -0.06)
    # the vertex in fibre coordinates: (0.1, 0.06) = u·(1, 0) + v·(cos α, sin α)
    v_vertex = 0.06 / math.sin(alpha)
    u_vertex = 0.1 - v_vertex * math.cos(alpha)
    for radius in (0.01, 0.02, 0.03):
        result = drape(
            rounded_box_corner(radius),
            node_spacing_m=d,
            ply=PlyOutline.rectangle((0.5, 0.5)),
            start_xy_m=start,
            orientation_rad=0.0,
            generator_angle_rad=alpha,
        )
        i0, j0 = result.start_index
        ii, jj = np.indices(result.shear.shape)
        u, v = (ii + 0.5 - i0) * d, (jj + 0.5 - j0) * d
        deep = (u > u_vertex + 0.06) & (u < u_vertex + 0.08) & (v > v_vertex + 0.06)
        deep &= v < v_vertex + 0.08
        assert np.count_nonzero(deep) > 30 and np.all(result.valid[deep]), radius
        np.testing.assert_allclose(result.shear[deep], alpha - math.pi, atol=math.radians(0.1))


def test_the_figures_mark_the_folds_at_the_hat_moulds_block_corners(hat: TriangleMesh) -> None:
    from preform.export.fig_drape import fold_triangles

    result = drape(
        hat,
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.36, 0.36)),
        start_xy_m=(0.004, 0.003),
        generator_angle_rad=0.5 * math.pi,
    )
    folds = fold_triangles(result)
    assert len(folds) == np.count_nonzero(result.status == NodeStatus.FOLDED) == 4
    centre = folds.mean(axis=1)
    # one fold at each of the block's top corners (±50, ±30, 40) mm, within a node spacing
    corners = np.array([[sx * 0.05, sy * 0.03] for sx in (-1, 1) for sy in (-1, 1)])
    gap = np.linalg.norm(centre[:, None, :2] - corners[None], axis=2)
    assert np.all(gap.min(axis=1) < 0.01) and len(set(gap.argmin(axis=1))) == 4


@pytest.fixture(scope="module")
def hat() -> TriangleMesh:
    return read_obj(HAT)


def test_the_hat_moulds_band_is_placed_at_every_substep_setting(hat: TriangleMesh) -> None:
    """Start (4, 3) mm, d = 10 mm, α = 90°: the cross-shaped band over the block's top (flat
    u ∈ (−54, 46) mm or v ∈ (−33, 27) mm) runs down the walls onto the plate and is placed
    wherever it lies on the plate (u from −194 to 186 mm, v from −143 to 137 mm, counting the
    40 mm walls); the net is the same for 4, 8, 16 and 32 generator sub-steps."""
    nets = []
    for substeps in (4, 8, 16, 32):
        result = drape(
            hat,
            node_spacing_m=0.01,
            ply=PlyOutline.rectangle((0.36, 0.36)),
            start_xy_m=(0.004, 0.003),
            generator_angle_rad=0.5 * math.pi,
            substeps=substeps,
        )
        nets.append(result)
        i0, j0 = result.start_index
        ii, jj = np.indices(result.status.shape)
        di, dj = ii - i0, jj - j0
        band = ((-5 <= di) & (di <= 4)) | ((-3 <= dj) & (dj <= 2))
        on_plate = (-19 <= di) & (di <= 18) & (-14 <= dj) & (dj <= 13)
        assert np.all(result.status[band & on_plate] == NodeStatus.PLACED), substeps
    for other in nets[1:]:
        np.testing.assert_array_equal(other.status, nets[0].status)
        np.testing.assert_allclose(other.nodes, nets[0].nodes, atol=1e-12, equal_nan=True)
