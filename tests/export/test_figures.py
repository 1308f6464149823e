from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from preform.drape.engine.result import CellStatus
from preform.export.fig_curves import energy_vs_angle_figure
from preform.export.fig_drape import (
    SHEAR_SCALE_DEG,
    SHEAR_VIEW_MAX_QUADS,
    fibre_lines,
    fibre_pattern_figure,
    part_edge_segments,
    shear_view_quads,
)
from preform.export.fig_unit_cell import refine_polyline, tow_ribbon, unit_cell_figure
from preform.shear.figures import shear_curve_figure


def by_gid(fig, gid):
    """The one artist of ``fig`` (the shear view's are the figure's own) with that gid."""
    (artist,) = [a for a in fig.get_children() if a.get_gid() == gid]
    return artist


def panel_texts(fig):
    """The texts the 3D shear view draws (on the figure, not in an axes)."""
    from matplotlib.text import Text

    return [a.get_text() for a in fig.artists if isinstance(a, Text)]


def assert_real_picture(pixels: np.ndarray, size_px: tuple[int, int], min_colours: int) -> None:
    width, height = size_px
    assert pixels.shape[:2] == (height, width)
    rgb = pixels[..., :3]
    assert rgb.var() > 1e-3, "image is (nearly) blank"
    colours = np.unique((rgb * 255).round().astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > min_colours


def test_unit_cell_figure_by_level(tmp_path, unit_cell, read_png):
    path = tmp_path / "cell.png"
    fig = unit_cell_figure(unit_cell, path, repeats=(2, 2), size_px=(640, 480))

    assert_real_picture(read_png(path), (640, 480), min_colours=50)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["level 1 (warp)", "level 2 (weft)", "level 3 (stitch)"]
    # 2 × 2 repeats; long segments are split to about a tow width for depth sorting.
    quads = sum(len(tow_ribbon(t, max_segment=t.width)) for t in unit_cell.tows)
    assert quads > 4 * 16 + 2
    assert len(fig.axes[0].collections[0].get_paths()) == 4 * quads
    assert "drawn ×" in fig.axes[0].get_zlabel()  # 0.8 mm thick over 16 mm: exaggerated


def test_unit_cell_figure_by_type_uses_level_names_and_types(tmp_path, unit_cell, read_png):
    path = tmp_path / "cell_types.png"
    fig = unit_cell_figure(unit_cell, path, colour_by="type", size_px=(500, 400), title="PW")
    assert_real_picture(read_png(path), (500, 400), min_colours=50)
    labels = {t.get_text() for t in fig.axes[0].get_legend().get_texts()}
    assert labels == {"glass 600 tex", "glass 1200 tex", "polyester"}
    with pytest.raises(ValueError, match="colour_by"):
        unit_cell_figure(unit_cell, tmp_path / "x.png", colour_by="colour")


def test_refined_ribbon_keeps_the_path(unit_cell):
    stitch = unit_cell.tows[-1]
    fine = refine_polyline(stitch.points, 1e-3)
    assert np.max(np.linalg.norm(np.diff(fine, axis=0), axis=1)) <= 1e-3 + 1e-15
    assert len(fine) == 1 + 1 + 9  # 0.8 mm leg stays whole, 8.9 mm leg in 9 pieces
    np.testing.assert_allclose(fine[[0, 1, -1]], stitch.points)
    ribbon = tow_ribbon(stitch, max_segment=1e-3)
    assert ribbon.shape == (len(fine) - 1, 4, 3)


def test_ribbon_is_a_flat_strip_of_the_tow_width(unit_cell):
    warp = unit_cell.tows[0]
    quads = tow_ribbon(warp)
    assert quads.shape == (len(warp.points) - 1, 4, 3)
    across = quads[:, 0] - quads[:, 3]  # left minus right at each segment start
    np.testing.assert_allclose(np.linalg.norm(across, axis=1), warp.width)
    np.testing.assert_allclose(across[:, 2], 0.0, atol=1e-15)  # in the fabric plane
    # The stitch's vertical first leg borrows the next in-plane direction: no NaN, right width.
    stitch = tow_ribbon(unit_cell.tows[-1])
    assert np.all(np.isfinite(stitch))
    np.testing.assert_allclose(np.linalg.norm(stitch[:, 0] - stitch[:, 3], axis=1), 0.3e-3)


def test_fibre_pattern_figure(tmp_path, damaged_net, make_energy, read_png):
    path = tmp_path / "pattern.png"
    fig = fibre_pattern_figure(
        damaged_net,
        make_energy(damaged_net),
        path,
        title="dome",
        tow_every=2,
        size_px=(1200, 600),
    )
    assert_real_picture(read_png(path), (1200, 600), min_colours=100)

    (top,) = fig.axes  # the shear view is drawn on the figure (fig_drape._Panel)
    u_fibres = top.get_lines()[0].get_xydata()
    # Lines of constant j through the start node (j0 = 6) every 2nd: j = 0, 2, ..., 10.
    assert fibre_lines(damaged_net, "u", 2) == [0, 2, 4, 6, 8, 10]
    assert fibre_lines(damaged_net, "v", 4) == [1, 5, 9]
    assert len(u_fibres) == 6 * (10 + 1)
    # The line j = 0 starts at unplaced node (0, 0): a break, then placed nodes in mm.
    assert np.all(np.isnan(u_fibres[0]))
    np.testing.assert_allclose(u_fibres[1], 1e3 * damaged_net.nodes[1, 0, :2])
    # Node (9, 5) is unplaced but j = 5 is not drawn at tow_every=2; j = 4 is whole.
    assert np.all(np.isfinite(u_fibres[2 * 11 : 2 * 11 + 10]))
    cells = by_gid(fig, "shear cells")
    assert len(cells.get_paths()) == np.count_nonzero(damaged_net.valid)
    # The colour scale spans the fixed ±SHEAR_SCALE_DEG (every figure alike), centred at zero,
    # labelled in degrees.
    scale = by_gid(fig, "colour scale")
    half = SHEAR_SCALE_DEG
    assert scale.norm.vmin == pytest.approx(-half) and scale.norm.vmax == pytest.approx(half)
    values = scale.get_array()
    assert values.min() == pytest.approx(-half) and values.max() == pytest.approx(half)
    texts = panel_texts(fig)
    assert "signed shear angle γ [deg]" in texts
    assert {"x [mm]", "y [mm]", "z [mm]"} <= set(texts)
    title = by_gid(fig, "shear title").get_text()
    assert title.startswith("Shear angle (black outline: past locking)")


def test_fibre_pattern_figure_without_energy_on_a_flat_net(tmp_path, make_net, read_png):
    path = tmp_path / "flat.png"
    fibre_pattern_figure(make_net(6, 6, generator_angle_deg=70.0), None, path, size_px=(800, 400))
    assert_real_picture(read_png(path), (800, 400), min_colours=30)


def _shear_curves() -> dict:
    angle = np.linspace(0.0, 50.0, 26)
    force_pos = 0.002 * angle + 1e-6 * angle**3
    force_neg = 0.001 * angle + 5e-7 * angle**3
    return {
        "angle_deg": angle.tolist(),
        "positive": {
            "force_N_per_mm": force_pos,
            "energy_J_per_m2": np.cumsum(force_pos) * 0.5,
            "label": "parallel to stitch",
        },
        "negative": {"force_N_per_mm": -force_neg, "energy_J_per_m2": np.cumsum(force_neg) * 0.5},
        "failure_angle_deg": 35.0,
    }


def test_shear_curve_figure(tmp_path, read_png):
    path = tmp_path / "shear.png"
    fig = shear_curve_figure(_shear_curves(), path, title="E-BX 318", size_px=(1000, 450))
    assert_real_picture(read_png(path), (1000, 450), min_colours=30)
    force_ax, energy_ax = fig.axes
    labels = [t.get_text() for t in force_ax.get_legend().get_texts()]
    assert labels == ["parallel to stitch", "negative shear (γ < 0)", "stitch failure"]
    # Signed negative-sense forces are drawn as magnitudes.
    assert np.all(force_ax.get_lines()[1].get_ydata() >= 0)
    assert "N/mm" in force_ax.get_ylabel() and "J/m²" in energy_ax.get_ylabel()


def test_shear_curve_figure_rejects_mismatched_lengths(tmp_path):
    curves = _shear_curves()
    curves["positive"]["force_N_per_mm"] = [1.0, 2.0]
    with pytest.raises(ValueError, match=r"positive\.force_N_per_mm has 2 values"):
        shear_curve_figure(curves, tmp_path / "bad.png")
    assert not (tmp_path / "bad.png").exists()


def test_energy_vs_angle_figure_marks_optima(tmp_path, read_png):
    angles = np.arange(30.0, 151.0, 5.0)
    curves = {
        "E-BXhd 936": [(a, 2.0 + 1e-3 * (a - 75.0) ** 2) for a in angles],
        "E-BX 318": [(a, 3.0 + 2e-3 * (a - 60.0) ** 2) for a in angles[::-1]]
        + [(155.0, float("nan"))],
    }
    path = tmp_path / "energy.png"
    fig = energy_vs_angle_figure(
        curves, path, optima={"E-BXhd 936": 75.0, "E-BX 318": 60.0}, size_px=(700, 500)
    )
    assert_real_picture(read_png(path), (700, 500), min_colours=30)
    stars = [line for line in fig.axes[0].get_lines() if line.get_marker() == "*"]
    assert [tuple(s.get_xydata()[0]) for s in stars] == [(75.0, 2.0), (60.0, 3.0)]
    # Sorted by angle, NaN dropped.
    second = fig.axes[0].get_lines()[2].get_xydata()
    assert np.all(np.diff(second[:, 0]) > 0) and np.all(np.isfinite(second))


def _blocks_by_loop(net, drawn, locked, k):
    """A second implementation of the 3D view's quads: loop over k × k blocks, a whole block
    one quad (its largest-|γ| cell's shear, locked if any cell is), every other cell alone."""
    nodes = 1e3 * net.nodes
    shear = np.degrees(net.shear)
    quads, values, flags, covered = [], [], [], np.zeros_like(drawn)
    for bi in range(drawn.shape[0] // k):
        for bj in range(drawn.shape[1] // k):
            cells = [(bi * k + a, bj * k + b) for a in range(k) for b in range(k)]
            if k > 1 and all(drawn[c] for c in cells):
                i, j = bi * k, bj * k
                quads.append([nodes[i, j], nodes[i + k, j], nodes[i + k, j + k], nodes[i, j + k]])
                values.append(max((shear[c] for c in cells), key=abs))
                flags.append(any(locked[c] for c in cells))
                for c in cells:
                    covered[c] = True
    for i, j in zip(*np.nonzero(drawn & ~covered), strict=True):
        quads.append([nodes[i, j], nodes[i + 1, j], nodes[i + 1, j + 1], nodes[i, j + 1]])
        values.append(shear[i, j])
        flags.append(locked[i, j])
    return np.asarray(quads).reshape(-1, 4, 3), np.asarray(values), np.asarray(flags, dtype=bool)


def _quad_area(quads):
    """Area [mm²] of planar quads (two triangles; exact for the flat nets below)."""
    a = np.cross(quads[:, 1] - quads[:, 0], quads[:, 2] - quads[:, 0])
    b = np.cross(quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 0])
    return 0.5 * (np.linalg.norm(a, axis=1) + np.linalg.norm(b, axis=1))


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    ni=st.integers(3, 24),
    nj=st.integers(3, 24),
    alpha=st.floats(35.0, 145.0),
    max_quads=st.integers(1, 400),
    seed=st.integers(0, 2**31),
)
def test_shear_view_blocks_keep_area_extremes_and_locking(make_net, ni, nj, alpha, max_quads, seed):
    """Coarser quads on big nets: the drawn area is the drawn cells' area (a flat net's blocks
    are exact parallelograms), the largest |γ| is kept, every locked cell stays outlined, and a
    loop over the blocks gives the same quads."""
    rng = np.random.default_rng(seed)
    net = make_net(ni, nj, generator_angle_deg=alpha)
    net_shear = np.asarray(net.shear) + rng.normal(0.0, 0.1, net.shear.shape)  # cells differ
    net = dataclasses.replace(net, shear=net_shear)
    drawn = np.asarray(net.valid) & (rng.random(net.shear.shape) > 0.15)
    locked = drawn & (rng.random(net.shear.shape) > 0.8)
    view = shear_view_quads(net, drawn, locked, max_quads=max_quads)
    count = np.count_nonzero(drawn)
    assert view.block == max(1, math.ceil(math.sqrt(count / max_quads)))
    quads, values, flags = _blocks_by_loop(net, drawn, locked, view.block)
    np.testing.assert_allclose(view.quads_mm, quads)
    np.testing.assert_array_equal(view.shear_deg, values)
    np.testing.assert_array_equal(view.locked, flags)
    cell_area = (1e3 * net.node_spacing) ** 2 * abs(np.sin(np.radians(alpha)))
    assert _quad_area(view.quads_mm).sum() == pytest.approx(count * cell_area, rel=1e-9)
    if count:
        assert np.max(np.abs(view.shear_deg)) == np.max(np.abs(np.degrees(net_shear[drawn])))
    assert np.count_nonzero(view.locked) >= (1 if locked.any() else 0)


def test_fibre_pattern_of_a_fine_net_draws_blocks_and_says_so(
    tmp_path, make_net, make_energy, read_png
):
    net = make_net(120, 120, dome=True)
    fig = fibre_pattern_figure(net, make_energy(net), tmp_path / "fine.png", size_px=(800, 400))
    cells = np.count_nonzero(np.asarray(net.valid) & (np.asarray(net.part_weight) > 0))
    drawn = len(by_gid(fig, "shear cells").get_paths())
    assert drawn <= SHEAR_VIEW_MAX_QUADS < cells
    assert "one quad per 3 × 3 cells" in by_gid(fig, "shear title").get_text()
    assert_real_picture(read_png(tmp_path / "fine.png"), (800, 400), min_colours=30)


def _edge_by_loop(net, phi):
    """A second implementation of the part's edge: cell by cell, side by side round the cell."""
    nodes = 1e3 * net.nodes
    corners = ((0, 0), (1, 0), (1, 1), (0, 1))
    segments = []
    for ci, cj in zip(*np.nonzero(net.cell_status == CellStatus.VALID), strict=True):
        values = [phi[ci + a, cj + b] for a, b in corners]
        if min(values) >= 0 or max(values) < 0:
            continue
        points = []
        for k in range(4):
            (a0, b0), (a1, b1) = corners[k], corners[(k + 1) % 4]
            f0, f1 = values[k], values[(k + 1) % 4]
            if (f0 >= 0) != (f1 >= 0):
                t = f0 / (f0 - f1)
                points.append((1 - t) * nodes[ci + a0, cj + b0] + t * nodes[ci + a1, cj + b1])
        segments.append(points[:2])
    return np.asarray(segments, dtype=float).reshape(-1, 2, 3)


@dataclasses.dataclass
class _Disc:
    """A part whose level function is a disc in plan [m] (positive inside)."""

    x: float
    y: float
    radius: float

    saddle: bool = False

    def level(self, points):
        dx, dy = points[..., 0] - self.x, points[..., 1] - self.y
        if self.saddle:  # cells where all four sides cross: the first two sides make the line
            return dx * dy
        return self.radius - np.hypot(dx, dy)


@settings(
    max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    x=st.floats(-0.03, 0.03),
    y=st.floats(-0.03, 0.03),
    radius=st.floats(0.0, 0.06),
    dome=st.booleans(),
    saddle=st.booleans(),
)
def test_the_part_edge_matches_a_cell_by_cell_loop(make_net, x, y, radius, dome, saddle):
    net = make_net(12, 14, dome=dome, unplaced=[(0, 0), (6, 7)], folded=[(3, 3)])
    part = _Disc(x, y, radius, saddle)
    phi = part.level(np.where(np.isfinite(net.nodes), net.nodes, 0.0))
    edge = part_edge_segments(net, part)
    np.testing.assert_allclose(edge, _edge_by_loop(net, phi), rtol=0, atol=1e-12)
    # Every end lies on the disc's edge where the net is flat (linear along a straight side).
    if not dome and not saddle and len(edge):
        ends = 1e-3 * edge.reshape(-1, 3)
        np.testing.assert_allclose(part.level(ends), 0.0, atol=0.006 * 0.006 / max(radius, 1e-3))
