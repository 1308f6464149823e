"""The fibre-pattern figure's 3D view drawn in 2D (issue 15g): the projection against mplot3d's
own, the painter's order, the panel's content, and the PNG file written without matplotlib's
writer."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from preform.base import figures
from preform.base.figures import new_figure, png_bytes, save_figure
from preform.export.fig_drape import (
    VIEW_AZIMUTH_DEG,
    VIEW_ELEVATION_DEG,
    fibre_pattern_figure,
    painter_order,
    shear_view_quads,
    view_axes,
)

angles = dict(
    elevation=st.floats(-89.0, 89.0),
    azimuth=st.floats(-180.0, 180.0),
)


@settings(max_examples=25, deadline=None)
@given(**angles)
def test_the_view_is_mplot3ds_orthographic_projection(elevation, azimuth):
    """Screen x, y of points equal mplot3d's orthographic projection up to one scale (the box
    normalisation), and the depth towards the viewer is mplot3d's depth reversed."""
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d import proj3d

    ax = Figure().add_subplot(projection="3d", proj_type="ortho")
    ax.view_init(elevation, azimuth)
    for set_lim in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        set_lim(-1.0, 1.0)
    ax.set_box_aspect((1, 1, 1))
    points = np.random.default_rng(1).uniform(-1.0, 1.0, (40, 3))
    theirs = np.stack(proj3d.proj_transform(*points.T, ax.get_proj()), axis=1)
    ours = points @ view_axes(elevation, azimuth).T
    scale = np.linalg.lstsq(ours[:, :2].reshape(-1, 1), theirs[:, :2].ravel(), rcond=None)[0]
    assert scale[0] > 0
    np.testing.assert_allclose(scale[0] * ours[:, :2], theirs[:, :2], atol=1e-12)
    depth = np.polyfit(ours[:, 2], theirs[:, 2], 1)
    assert depth[0] < 0  # mplot3d's depth grows away from the viewer
    np.testing.assert_allclose(np.polyval(depth, ours[:, 2]), theirs[:, 2], atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(**angles)
def test_the_view_axes_are_the_camera_rotation(elevation, azimuth):
    """A second derivation: turn the scene about z by −(azimuth + 90°), then tilt it about the
    screen's x by elevation − 90°; the rows are a right-handed orthonormal frame."""

    def about_z(t):
        c, s = math.cos(t), math.sin(t)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def about_x(t):
        c, s = math.cos(t), math.sin(t)
        return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])

    camera = about_x(math.radians(elevation - 90.0)) @ about_z(math.radians(-azimuth - 90.0))
    axes = view_axes(elevation, azimuth)
    np.testing.assert_allclose(axes, camera, atol=1e-14)
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(axes) == pytest.approx(1.0)


def test_from_straight_above_the_view_is_the_plan():
    np.testing.assert_allclose(view_axes(90.0, -90.0), np.eye(3), atol=1e-15)


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 30),
    gap=st.floats(0.5, 50.0),
    elevation=st.floats(5.0, 85.0),
    azimuth=st.floats(-180.0, 180.0),
    seed=st.integers(0, 2**31),
)
def test_a_cell_hidden_behind_another_is_drawn_first(n, gap, elevation, azimuth, seed):
    """Two layers of cells (a hat's top over its base, a fold over the net): each cell of the
    near layer is the far one moved towards the viewer, so it covers it on the screen and must
    paint after it, whatever the order the cells come in."""
    rng = np.random.default_rng(seed)
    axes = view_axes(elevation, azimuth)
    far = rng.uniform(-100.0, 100.0, (n, 1, 3)) + rng.uniform(-3.0, 3.0, (n, 4, 3))
    near = far + gap * axes[2]
    polygons = np.concatenate([far, near])
    shuffle = rng.permutation(2 * n)
    order = shuffle[painter_order(polygons[shuffle], axes[2])]
    rank = np.empty(2 * n, dtype=int)
    rank[order] = np.arange(2 * n)
    assert np.all(rank[n:] > rank[:n])  # near cell k after far cell k
    np.testing.assert_allclose(near @ axes[:2].T, far @ axes[:2].T, atol=1e-9)  # same place
    depth = polygons[order].mean(axis=1) @ axes[2]
    assert np.all(np.diff(depth) >= 0)


