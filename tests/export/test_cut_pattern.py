"""The cutting pattern: area, seam allowance, part outlines through the net, and the files read
back (ezdxf, XML, CSV)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import ezdxf
import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.cut_pattern import (
    cut_pattern,
    flat_points,
    write_cut_pattern_csv,
    write_cut_pattern_dxf,
    write_cut_pattern_svg,
)
from preform.plugins.surfaces.basic import Hemisphere, Plane


def hemisphere_drape(d: float):
    return drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=d,
        ply=PlyOutline.rectangle((0.4, 0.4)),
        generator_angle_rad=np.radians(80.0),
    )


HEMI = hemisphere_drape(0.005)


def test_area_converges_to_the_covered_fabric_area() -> None:
    errors = []
    for d in (0.01, 0.005, 0.0025):
        result = hemisphere_drape(d)
        pattern = cut_pattern(result)
        cells = np.count_nonzero(result.valid & result.in_part)
        assert pattern.cell_count == cells
        errors.append(abs(pattern.area_mm2 / (cells * (1e3 * d) ** 2) - 1))
    # measured 5.5e-3, 1.3e-3, 3.2e-4: second order in d
    assert errors[0] < 0.01 and errors[0] > 3 * errors[1] > 9 * errors[2], errors


@pytest.mark.parametrize("d", [0.01, 0.005])
def test_the_outline_is_not_a_staircase(d) -> None:
    result = hemisphere_drape(d)
    pattern = cut_pattern(result)
    cells = np.count_nonzero(result.valid & result.in_part)
    staircase = cut_pattern(result, smoothing=0.0)
    assert staircase.area_mm2 == pytest.approx(cells * (1e3 * d) ** 2, rel=1e-12)
    # a staircase only turns by 90°; the smoothed outline has no right-angle corner
    ring = np.asarray(pattern.outline.geoms[0].exterior.coords)[:-1]
    e1 = ring - np.roll(ring, 1, axis=0)
    e2 = np.roll(ring, -1, axis=0) - ring
    cos = np.sum(e1 * e2, axis=1) / np.linalg.norm(e1, axis=1) / np.linalg.norm(e2, axis=1)
    assert np.min(cos) > 0.5  # no turn sharper than 60° at any vertex
    assert pattern.perimeter_mm < 0.9 * staircase.perimeter_mm


@settings(max_examples=15, deadline=None)
@given(a=st.floats(0.1, 8.0))
def test_seam_allowance_grows_the_area_by_a_times_the_perimeter(a) -> None:
    pattern = cut_pattern(HEMI, seam_allowance_mm=a)
    growth = pattern.allowance_area_mm2 - pattern.area_mm2
    # round joins: a·P + a² × (total turning at convex corners, at most ~2π over a closed curve)
    assert abs(growth - a * pattern.perimeter_mm) <= 2 * np.pi * a * a + 1e-6 * pattern.area_mm2
    assert pattern.allowance.contains(pattern.outline)


def test_rectangle_on_a_plate_flattens_to_itself_with_rounded_corners_only() -> None:
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.2, 0.1)),
        orientation_rad=0.7,
        generator_angle_rad=np.radians(65.0),
    )
    pattern = cut_pattern(result)
    assert pattern.outline.bounds == pytest.approx((-100.0, -50.0, 100.0, 50.0))
    # the sides stay where they are; only the four corners are rounded, over about σ = d
    for x, y in ((0.0, 49.9), (0.0, -49.9), (99.9, 0.0), (-99.9, 0.0)):
        assert pattern.outline.contains(Point(x, y))
    assert 200 * 100 - 4 * 10.0**2 < pattern.area_mm2 < 200 * 100
    assert "laid at 40.1 deg" in pattern.label
    assert {m.family for m in pattern.marks} == {"u", "v"}
    for mark in pattern.marks:
        (x0, y0), (x1, y1) = mark.start, mark.end
        assert (y0 == y1) if mark.family == "u" else (x0 == x1)


def test_part_outline_maps_through_the_net_inside_cells() -> None:
    """A circle of radius 40 mm on a plate, draped at α = 60°: in the flat it is the ellipse
    the inverse shear makes of it, area π·40²/sin 60° (the flat is the unsheared fabric)."""
    alpha = np.radians(60.0)
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.3, 0.3)),
        generator_angle_rad=alpha,
    )
    phi = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    circle = np.column_stack([0.04 * np.cos(phi), 0.04 * np.sin(phi), np.zeros_like(phi)])
    pattern = cut_pattern(result, part_outline_m=circle)
    assert pattern.outline_from == "part outline"
    polygon_area = 0.5 * 400 * 40**2 * np.sin(2 * np.pi / 400)
    assert pattern.area_mm2 == pytest.approx(polygon_area / np.sin(alpha), rel=1e-9)
    # net coordinates: the point d·(a, b) of the flat is at d·(a·t_u + b·t_v) on the plate
    xy = flat_points(result, circle[:3])
    t_u, t_v = np.array([1.0, 0.0]), np.array([np.cos(alpha), np.sin(alpha)])
    back = xy[:, :1] * t_u + xy[:, 1:] * t_v
    np.testing.assert_allclose(back, 1e3 * circle[:3, :2], atol=1e-9)


def test_files_read_back(tmp_path) -> None:
    pattern = cut_pattern(HEMI, seam_allowance_mm=10.0, ply_name="E-BX 318, ply 1")
    write_cut_pattern_dxf(pattern, tmp_path / "p.dxf")
    doc = ezdxf.readfile(tmp_path / "p.dxf")
    assert doc.units == ezdxf.units.MM
    assert {"OUTLINE", "ALLOWANCE", "FIBRE_MARKS", "LABELS"} <= {
        layer.dxf.name for layer in doc.layers
    }
    msp = doc.modelspace()
    outline = [e for e in msp.query("LWPOLYLINE") if e.dxf.layer == "OUTLINE"]
    assert len(outline) == 1 and outline[0].closed
    pts = np.array([p[:2] for p in outline[0].get_points()])
    ring = np.asarray(pattern.outline.geoms[0].exterior.coords)[:-1]
    np.testing.assert_allclose(pts, ring, atol=1e-9)
    assert len(msp.query("LINE")) == len(pattern.marks) > 4
    texts = [e.dxf.text for e in msp.query("TEXT")]
    assert texts == list(pattern.label_lines) and texts[0] == "E-BX 318, ply 1"

    write_cut_pattern_svg(pattern, tmp_path / "p.svg")
    root = ET.parse(tmp_path / "p.svg").getroot()
    assert root.attrib["width"].endswith("mm")
    ns = {"s": "http://www.w3.org/2000/svg"}
    ids = [p.attrib["id"] for p in root.findall("s:path", ns)]
    assert ids == ["allowance", "outline"]
    assert len(root.findall("s:line", ns)) == len(pattern.marks)

    write_cut_pattern_csv(pattern, tmp_path / "p.csv")
    table = pd.read_csv(tmp_path / "p.csv")
    out = table[table.layer == "outline"][["x_mm", "y_mm"]].to_numpy()
    x, y = out[:, 0], out[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    assert area == pytest.approx(pattern.area_mm2, rel=1e-6)
    assert set(table.layer) == {"outline", "allowance"}


def test_bad_allowance_is_refused() -> None:
    with pytest.raises(ValueError, match="seam_allowance_mm"):
        cut_pattern(HEMI, seam_allowance_mm=-1.0)


def plate_pattern(**kwargs):
    """A 200 × 100 mm rectangle on a plate at d = 10 mm; smoothing 0 keeps it exactly the
    rectangle [−100, 100] × [−50, 50] mm, so every area below is known by hand."""
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.2, 0.1)),
    )
    return cut_pattern(result, smoothing=0, **kwargs)


def test_plate_pattern_is_the_rectangle() -> None:
    assert plate_pattern().area_mm2 == pytest.approx(20000.0, rel=1e-12)


@pytest.mark.parametrize(
    ("cut", "areas"),
    [
        # vertical at x = 30: 130 × 100 and 70 × 100
        (((30.0, -80.0), (30.0, 80.0)), [7000.0, 13000.0]),
        # y = x/4 + 10 from edge to edge: below it ∫(x/4 + 60) dx over [−100, 100] = 12000
        (((-120.0, -20.0), (120.0, 40.0)), [8000.0, 12000.0]),
    ],
)
def test_a_straight_cut_splits_the_area_exactly(cut, areas) -> None:
    pattern = plate_pattern(cuts_mm=[cut])
    assert len(pattern.outline.geoms) == 2 and pattern.cuts[0].splits
    assert sorted(g.area for g in pattern.outline.geoms) == pytest.approx(areas, rel=1e-12)
    assert pattern.area_mm2 == pytest.approx(20000.0, rel=1e-12)
    assert pattern.problems == ()


def test_a_slit_ending_inside_keeps_one_piece_and_its_length() -> None:
    pattern = plate_pattern(cuts_mm=[((0.0, 80.0), (0.0, 10.0))])
    assert len(pattern.outline.geoms) == 1 and not pattern.cuts[0].splits
    assert pattern.cuts[0].length_in_fabric_mm == pytest.approx(40.0, rel=1e-12)
    assert pattern.area_mm2 == pytest.approx(20000.0, rel=1e-12)


@pytest.mark.parametrize(
    "mouth",
    [
        ((-10.0, 50.0), (10.0, 50.0)),  # on the edge: the whole triangle, ½·20·30
        ((-20.0, 80.0), (20.0, 80.0)),  # past it: the similar triangle up to y = 50, ½·20·30
    ],
)
def test_a_dart_removes_its_triangle(mouth) -> None:
    pattern = plate_pattern(darts_mm=[((0.0, 20.0), mouth)])
    assert pattern.darts[0].removed_area_mm2 == pytest.approx(300.0, rel=1e-12)
    assert pattern.area_mm2 == pytest.approx(20000.0 - 300.0, rel=1e-12)
    assert not pattern.outline.contains(Point(0.0, 45.0))
    assert pattern.outline.contains(Point(0.0, 15.0))


def test_dart_and_cut_open_the_allowance_too() -> None:
    pattern = plate_pattern(
        seam_allowance_mm=5.0,
        darts_mm=[((0.0, 20.0), ((-10.0, 50.0), (10.0, 50.0)))],
        cuts_mm=[((30.0, -60.0), (30.0, 60.0))],
    )
    assert not pattern.allowance.contains(Point(0.0, 52.0))  # in the wedge carried on
    assert pattern.allowance.buffer(1e-9).contains(Point(-50.0, 52.0))
    assert len(pattern.allowance.geoms) == 2  # the cut runs on across the allowance


def test_a_dart_or_cut_off_the_pattern_is_reported() -> None:
    pattern = plate_pattern(
        darts_mm=[((300.0, 0.0), ((310.0, 10.0), (310.0, -10.0)))],
        cuts_mm=[((300.0, -10.0), (300.0, 10.0))],
    )
    assert pattern.area_mm2 == pytest.approx(20000.0, rel=1e-12)
    assert len(pattern.problems) == 2
    assert "dart 0" in pattern.problems[0] and "cut 0 misses" in pattern.problems[1]


def test_darts_and_cuts_read_back(tmp_path) -> None:
    dart = ((0.0, 20.0), ((-10.0, 50.0), (10.0, 50.0)))
    cut = ((30.0, -80.0), (30.0, 80.0))
    pattern = plate_pattern(darts_mm=[dart], cuts_mm=[cut])
    write_cut_pattern_dxf(pattern, tmp_path / "p.dxf")
    msp = ezdxf.readfile(tmp_path / "p.dxf").modelspace()
    darts = [e for e in msp.query("LWPOLYLINE") if e.dxf.layer == "DARTS"]
    assert len(darts) == 1 and not darts[0].closed
    pts = [tuple(p[:2]) for p in darts[0].get_points()]
    assert pts == [(-10.0, 50.0), (0.0, 20.0), (10.0, 50.0)]
    cuts = [e for e in msp.query("LINE") if e.dxf.layer == "CUTS"]
    assert len(cuts) == 1
    assert tuple(cuts[0].dxf.start)[:2] == cut[0] and tuple(cuts[0].dxf.end)[:2] == cut[1]
    assert len([e for e in msp.query("LWPOLYLINE") if e.dxf.layer == "OUTLINE"]) == 2

    write_cut_pattern_csv(pattern, tmp_path / "p.csv")
    table = pd.read_csv(tmp_path / "p.csv")
    rows = table[table.layer == "dart"][["x_mm", "y_mm"]].to_numpy()
    np.testing.assert_array_equal(rows, [[-10, 50], [0, 20], [10, 50]])
    rows = table[table.layer == "cut"][["x_mm", "y_mm"]].to_numpy()
    np.testing.assert_array_equal(rows, [[30, -80], [30, 80]])
    assert set(table[table.layer == "outline"].piece) == {0, 1}

    write_cut_pattern_svg(pattern, tmp_path / "p.svg")
    root = ET.parse(tmp_path / "p.svg").getroot()
    ns = {"s": "http://www.w3.org/2000/svg"}
    assert len(root.findall("s:polyline[@class='dart']", ns)) == 1
    assert len(root.findall("s:line[@class='cut']", ns)) == 1


def test_cells_past_locking_are_drawn_where_they_lie_in_the_flat(tmp_path) -> None:
    """Cell (i, j) of the net is the square from ((i − i0)·d, (j − j0)·d) in the flat: marking
    two neighbouring cells and one far away draws exactly those squares (area 3·d²)."""
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.2, 0.1)),
    )
    i0, j0 = result.start_index
    region = result.valid & result.in_part
    mask = np.zeros_like(region)
    for di, dj in ((2, -1), (3, -1), (-5, 2)):
        assert region[i0 + di, j0 + dj]
        mask[i0 + di, j0 + dj] = True
    pattern = cut_pattern(result, smoothing=0, past_locking=mask)
    assert pattern.past_locking.area == pytest.approx(300.0, rel=1e-12)
    assert len(pattern.past_locking.geoms) == 2
    assert pattern.past_locking.buffer(1e-9).contains(Point(25.0, -5.0))
    assert pattern.past_locking.buffer(1e-9).contains(Point(-45.0, 25.0))
    assert pattern.past_locking.bounds == pytest.approx((-50.0, -10.0, 40.0, 30.0))
    write_cut_pattern_dxf(pattern, tmp_path / "p.dxf")
    msp = ezdxf.readfile(tmp_path / "p.dxf").modelspace()
    drawn = [e for e in msp.query("LWPOLYLINE") if e.dxf.layer == "PAST_LOCKING"]
    assert len(drawn) == 2 and all(e.closed for e in drawn)
    write_cut_pattern_csv(pattern, tmp_path / "p.csv")
    assert "past_locking" in set(pd.read_csv(tmp_path / "p.csv").layer)
    with pytest.raises(ValueError, match="cell shape"):
        cut_pattern(result, past_locking=mask[:-1])


def test_marked_cells_outside_the_pattern_region_are_not_drawn(make_net) -> None:
    """A 10 × 12 node net (9 × 11 cells, d = 5 mm) with one cell out of the part and one
    folded: every cell marked, the drawing covers the 97 cells of the region, 97 · 25 mm²."""
    net = make_net(10, 12, outside_part=[(4, 7)], folded=[(2, 2)])
    pattern = cut_pattern(net, past_locking=np.ones(net.valid.shape, dtype=bool))
    assert pattern.past_locking.area == pytest.approx(97 * 25.0, rel=1e-12)
    i0, j0 = net.start_index
    hole = Point((4 - i0 + 0.5) * 5.0, (7 - j0 + 0.5) * 5.0)
    assert not pattern.past_locking.contains(hole)


# -- the scene's part, clipped in the flat ----------------------------------------------------


def _hexagon_on_a_plate(d: float, alpha_deg: float = 60.0):
    from preform.drape.engine.part import PlanPolygon

    t = np.linspace(0, 2 * np.pi, 7)[:-1] + 0.3
    hexagon = PlanPolygon(np.column_stack([0.05 * np.cos(t), 0.05 * np.sin(t)]))
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=d,
        ply=PlyOutline.rectangle((0.3, 0.3)),
        generator_angle_rad=np.radians(alpha_deg),
        trim=hexagon,
    )
    return result, hexagon


def test_a_plan_part_on_a_plate_is_its_inverse_shear_in_the_flat() -> None:
    """A regular hexagon (circumradius 50 mm) on a plate, draped at α = 60°: in the flat it is
    the hexagon under the inverse shear, of area A/sin α. The part's level function is linear
    across a cell wherever one straight side cuts it, so only the six corners are cut short:
    the area error is O(d²) per corner (second order); the outline maps back exactly onto the
    hexagon's sides away from the corners, and within 2d (a sheared cell's diagonal) at them."""
    from shapely.geometry import Polygon

    alpha = np.radians(60.0)
    exact = 0.5 * 6 * 50.0**2 * np.sin(2 * np.pi / 6) / np.sin(alpha)
    errors = []
    for d in (0.01, 0.005, 0.0025):
        result, hexagon = _hexagon_on_a_plate(d)
        pattern = cut_pattern(result, part=hexagon)
        assert pattern.outline_from == "part, clipped in the flat"
        errors.append(abs(pattern.area_mm2 / exact - 1))
        # back to the plate: flat (a, b) is at a·t_u + b·t_v
        ring = np.asarray(pattern.outline.geoms[0].exterior.coords)
        t_u, t_v = np.array([1.0, 0.0]), np.array([np.cos(alpha), np.sin(alpha)])
        plate = ring[:, :1] * t_u + ring[:, 1:] * t_v
        sides = Polygon(1e3 * hexagon.vertices_m).exterior
        gaps = np.array([sides.distance(Point(x, y)) for x, y in plate])
        # exact along the straight sides; a corner is cut within the rhombus cells it touches
        assert np.median(gaps) < 1e-9 and gaps.max() < 2 * 1e3 * d, (np.median(gaps), gaps.max())
    # measured 1.3e-2, 4.1e-3, 7.0e-4
    assert errors[0] < 0.02 and errors[0] > 2.5 * errors[1] > 2.5**2 * errors[2], errors


def test_a_height_cut_part_in_the_flat_has_the_area_the_energy_counts() -> None:
    """The bare hemisphere's part z ≥ 0, draped past the rim: the flat region of the part has
    the fabric area the energy counts, Σ share·d², to the O(d²) difference between one
    diagonal split (the outline) and the average of both (the share)."""
    from preform.drape.engine.part import HeightCut

    cut = HeightCut(0.0)
    ratios = []
    for d in (0.01, 0.005):
        result = drape(
            Hemisphere(0.1, run_off_m=0.025),
            start_xy_m=(0.0, 0.0),
            node_spacing_m=d,
            ply=PlyOutline.rectangle((0.4, 0.4)),
            generator_angle_rad=np.radians(80.0),
            trim=cut,
        )
        pattern = cut_pattern(result, part=cut)
        counted = float(result.part_weight.sum()) * (1e3 * d) ** 2
        ratios.append(abs(pattern.area_mm2 / counted - 1))
        assert len(pattern.outline.geoms) == 1 and not pattern.outline.geoms[0].interiors
    assert ratios[0] < 2e-3 and ratios[1] < ratios[0], ratios
