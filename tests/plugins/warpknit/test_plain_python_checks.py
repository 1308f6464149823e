"""The checks a library listing runs are plain Python (issue 15: `materials list` imports no
numpy); each is held here to a numpy implementation written in the test (the code they
replaced), on generated fabrics and polynomials."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st
from numpy.polynomial import polynomial as npoly

from preform.plugins.warpknit.geometry import (
    ANGLE_TOLERANCE_DEG,
    MAX_REPEATS,
    SPACING_TOLERANCE,
    ThreadLevel,
    TowLayer,
    TowType,
    WarpKnitGeometry,
    _LayerLattice,
    polyline_length,
)
from preform.plugins.warpknit.lapping import parse_lapping
from preform.shear.laws import polynomial_extremes, polynomial_value

MM = 1e-3

# -- the numpy implementations these checks had before ----------------------------------------


def numpy_cell_fit(geo: WarpKnitGeometry) -> tuple[tuple[int, int], bool, list[tuple]]:
    """(repeats, within tolerance, per layer (k_machine, k_cross, spacing, angle))."""
    length, width = geo.stitch_repeat()
    m = np.arange(1, MAX_REPEATS + 1)
    m_x, m_y = np.meshgrid(m, m, indexing="ij")
    score = np.zeros(m_x.shape)
    fits = []
    for i, layer in enumerate(geo.tow_layers):
        theta = np.radians(layer.orientation_deg)
        period_x, period_y = m_x * length, m_y * width
        k_x = np.rint(period_x * np.sin(theta) / layer.spacing)
        k_y = np.rint(period_y * np.cos(theta) / layer.spacing)
        q = np.hypot(k_x / period_x, k_y / period_y)
        with np.errstate(divide="ignore", invalid="ignore"):
            spacing = np.where(q > 0, 1.0 / q, np.inf)
        angle = np.degrees(np.arctan2(k_x / period_x, k_y / period_y))
        d_angle = (angle - layer.orientation_deg + 90.0) % 180.0 - 90.0
        layer_score = np.maximum(
            np.abs(spacing / layer.spacing - 1.0) / SPACING_TOLERANCE,
            np.abs(d_angle) / ANGLE_TOLERANCE_DEG,
        )
        tows = np.gcd(np.abs(k_x).astype(int), np.abs(k_y).astype(int))
        row = geo.placement_rows()[i] if i < len(geo.placement_rows()) else (1,)
        repeats = (tows > 0) & (tows % max(1, len(row)) == 0)
        score = np.maximum(score, np.where(repeats, layer_score, np.inf))
        fits.append((k_x, k_y, spacing, angle))
    area = m_x * m_y
    order = np.lexsort((m_y.ravel(), m_x.ravel(), area.ravel()))
    ok = score.ravel()[order] <= 1.0
    if ok.any():
        best = int(order[int(np.argmax(ok))])
    else:
        best = int(np.argmin(np.where(np.isfinite(score.ravel()), score.ravel(), np.inf)))
    a, b = np.unravel_index(best, m_x.shape)
    layers = [
        (int(kx[a, b]), int(ky[a, b]), float(s[a, b]), float(t[a, b])) for kx, ky, s, t in fits
    ]
    return (int(m_x[a, b]), int(m_y[a, b])), bool(score[a, b] <= 1.0), layers


def numpy_extremes(c: list[float], start: float, end: float) -> tuple[float, float, float]:
    """Ends, a 513-point grid and the companion-matrix roots of the derivative."""
    coefficients = np.trim_zeros(np.asarray(c, dtype=float), "b")
    if coefficients.size == 0:
        return 0.0, start, 0.0
    candidates = [start, end, *np.linspace(start, end, 513)]
    # leading terms too small to matter on the interval only send the roots astray
    size = np.abs(coefficients) * max(abs(start), abs(end), 1.0) ** np.arange(coefficients.size)
    significant = np.nonzero(size > 1e-14 * size.max())[0] if size.max() > 0 else [0]
    trimmed = coefficients[: int(significant[-1]) + 1]
    if trimmed.size > 2:
        for root in npoly.polyroots(npoly.polyder(trimmed)):
            if abs(root.imag) <= 1e-9 * max(1.0, abs(root.real)) and start < root.real < end:
                candidates.append(float(root.real))
    values = npoly.polyval(np.asarray(candidates), coefficients)
    k = int(np.argmin(values))
    return float(values[k]), float(candidates[k]), float(np.max(values))


# -- generated fabrics ------------------------------------------------------------------------

ANGLES = st.sampled_from([0.0, 90.0, 45.0, -45.0, 30.0, -60.0, 22.5, 15.0]) | st.floats(-90, 90)


@st.composite
def geometries(draw: st.DrawFn) -> WarpKnitGeometry:
    layers = tuple(
        TowLayer(
            orientation_deg=draw(ANGLES),
            spacing=draw(st.floats(0.5, 8.0)) * MM,
            tow=TowType("glass", 600.0, width=2.5 * MM, height=0.2 * MM),
            offset=draw(st.floats(0.0, 2.0)) * MM,
        )
        for _ in range(draw(st.integers(1, 4)))
    )
    levels = tuple(
        ThreadLevel(
            sequence=parse_lapping(
                draw(st.sampled_from(["1-0/1-2", "1-0/0-1", "1-0/2-3", "0-1/2-1"]))
            ),
            overlap_length=draw(st.floats(4.0, 9.0)) * MM,
            stitch_length=2.5 * MM,
            linear_density_tex=7.6,
            gauge_needles_per_inch=draw(st.sampled_from([5.0, 7.0, 12.0])),
        )
        for _ in range(draw(st.integers(1, 2)))
    )
    return WarpKnitGeometry(tow_layers=layers, thread_levels=levels)


def layer_scores(geo: WarpKnitGeometry, cell: tuple[int, int]) -> list[float]:
    """Each layer's score on ``cell`` (the fit's own scoring)."""
    length, width = geo.stitch_repeat()
    lattices = [
        _LayerLattice(layer, length, width, geo._row_length(i))
        for i, layer in enumerate(geo.tow_layers)
    ]
    return [lattice.score(*cell) for lattice in lattices]


#: Found by hypothesis: no cell fits, and the 29.25° layer's score is the same on the cells
#: 4 × 3 and 4 × 8 (it depends on m_x alone there); the 0° layer fits 4 × 8 far better.
_GLASS = TowType("glass", 600.0, width=2.5 * MM, height=0.2 * MM)
TIED_WORST_LAYER = WarpKnitGeometry(
    tow_layers=(
        TowLayer(29.25, 0.0032265625000000003, _GLASS, 0.0),
        TowLayer(0.0, 1.0 * MM, _GLASS, 0.0),
    ),
    thread_levels=(
        ThreadLevel(
            sequence=parse_lapping("1-0/1-2"),
            overlap_length=4.0 * MM,
            stitch_length=2.5 * MM,
            linear_density_tex=7.6,
            gauge_needles_per_inch=7.0,
        ),
    ),
)


def test_a_tie_in_the_worst_layer_goes_to_the_cell_the_other_layers_fit():
    """Every cell scored in the test: the fit's worst layer is the least worst of all cells,
    and among the cells whose worst layer ties with it, its layers' sum is the smallest."""
    fit = TIED_WORST_LAYER.cell_fit
    assert not fit.within_tolerance
    cells = [(m_x, m_y) for m_x in range(1, MAX_REPEATS + 1) for m_y in range(1, MAX_REPEATS + 1)]
    scores = {cell: layer_scores(TIED_WORST_LAYER, cell) for cell in cells}
    least = min(max(v) for v in scores.values())
    tied = [cell for cell, v in scores.items() if math.isclose(max(v), least, rel_tol=1e-9)]
    assert (4, 3) in tied and len(tied) > 1  # the tie the example is about
    assert fit.repeats in tied
    assert sum(scores[fit.repeats]) == min(sum(scores[cell]) for cell in tied)
    assert sum(scores[fit.repeats]) < sum(scores[(4, 3)])


