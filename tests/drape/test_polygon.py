"""Simple polygons (``preform.drape.engine.polygon``) against shapely's GEOS validity, a second
implementation: on an integer grid every crossing and touching is exact, so the two must agree
on every polygon, degenerate ones included."""

from __future__ import annotations

import sys
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape.engine.polygon import outline_problem, self_crossing, signed_area

shapely = pytest.importorskip("shapely")

grid_polygons = st.lists(
    st.tuples(st.integers(0, 5), st.integers(0, 5)), min_size=3, max_size=9
).map(lambda v: np.asarray(v, dtype=float) * 7.5)


def _shapely_region(v: np.ndarray) -> bool:
    polygon = shapely.Polygon(v)
    return bool(polygon.is_valid and polygon.area > 0)


@settings(max_examples=400, deadline=None)
@given(grid_polygons)
def test_the_fallback_agrees_with_shapely(v: np.ndarray) -> None:
    """Without shapely (the fallback, this module's own sweep) and with it, the verdict is
    shapely's: a region exactly when shapely calls the polygon valid with area."""
    truth = _shapely_region(v)
    saved = sys.modules.get("shapely")
    sys.modules["shapely"] = None  # type: ignore[assignment]  # import shapely now fails
    try:
        fallback = outline_problem(v)
    finally:
        sys.modules["shapely"] = saved  # type: ignore[assignment]
    assert (fallback is None) == truth, fallback
    assert (outline_problem(v) is None) == truth


@settings(max_examples=200, deadline=None)
@given(grid_polygons)
def test_a_reported_crossing_point_lies_on_both_edges(v: np.ndarray) -> None:
    found = self_crossing(v)
    if found is None:
        return
    k, m, point = found
    keep = np.any(v != np.roll(v, 1, axis=0), axis=1)
    w = v[keep] if keep.any() else v[:1]
    edges = [shapely.LineString([w[i], w[(i + 1) % len(w)]]) for i in (k, m)]
    for edge in edges:
        assert edge.distance(shapely.Point(point)) < 1e-9


def test_the_bow_tie_crosses_at_its_centre() -> None:
    bow_tie = [(-50, -50), (50, 50), (50, -50), (-50, 50)]
    assert signed_area(bow_tie) == 0.0  # why the test of no area is not of the signed area
    assert self_crossing(bow_tie) == (0, 2, (0.0, 0.0))
    assert "near (x, y) = (0, 0) mm" in (outline_problem(bow_tie) or "")


def test_a_star_of_the_scene_limit_is_judged_quickly() -> None:
    """10⁴ vertices (MAX_POLYGON_VERTICES), every edge spanning the outline: the worst case
    of the sweep, bounded by shapely's test where it is installed."""
    angle = np.linspace(0.0, 2.0 * np.pi, 10_000, endpoint=False)
    radius = np.where(np.arange(10_000) % 2, 100.0, 1.0)
    star = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    started = time.process_time()
    assert outline_problem(star) is None
    assert time.process_time() - started < 2.0
