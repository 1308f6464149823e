from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from preform.export.flat_pattern import flat_node_positions, flat_pattern, outline_loops


def _signed_area(loop: np.ndarray) -> float:
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


@pytest.mark.parametrize("angle", [90.0, 55.0])
def test_full_net_flattens_to_one_rectangle_whatever_the_draped_shear(make_net, angle):
    net = make_net(10, 12, spacing=0.005, generator_angle_deg=angle, start=(2, 3))
    pattern = flat_pattern(net)

    assert len(pattern.loops) == 1 and pattern.holes == (False,)
    loop = pattern.loops[0]
    assert len(loop) == 4  # straight sides keep only their corners
    x0, y0, x1, y1 = pattern.bounds_mm
    assert (x0, y0) == pytest.approx((-2 * 5.0, -3 * 5.0))
    assert (x1 - x0, y1 - y0) == pytest.approx((9 * 5.0, 11 * 5.0))
    assert pattern.area_mm2 == pytest.approx(45.0 * 55.0)
    assert _signed_area(loop) > 0  # outer loops run counter-clockwise
    assert pattern.cell_count == 9 * 11


def test_flat_node_positions_are_the_unsheared_net(make_net):
    net = make_net(4, 3, spacing=0.002, generator_angle_deg=70.0, start=(1, 0))
    flat = flat_node_positions(net)
    assert flat.shape == (4, 3, 2)
    np.testing.assert_allclose(flat[1, 0], [0.0, 0.0])
    np.testing.assert_allclose(flat[3, 2], [0.004, 0.004])


def test_cells_out_of_the_part_make_a_hole(make_net):
    hole = [(i, j) for i in (4, 5) for j in (5, 6, 7)]
    net = make_net(10, 12, spacing=0.005, outside_part=hole)
    pattern = flat_pattern(net)

    assert pattern.holes == (False, True)
    outer, inner = pattern.loops
    assert _signed_area(outer) == pytest.approx(45.0 * 55.0)
    assert _signed_area(inner) == pytest.approx(-10.0 * 15.0)  # clockwise
    assert pattern.area_mm2 == pytest.approx(45.0 * 55.0 - 150.0)
    assert len(inner) == 4


def test_unplaced_corner_and_folded_cell_are_cut_out(damaged_net):
    pattern = flat_pattern(damaged_net)
    # Node (0, 0) is lost with its one cell: a corner notch (+2 corners). Node (9, 5) on the far
    # side takes two cells: a notch in the side (+4 corners).
    assert pattern.holes.count(False) == 1
    assert len(pattern.loops[0]) == 4 + 2 + 4
    # The folded cell (3, 3) and the out-of-part cell (4, 7) are holes.
    assert pattern.holes.count(True) == 2
    assert pattern.cell_count == 9 * 11 - 1 - 2 - 1 - 1
    d = 5.0
    assert pattern.area_mm2 == pytest.approx(pattern.cell_count * d * d)


def test_cells_touching_at_one_corner_are_separate_pieces():
    cells = np.array([[True, False], [False, True]])
    loops = outline_loops(cells)
    assert sorted(map(sorted, loops)) == [
        [(0, 0), (0, 1), (1, 0), (1, 1)],
        [(1, 1), (1, 2), (2, 1), (2, 2)],
    ]


@settings(max_examples=60, deadline=None)
@given(arrays(bool, st.tuples(st.integers(1, 7), st.integers(1, 7))))
def test_outline_encloses_exactly_the_cells(cells):
    loops = outline_loops(cells)
    area = sum(_signed_area(np.asarray(loop, dtype=float)) for loop in loops)
    assert area == pytest.approx(np.count_nonzero(cells))
    for loop in loops:
        pts = np.asarray(loop)
        step = np.roll(pts, -1, axis=0) - pts
        assert np.all((step == 0).sum(axis=1) == 1)  # closed, axis-aligned sides only
        assert len(loop) >= 4


def test_empty_part_gives_an_empty_pattern(make_net):
    pattern = flat_pattern(make_net(3, 3, unplaced=[(1, 1)]))
    assert pattern.loops == () and pattern.area_mm2 == 0.0 and pattern.cell_count == 0
