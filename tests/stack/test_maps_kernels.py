"""The stack's holding-cell kernel (preform.stack.maps_kernels) on flat sheared nets, where the
cell holding a point is known in closed form: the net is the lattice x = u·e1 + v·e2 with
|e1| = |e2| = d and the angle between them 90° − γ, so the point's cell is (⌊u⌋, ⌊v⌋) and
its gap is its height above the plane."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.stack.maps_kernels import holding_cells

D_MM = 4.0
N = 9  # cells a side


def sheared_net(shear_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nodes (N+1, N+1, 3) [mm], centroids (N, N, 3) [mm] and the lattice vectors e1, e2."""
    e1 = np.array([D_MM, 0.0, 0.0])
    angle = math.radians(90.0 - shear_deg)
    e2 = D_MM * np.array([math.cos(angle), math.sin(angle), 0.0])
    i, j = np.meshgrid(np.arange(N + 1), np.arange(N + 1), indexing="ij")
    nodes = i[..., None] * e1 + j[..., None] * e2
    centroid = 0.25 * (nodes[:-1, :-1] + nodes[1:, :-1] + nodes[:-1, 1:] + nodes[1:, 1:])
    return nodes, centroid, e1, e2


@settings(max_examples=60, deadline=None)
@given(
    shear_deg=st.floats(0.0, 70.0),
    seed=st.integers(0, 2**32 - 1),
    gap_mm=st.floats(0.1, 3.0),
    holes=st.booleans(),
)
def test_a_point_is_read_in_the_cell_that_holds_it_or_left_in_doubt(
    shear_deg: float, seed: int, gap_mm: float, holes: bool
) -> None:
    rng = np.random.default_rng(seed)
    nodes, centroid, e1, e2 = sheared_net(shear_deg)
    region = rng.random((N, N)) < (0.8 if holes else 1.0)
    region[N // 2, N // 2] = True
    uv = rng.uniform(-1.5, N + 1.5, size=(400, 2))
    height = rng.uniform(-1.5 * gap_mm, 1.5 * gap_mm, size=400)
    points = uv[:, :1] * e1 + uv[:, 1:] * e2 + height[:, None] * np.array([0.0, 0.0, 1.0])
    # away from ties: cell edges and the gap limit
    clear = (np.abs(uv - np.round(uv)) > 1e-6).all(axis=1) & (
        np.abs(np.abs(height) - gap_mm) > 1e-9
    )
    points, uv, height = points[clear], uv[clear], height[clear]
    ci_all, cj_all = np.nonzero(region)
    centres = centroid[ci_all, cj_all]
    distance = np.linalg.norm(points[:, None, :] - centres[None], axis=2)
    nearest = np.argmin(distance, axis=1)  # a second search: brute force
    bound = 2.0 * D_MM + gap_mm
    far = distance[np.arange(len(points)), nearest] > bound
    present, ci, cj, doubt = holding_cells(
        points,
        ci_all[nearest],
        cj_all[nearest],
        far,
        nodes,
        centroid,
        region,
        np.full(len(points), gap_mm),
        D_MM,
    )
    cell = np.floor(uv).astype(int)
    inside = ((cell >= 0) & (cell < N)).all(axis=1)
    held = np.zeros(len(points), bool)
    held[inside] = region[cell[inside, 0], cell[inside, 1]]
    held &= np.abs(height) <= gap_mm
    # read where the kernel says so: in the holding cell
    assert np.all(held[present])
    assert np.array_equal(ci[present], cell[present, 0])
    assert np.array_equal(cj[present], cell[present, 1])
    # what it neither reads nor doubts is held by no cell; doubt is never also a read
    assert not np.any(held & ~present & ~doubt)
    assert not np.any(doubt & present)
    assert not np.any(far & (present | doubt))
    # on a whole flat net the nearest centroid is the holding cell's or an edge neighbour's
    # (at any shear: the lattice's Voronoi cells), so no held point is left in doubt; beside a
    # hole the nearest cell of the net may be farther and the exact search decides
    if not holes:
        assert np.array_equal(present, held)


def test_on_an_unsheared_net_the_nearest_cell_is_the_holding_cell() -> None:
    """With square cells the nearest centroid's cell holds every point of the net (its Voronoi
    cell is the cell), so the neighbours are never asked: a point is read there."""
    nodes, centroid, e1, e2 = sheared_net(0.0)
    region = np.ones((N, N), bool)
    rng = np.random.default_rng(3)
    uv = rng.uniform(0.01, N - 0.01, size=(500, 2))
    points = uv[:, :1] * e1 + uv[:, 1:] * e2
    cell = np.floor(uv).astype(np.intp)
    present, ci, cj, doubt = holding_cells(
        points, cell[:, 0], cell[:, 1], np.zeros(500, bool), nodes, centroid, region,
        np.full(500, 1.0), D_MM,
    )  # fmt: skip
    assert present.all() and not doubt.any()
    assert np.array_equal(np.column_stack([ci, cj]), cell)
