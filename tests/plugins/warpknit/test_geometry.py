"""Warp-knit geometric model: gauge, stitch paths, stack, cell, placement self-checks."""

from __future__ import annotations

from dataclasses import replace
from math import hypot

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.plugins.warpknit.geometry import (
    ThreadLevel,
    TowLayer,
    TowType,
    WarpKnitGeometry,
    cell_areal_density_g_m2,
    needle_distance_from_gauge,
)
from preform.plugins.warpknit.lapping import parse_lapping

MM = 1e-3


def layer(angle: float, spacing_mm: float = 2.5, tex: float = 600.0) -> TowLayer:
    return TowLayer(
        orientation_deg=angle,
        spacing=spacing_mm * MM,
        tow=TowType("glass", tex, width=spacing_mm * MM, height=0.2 * MM),
    )


def thread(seq: str = "1-0/1-2", **kw) -> ThreadLevel:
    args = dict(
        sequence=parse_lapping(seq),
        overlap_length=6.0 * MM,
        stitch_length=2.5 * MM,
        linear_density_tex=7.6,
        gauge_needles_per_inch=5.0,
    )
    args.update(kw)
    return ThreadLevel(**args)


def fabric(**kw) -> WarpKnitGeometry:
    args = dict(tow_layers=(layer(0.0, 2.54), layer(90.0, 2.5)), thread_levels=(thread(),))
    args.update(kw)
    return WarpKnitGeometry(**args)


@pytest.mark.parametrize(("gauge", "d_mm"), [(5, 5.08), (7, 3.628571), (12, 2.116667), (25.4, 1.0)])
def test_gauge_and_needle_distance(gauge, d_mm):
    assert needle_distance_from_gauge(gauge) == pytest.approx(d_mm * MM, rel=1e-6)


def test_gauge_contradicting_needle_distance_is_an_error():
    ok = fabric(thread_levels=(thread(needle_distance=5.08 * MM),))
    assert ok.problems() == []
    bad = fabric(thread_levels=(thread(needle_distance=4.0 * MM),))
    assert [loc for loc, _ in bad.problems()] == [("threads", 0, "gauge_needles_per_inch")]
    neither = fabric(thread_levels=(thread(gauge_needles_per_inch=None),))
    assert [loc for loc, _ in neither.problems()] == [("threads", 0)]


def test_guide_bars_must_share_the_machine():
    other = thread("1-0/0-1", gauge_needles_per_inch=7.0, stitch_length=3.0 * MM)
    locs = [loc for loc, _ in fabric(thread_levels=(thread(), other)).problems()]
    assert ("threads", 1, "needle_distance_mm") in locs
    assert ("threads", 1, "stitch_length_mm") in locs


def test_underlap_vectors_follow_the_lapping():
    d = 5.08 * MM
    for seq, lateral in [
        ("1-0/1-2", (d, -d)),
        ("1-0/0-1", (0.0, 0.0)),
        ("1-0/3-4", (3 * d, -3 * d)),
    ]:
        path = fabric(thread_levels=(thread(seq),)).stitch_path(0)
        np.testing.assert_allclose(path.underlap_vectors[:, 0], 2.5 * MM)
        np.testing.assert_allclose(path.underlap_vectors[:, 1], lateral, atol=1e-12)


def test_loops_have_the_overlap_length_and_sit_on_the_face():
    geo = fabric()
    path = geo.stitch_path(0)
    for loop in path.overlaps:
        assert np.linalg.norm(np.diff(loop, axis=0), axis=1).sum() == pytest.approx(6.0 * MM)
        assert loop[1:4, 2].max() < geo.unit_cell().tows[0].points[0, 2]  # below the tows
    # the thread ends where the next repeat starts
    np.testing.assert_allclose(path.points[-1] - path.points[0], [5.0 * MM, 0.0, 0.0], atol=1e-15)


def test_stitch_areal_density_matches_a_hand_calculation():
    # tricot, E5, 2.5 mm courses, 6 mm loops, 7.6 tex: per course and thread one loop and one
    # underlap of sqrt(2.5² + 5.08²) mm over an area of 2.5 × 5.08 mm².
    per_course_mm = 6.0 + hypot(2.5, 5.08)
    expected = 7.6 * per_course_mm / (2.5 * 5.08)
    geo = fabric()
    assert geo.stitch_areal_density_g_m2(0) == pytest.approx(expected, rel=1e-9)
    # one empty guide between loaded guides halves it
    half = fabric(thread_levels=(thread(empty_guides=1),))
    assert half.stitch_areal_density_g_m2(0) == pytest.approx(expected / 2, rel=1e-9)
    cell = geo.unit_cell()
    assert cell_areal_density_g_m2(cell, "stitch") == pytest.approx(expected, rel=1e-9)


def test_layer_areal_density_is_tex_over_spacing():
    geo = fabric()
    assert [t.areal_density_g_m2 for t in geo.tow_layers] == pytest.approx([600 / 2.54, 240.0])
    assert cell_areal_density_g_m2(geo.unit_cell(), "tow") == pytest.approx(600 / 2.54 + 240)