def by_gid(fig, gid):
    (artist,) = [a for a in fig.get_children() if a.get_gid() == gid]
    return artist


def test_the_shear_cells_are_the_quads_projected_in_depth_order(make_net, make_energy):
    """The drawn polygons are the blocked quads (and nothing else) seen from the panel's view,
    farthest first; locked cells keep their black outline, failed ones their own."""
    net = make_net(14, 16, dome=True, unplaced=[(0, 0)])
    energy = make_energy(net)
    fig = fibre_pattern_figure(net, energy, None, size_px=(800, 400))
    cells = by_gid(fig, "shear cells")
    view = shear_view_quads(
        net,
        np.asarray(net.valid),
        np.asarray(energy.past_locking),
        past_failure=np.asarray(energy.past_failure),
    )
    axes = view_axes(VIEW_ELEVATION_DEG, VIEW_AZIMUTH_DEG)
    depth = view.quads_mm.mean(axis=1) @ axes[2]
    order = np.argsort(depth, kind="stable")
    drawn = np.array([p.vertices[:4] for p in cells.get_paths()])
    np.testing.assert_allclose(drawn, view.quads_mm[order] @ axes[:2].T, atol=1e-9)
    outlined = np.asarray(cells.get_linewidths()) > 0.5
    marked = np.asarray(view.locked) | np.asarray(view.failed)
    np.testing.assert_array_equal(outlined, marked[order])
    assert np.count_nonzero(outlined) > 0


def test_the_panel_frames_the_net_with_round_ticks_in_mm(make_net, make_energy):
    """Each axis of the box has round ticks [mm] spanning the drawn net, and its label."""
    net = make_net(12, 12, dome=True)
    fig = fibre_pattern_figure(net, make_energy(net), None, size_px=(800, 400))
    from matplotlib.text import Text

    assert len(fig.axes) == 1  # the top view; the 3D view, its frame and ticks are drawn
    panel = [a for a in fig.artists if isinstance(a, Text)]
    texts = [t.get_text() for t in panel]
    nodes_mm = 1e3 * np.asarray(net.nodes).reshape(-1, 3)
    for a, name in enumerate("xyz"):
        assert f"{name} [mm]" in texts
        ticks = [
            float(t.get_text().replace("\N{MINUS SIGN}", "-"))
            for t in panel
            if t.get_gid() == f"{name} tick"
        ]
        lo, hi = nodes_mm[:, a].min(), nodes_mm[:, a].max()
        pad = 0.02 * np.ptp(nodes_mm, axis=0).max()
        assert len(ticks) >= 2
        assert lo - pad <= min(ticks) and max(ticks) <= hi + pad
        step = np.diff(ticks)
        np.testing.assert_allclose(step, step[0])
        mantissa = step[0] / 10 ** math.floor(math.log10(step[0]))
        assert min(abs(mantissa - m) for m in (1, 2, 2.5, 5, 10)) < 1e-9
        # the ticks cover most of the range: no more than a step empty at either end
        assert min(ticks) - lo < step[0] + pad and hi - max(ticks) < step[0] + pad


def test_a_net_with_a_fold_draws_its_triangle_with_the_cells(make_net, make_energy):
    net = make_net(10, 10, folded=[(7, 7)])
    from preform.drape.engine.result import NodeStatus

    status = np.asarray(net.status).copy()
    status[8, 8] = NodeStatus.FOLDED
    import dataclasses

    net = dataclasses.replace(net, status=status)
    fig = fibre_pattern_figure(net, make_energy(net), None, size_px=(800, 400))
    cells = by_gid(fig, "shear cells")
    view = shear_view_quads(net, np.asarray(net.valid), None)
    assert len(cells.get_paths()) == len(view.quads_mm) + 1
    orange = [tuple(np.round(c, 3)) for c in cells.get_facecolors()]
    assert orange.count((0.878, 0.541, 0.0, 1.0)) == 1  # FOLD_COLOUR #e08a00
    # its mark sits at the triangle's centre, seen from the view
    from preform.export.fig_drape import fold_triangles

    centre = 1e3 * fold_triangles(net).mean(axis=1) @ view_axes(30.0, -60.0)[:2].T
    np.testing.assert_allclose(by_gid(fig, "fold marks").get_xydata(), centre)