@settings(max_examples=150, deadline=None)
@given(geometries())
@example(TIED_WORST_LAYER)
def test_cell_fit_picks_the_cell_numpy_picked(geo: WarpKnitGeometry) -> None:
    repeats, within, layers = numpy_cell_fit(geo)
    fit = geo.cell_fit
    assert fit.within_tolerance == within
    if not within and fit.repeats != repeats:
        # No cell fits, and two cells' worst layers score the same to rounding: numpy's last
        # bit picked one of them, the fit takes the one whose other layers fit better.
        new, old = layer_scores(geo, fit.repeats), layer_scores(geo, repeats)
        assert math.isclose(max(new), max(old), rel_tol=1e-9)
        assert sum(new) < sum(old)
        return
    assert fit.repeats == repeats
    for fitted, (k_machine, k_cross, spacing, angle) in zip(fit.layers, layers, strict=True):
        assert (fitted.k_machine, fitted.k_cross) == (k_machine, k_cross)
        # math.hypot/atan2 and numpy's may differ in the last bit; nothing more
        assert math.isclose(fitted.spacing, spacing, rel_tol=1e-15) or spacing == math.inf
        assert math.isclose(fitted.orientation_deg, angle, rel_tol=1e-15, abs_tol=1e-13)


@settings(max_examples=60, deadline=None)
@given(geometries())
def test_stitch_path_and_thread_length_are_numpy_s(geo: WarpKnitGeometry) -> None:
    for k in range(len(geo.thread_levels)):
        path = geo.stitch_path(k)
        # the thread closes on the next repeat: last point = first point + one repeat along x
        shift = path.points[-1] - path.points[0]
        assert np.array_equal(shift, [geo.thread_levels[k].repeat_length, 0.0, 0.0])
        assert np.array_equal(np.vstack(path.overlaps), path.points[:-1])
        assert np.array_equal(path.underlaps[:, 0], path.points[4:-1:5])
        assert np.array_equal(path.underlaps[:, 1], path.points[5::5])
        # bit for bit what numpy's norm and sum give
        expected = float(np.linalg.norm(np.diff(path.points, axis=0), axis=1).sum())
        assert geo.thread_length_per_repeat(k) == expected


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0.0, 1e3), min_size=1, max_size=300))
def test_polyline_length_sums_as_numpy_does(steps: list[float]) -> None:
    """Segment lengths summed in numpy's pairwise order, for any count of segments."""
    points = [(0.0, 0.0, 0.0)]
    for i, step in enumerate(steps):
        x, y, z = points[-1]
        points.append((x + step, y + 0.1 * step * (i % 3), z - 0.01 * step))
    expected = float(np.linalg.norm(np.diff(np.array(points), axis=0), axis=1).sum())
    assert polyline_length(points) == expected