def test_unit_cell_kinds_levels_and_stitch_direction():
    cell = fabric().unit_cell()
    assert {t.kind for t in cell.tows} == {"tow", "stitch"}
    assert {t.level for t in cell.tows if t.kind == "tow"} == {1, 2}
    assert {t.level for t in cell.tows if t.kind == "stitch"} == {3}
    assert cell.reference_direction == 0.0
    # a 0/90 fabric registered with E5 tricot repeats over 2 courses and one needle
    np.testing.assert_allclose(cell.period, [[5.0 * MM, 0.0], [0.0, 5.08 * MM]])


@settings(max_examples=25, deadline=None)
@given(
    angle=st.floats(-89.0, 89.0),
    spacing_mm=st.floats(1.5, 6.0),
    n1=st.integers(1, 3),
    n2=st.integers(1, 3),
)
def test_tiling_leaves_areal_density_unchanged(angle, spacing_mm, n1, n2):
    geo = fabric(tow_layers=(layer(angle, spacing_mm), layer(-angle, spacing_mm)))
    cell = geo.unit_cell()
    base = cell_areal_density_g_m2(cell)
    assert cell_areal_density_g_m2(cell.tiled(n1, n2)) == pytest.approx(base, rel=1e-9)
    # the cell's tows carry the nominal tex/spacing to within the fitting tolerance, or the
    # fabric says that it could not fit them
    tows = cell_areal_density_g_m2(cell, "tow")
    if geo.cell_fit.within_tolerance:
        assert tows == pytest.approx(2 * 600 / spacing_mm, rel=0.0101)
    else:
        assert ("tow_layers",) in [loc for loc, _ in geo.warnings()]


def test_tow_pieces_stay_inside_the_cell():
    cell = fabric(tow_layers=(layer(45.0, 2.6), layer(-45.0, 2.6))).unit_cell()
    length, width = cell.period[0, 0], cell.period[1, 1]
    for t in cell.tows:
        if t.kind == "tow":
            assert t.points[:, 0].min() >= -1e-12 and t.points[:, 0].max() <= length + 1e-12
            assert t.points[:, 1].min() >= -1e-12 and t.points[:, 1].max() <= width + 1e-12


# -- placement self-checks ------------------------------------------------------------------
def two_levels(**kw) -> WarpKnitGeometry:
    return fabric(thread_levels=(thread(), thread("1-0/0-1", overlap_length=7.0 * MM)), **kw)


def test_valid_placements_pass():
    assert two_levels(placement=((1,), (2,))).problems() == []
    assert two_levels(placement=((1, 1), (1, 2))).problems() == []


@pytest.mark.parametrize(
    ("placement", "location", "words"),
    [
        (((1,), (0,)), ("placement", 1, 0), "not integrated"),
        (((1,), (1, 3)), ("placement", 1, 1), "names thread level 3"),
        (((2,), (1,)), ("placement", 1, 0), "outside"),
        (((1, 2), (1,)), ("placement", 1, 0), "outside"),
        (((1,),), ("placement",), "2 tow layers"),
    ],
)
def test_placement_problems_name_the_tow(placement, location, words):
    problems = two_levels(placement=placement).problems()
    assert [loc for loc, _ in problems] == [location]
    assert words in problems[0][1]


def test_underlaps_stack_above_the_tows_that_name_them():
    geo = two_levels(placement=((1,), (2,)))
    tow_z, underlap_z, loop_z = geo._stack
    assert loop_z < tow_z[0] < underlap_z[0] < tow_z[1] < underlap_z[1]


def test_a_non_integrated_tow_is_drawn_on_top():
    geo = two_levels(placement=((1,), (0,)))
    cell = geo.unit_cell()
    top_tows = [t for t in cell.tows if t.level == 2]
    assert all(t.points[0, 2] > geo.thickness for t in top_tows)


def test_overlap_too_short_for_the_stack():
    geo = fabric(thread_levels=(thread(overlap_length=0.5 * MM),))
    assert [loc for loc, _ in geo.problems()] == [("threads", 0, "overlap_length_mm")]


def test_zero_degree_tows_between_pillar_wales_are_reported():
    narrow = TowLayer(0.0, 5.08 * MM, TowType("glass", 600, 1.0 * MM, 0.2 * MM), offset=0.0)
    pillar = (thread("1-0/0-1"),)
    geo = fabric(tow_layers=(narrow, layer(90.0)), thread_levels=pillar)
    assert [loc for loc, _ in geo.warnings()] == [("tow_layers", 0)]
    # the same tows under a needle are pierced; under tricot they are crossed
    pierced = replace(narrow, offset=2.54 * MM)
    assert fabric(tow_layers=(pierced, layer(90.0)), thread_levels=pillar).warnings() == []
    assert fabric(tow_layers=(narrow, layer(90.0))).warnings() == []


def test_tows_that_fit_no_small_cell_are_reported():
    # 5 mm spacing against 5.08 mm needles: within 1 % only on a cell of 60+ needles
    geo = fabric(tow_layers=(layer(0.0, 5.0), layer(90.0)))
    assert not geo.cell_fit.within_tolerance
    assert ("tow_layers",) in [loc for loc, _ in geo.warnings()]