@settings(max_examples=30, deadline=None)
@given(
    height=st.integers(1, 40),
    width=st.integers(1, 40),
    level=st.integers(0, 9),
    seed=st.integers(0, 2**31),
)
def test_png_bytes_decode_to_the_image(height, width, level, seed):
    """Pillow, an independent decoder, reads back every pixel."""
    from PIL import Image

    rng = np.random.default_rng(seed)
    image = rng.integers(0, 256, (height, width, 3), dtype=np.uint8)
    decoded = Image.open(io.BytesIO(png_bytes(image, level)))
    assert decoded.mode == "RGB"
    np.testing.assert_array_equal(np.asarray(decoded), image)


def test_png_bytes_rejects_what_is_not_8_bit_rgb():
    with pytest.raises(ValueError, match="uint8"):
        png_bytes(np.zeros((4, 4, 4), dtype=np.uint8))
    with pytest.raises(ValueError, match="uint8"):
        png_bytes(np.zeros((4, 4, 3)))


@settings(
    max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(size=st.sampled_from([(300, 200), (420, 260)]), seed=st.integers(0, 100))
def test_a_saved_png_is_the_figure_as_matplotlib_draws_it(tmp_path, size, seed):
    """save_figure draws on a renderer kept between figures: each file is still exactly its
    own figure as a fresh Agg canvas draws it (nothing left from the figure before)."""
    import matplotlib
    from PIL import Image

    rng = np.random.default_rng(seed)
    for n in range(2):
        fig = new_figure(size)
        ax = fig.add_subplot()
        ax.plot(rng.normal(size=20), label=f"series {n}")
        ax.set_title(f"figure {n} of seed {seed}")
        ax.legend()
        path = tmp_path / f"f{n}.png"
        save_figure(fig, path)
        with matplotlib.rc_context(figures.DRAW_RC):
            fig.canvas.draw()
        expected = np.asarray(fig.canvas.buffer_rgba())[..., :3]
        np.testing.assert_array_equal(np.asarray(Image.open(path)), expected)


def test_other_formats_still_go_through_matplotlib(tmp_path):
    fig = new_figure((200, 100))
    fig.add_subplot().plot([0, 1], [1, 0])
    save_figure(fig, tmp_path / "f.svg")
    assert (tmp_path / "f.svg").read_text(encoding="utf-8").lstrip().startswith("<?xml")


def test_the_kept_renderers_are_few_and_per_thread(tmp_path):
    """One renderer a figure size, at most KEPT_RENDERERS of them; another thread keeps its own."""
    import threading

    sizes = [(100 + 10 * n, 80) for n in range(figures.KEPT_RENDERERS + 2)]
    for n, size in enumerate(sizes):
        fig = new_figure(size)
        fig.add_subplot().plot([0, n])
        save_figure(fig, tmp_path / f"{n}.png")
    kept = figures._renderers.by_size
    assert len(kept) == figures.KEPT_RENDERERS
    assert {key[:2] for key in kept} == set(sizes[-figures.KEPT_RENDERERS :])
    seen = []

    def other() -> None:
        save_figure(new_figure(sizes[-1]), tmp_path / "other.png")
        seen.append(figures._renderers.by_size[(*sizes[-1], 100.0)])

    thread = threading.Thread(target=other)
    thread.start()
    thread.join()
    assert seen and seen[0] is not kept[(*sizes[-1], 100.0)]


def test_a_flat_nets_z_edge_gets_one_tick(make_net):
    """Seen nearly end-on, the z edge of a flat net's box has one tick, at z = 0."""
    from matplotlib.text import Text

    fig = fibre_pattern_figure(make_net(6, 6, generator_angle_deg=70.0), None, None)
    z_ticks = [a.get_text() for a in fig.artists if isinstance(a, Text) and a.get_gid() == "z tick"]
    assert z_ticks == ["0"]
