from __future__ import annotations

import csv
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from preform.export.flat_pattern import (
    flat_node_positions,
    flat_pattern,
    outline_loops,
    write_flat_pattern_csv,
    write_flat_pattern_dxf,
    write_flat_pattern_svg,
)


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


@pytest.fixture
def holed_pattern(make_net):
    return flat_pattern(make_net(6, 5, spacing=0.01, start=(0, 0), outside_part=[(2, 2)]))


def test_csv_lists_every_vertex(tmp_path, holed_pattern):
    path = tmp_path / "pattern.csv"
    write_flat_pattern_csv(holed_pattern, path)
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == sum(len(loop) for loop in holed_pattern.loops)
    for k, loop in enumerate(holed_pattern.loops):
        mine = [r for r in rows if int(r["loop"]) == k]
        assert [int(r["vertex"]) for r in mine] == list(range(len(loop)))
        assert {int(r["hole"]) for r in mine} == {int(holed_pattern.holes[k])}
        np.testing.assert_allclose([[float(r["x_mm"]), float(r["y_mm"])] for r in mine], loop)


def _read_dxf_polylines(text: str) -> list[dict]:
    """A tiny DXF reader: group-code/value pairs, POLYLINE/VERTEX/SEQEND in ENTITIES."""
    lines = text.splitlines()
    assert len(lines) % 2 == 0
    pairs = [(int(lines[k]), lines[k + 1].strip()) for k in range(0, len(lines), 2)]
    assert pairs[-1] == (0, "EOF")
    polylines: list[dict] = []
    current: dict | None = None
    for code, value in pairs:
        if code == 0:
            if value == "POLYLINE":
                current = {"vertices": [], "flags": 0}
                polylines.append(current)
                target = current
            elif value == "VERTEX":
                assert current is not None
                target = {"x": None, "y": None}
                current["vertices"].append(target)
            else:
                target = {}
        elif code == 8 and "vertices" in target:
            target["layer"] = value
        elif code == 70 and "vertices" in target:
            target["flags"] = int(value)
        elif code == 10 and "x" in target:
            target["x"] = float(value)
        elif code == 20 and "y" in target:
            target["y"] = float(value)
    return polylines


def test_dxf_polylines_are_closed_and_match_the_loops(tmp_path, holed_pattern):
    path = tmp_path / "pattern.dxf"
    write_flat_pattern_dxf(holed_pattern, path)
    text = path.read_text(encoding="ascii")
    assert "AC1009" in text

    polylines = _read_dxf_polylines(text)
    assert len(polylines) == len(holed_pattern.loops) == 2
    for poly, loop, hole in zip(polylines, holed_pattern.loops, holed_pattern.holes, strict=True):
        assert poly["flags"] & 1  # closed
        assert poly["layer"] == ("HOLE" if hole else "OUTLINE")
        np.testing.assert_allclose([[v["x"], v["y"]] for v in poly["vertices"]], loop)


def test_svg_is_xml_in_millimetres(tmp_path, holed_pattern):
    path = tmp_path / "pattern.svg"
    write_flat_pattern_svg(holed_pattern, path, title="ply 1 <hemisphere>")
    root = ET.parse(path).getroot()
    ns = "{http://www.w3.org/2000/svg}"
    assert root.tag == f"{ns}svg"
    assert root.attrib["width"] == f"{50.0 + 10.0:.4f}mm"
    assert root.attrib["height"] == f"{40.0 + 10.0:.4f}mm"
    view = [float(v) for v in root.attrib["viewBox"].split()]
    assert view == pytest.approx([-5.0, -45.0, 60.0, 50.0])
    paths = root.findall(f"{ns}path")
    assert len(paths) == 1
    d = paths[0].attrib["d"]
    assert d.count("M") == 2 and d.count("Z") == 2
    assert [t.text for t in root.findall(f"{ns}title")] == ["ply 1 <hemisphere>"]


def test_empty_part_gives_an_empty_pattern_and_valid_files(tmp_path, make_net):
    pattern = flat_pattern(make_net(3, 3, unplaced=[(1, 1)]))
    assert pattern.loops == () and pattern.area_mm2 == 0.0 and pattern.cell_count == 0
    write_flat_pattern_dxf(pattern, tmp_path / "e.dxf")
    write_flat_pattern_svg(pattern, tmp_path / "e.svg")
    assert _read_dxf_polylines((tmp_path / "e.dxf").read_text()) == []
    assert ET.parse(tmp_path / "e.svg").getroot().tag.endswith("svg")