# -- polynomials ------------------------------------------------------------------------------

COEFFICIENT = st.floats(-1.0, 1.0, allow_subnormal=False)


@settings(max_examples=300, deadline=None)
@given(
    st.lists(COEFFICIENT, min_size=1, max_size=9),
    st.sampled_from([20.0, 45.0, 60.0, 70.0, 90.0]),
)
@example(raw=[0.0, 0.7200358324442404, -1.0, 1.7303754948657723e-13], end=20.0)
# slopes ~1e-198 and ~1e-195 either side of the hump: their product underflowed to 0
@example(raw=[0.0, 1.416030275987887e-198, -6.118341350390407e-195], end=20.0)
# no linear term: the slope is exactly 0 at the grid's first point and a hump of 5.7e-7 rises
# before the next one (found by the quick hypothesis profile)
@example(raw=[0.0, 0.0, 0.015625, -1.0], end=20.0)
def test_polynomial_extremes_agree_with_companion_roots(raw: list[float], end: float) -> None:
    """As extreme as the companion-matrix roots find (those can be off where the other root is
    huge: the example's, 7.7e12, put numpy's maximum 1.1e-7 low) and never past what the
    polynomial reaches: a dense grid plus its second-derivative bound h²/8 · max|p''|."""
    c = [a * (10.0 / end) ** k for k, a in enumerate(raw)]  # every term matters on [0, end]
    low, at, high = polynomial_extremes(c, 0.0, end)
    ref_low, _, ref_high = numpy_extremes(c, 0.0, end)
    scale = max(abs(ref_low), abs(ref_high), 1e-300)
    assert low <= ref_low + 1e-12 * scale
    assert high >= ref_high - 1e-12 * scale
    grid = np.linspace(0.0, end, 20001)
    values = npoly.polyval(grid, c)
    h = grid[1] - grid[0]
    bend = sum(k * (k - 1) * abs(a) * end ** (k - 2) for k, a in enumerate(c) if k >= 2)
    slack = h * h / 8.0 * bend + 1e-12 * scale
    assert low >= values.min() - slack
    assert high <= values.max() + slack
    assert 0.0 <= at <= end
    assert abs(polynomial_value(c, at) - low) <= 1e-12 * scale


def test_polynomial_extremes_of_a_parabola_are_its_vertex_and_an_end() -> None:
    """(x − 23.7)² + 1 on [0, 60]: minimum 1 at the vertex, maximum at x = 60."""
    a = 23.7
    low, at, high = polynomial_extremes([a * a + 1.0, -2.0 * a, 1.0], 0.0, 60.0)
    assert math.isclose(at, a, rel_tol=1e-12)
    assert math.isclose(low, 1.0, rel_tol=1e-12)
    assert math.isclose(high, (60.0 - a) ** 2 + 1.0, rel_tol=1e-12)


def test_polynomial_value_is_numpy_polyval() -> None:
    c = [0.3, -1.2e-2, 4.5e-4, -2.2e-6, 1.1e-8]
    for x in np.linspace(0.0, 80.0, 97):
        assert polynomial_value(c, float(x)) == float(npoly.polyval(float(x), c))
