"""The fibre pattern of a draped net: tows seen from above and the net in 3D coloured by shear
(the paper's Fig. 11)."""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.figures import new_figure, save_figure
from preform.drape.engine.part import Part
from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField, NodeStatus

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Colours of the two fibre families in the top view.
U_COLOUR = "#1f3b73"
V_COLOUR = "#9a2a1f"


def fibre_lines(result: DrapeResult, family: str, every: int = 1) -> list[int]:
    """Indices of the fibre lines of ``family`` ("u": lines of constant j running along i;
    "v": constant i) drawn at spacing ``every``, always including the generator line."""
    if every < 1:
        raise ValueError(f"tow_every must be at least 1, got {every}")
    ni, nj = result.shape
    i0, j0 = result.start_index
    count, through = (nj, j0) if family == "u" else (ni, i0)
    return [k for k in range(count) if (k - through) % every == 0]


def _part_nodes(result: DrapeResult) -> np.ndarray:
    """Nodes (ni, nj) drawn: placed, and (when the result was clipped to a part) a corner of a
    cell with some area in the part, so fabric draped past the part's edge (a hemisphere's
    run-off below its rim) is not drawn over the part in the top view."""
    placed = np.asarray(result.status == NodeStatus.PLACED)
    if result.part_share is None:
        return placed
    weight = np.asarray(result.part_weight) > 0
    near = np.zeros_like(placed)
    near[:-1, :-1] |= weight
    near[1:, :-1] |= weight
    near[:-1, 1:] |= weight
    near[1:, 1:] |= weight
    return placed & near


def part_edge_segments(result: DrapeResult, part: Part) -> np.ndarray:
    """Segments (k, 2, 3) [mm] of the part's edge across the cells it cuts: on each cut cell's
    sides φ is interpolated linearly to its zero (the rule of the cell's share, so the line is
    the one the energy was clipped along)."""
    nodes = np.asarray(result.nodes, dtype=float)
    with np.errstate(invalid="ignore"):
        phi = np.asarray(part.level(np.where(np.isfinite(nodes), nodes, 0.0)), dtype=float)
    valid = np.asarray(result.cell_status == CellStatus.VALID)
    ni, nj = phi.shape
    corners = ((0, 0), (1, 0), (1, 1), (0, 1))  # round the cell; side k runs corner k -> k+1
    values = [phi[a : ni - 1 + a, b : nj - 1 + b] for a, b in corners]
    points = [nodes[a : ni - 1 + a, b : nj - 1 + b] for a, b in corners]
    low = np.minimum.reduce(values)
    cut = valid & (low < 0) & (np.maximum.reduce(values) >= 0)
    first = np.full((*cut.shape, 3), np.nan)
    second = np.full((*cut.shape, 3), np.nan)
    found = np.zeros(cut.shape, dtype=int)
    with np.errstate(invalid="ignore", divide="ignore"):
        for k in range(4):
            f0, f1 = values[k], values[(k + 1) % 4]
            crosses = cut & ((f0 >= 0) != (f1 >= 0))
            t = (f0 / (f0 - f1))[..., None]
            point = (1 - t) * points[k] + t * points[(k + 1) % 4]
            # The first two sides crossed, in order round the cell, make the segment.
            first = np.where((crosses & (found == 0))[..., None], point, first)
            second = np.where((crosses & (found == 1))[..., None], point, second)
            found += crosses
    ci, cj = np.nonzero(cut & (found >= 2))
    segments = np.stack([first[ci, cj], second[ci, cj]], axis=1)
    return 1e3 * segments.reshape(-1, 2, 3)


def _polyline_xy(result: DrapeResult, family: str, lines: list[int]) -> np.ndarray:
    """Top-view (x, y) [mm] of the chosen fibre lines, one array with NaN rows between lines and
    at every node not drawn (unplaced, or past the part), so matplotlib breaks the line there."""
    placed = _part_nodes(result)
    xy = np.where(placed[..., None], 1e3 * np.asarray(result.nodes, dtype=float)[..., :2], np.nan)
    gap = np.full((1, 2), np.nan)
    parts: list[np.ndarray] = []
    for k in lines:
        parts.append(xy[:, k] if family == "u" else xy[k, :])
        parts.append(gap)
    return np.concatenate(parts) if parts else np.empty((0, 2))


#: Colour of the cells where the net folded (turned over at a sharp vertex or edge).
FOLD_COLOUR = "#e08a00"
#: Outline of the cells past stitch failure (past locking: black): where a warp-knit's stitch
#: breaks and the fabric no longer holds together as the law assumes.
FAILURE_COLOUR = "#d01c8b"
#: The shear colour scale of every fibre-pattern figure spans ±SHEAR_SCALE_DEG [deg], whatever
#: the fabric, so two fabrics' figures (a run's sweep) compare colour for colour: a scale per
#: figure made the same colour mean 20° in one and 45° in the next. 60° lies past the limits
#: of the bundled fabrics that have one (locking 22–53°, E-BX-318's stitch failure 35°), so
#: cells beyond it are outlined anyway; they take the end colours and the panel says how many
#: cells do. A drawing choice, not a modelling one: ``shear_scale_deg=None`` scales one figure
#: to itself.
SHEAR_SCALE_DEG = 60.0


def fold_triangles(result: DrapeResult) -> np.ndarray:
    """Where the net folded (k, 3, 3) [m]: for each FOLDED node, the triangle of its three
    placed parents, the cell that would have turned over. Beyond it lies the fold zone (the
    nodes not reached behind the fold), which has no draped position to draw."""
    i0, j0 = result.start_index
    nodes = np.asarray(result.nodes, dtype=float)
    fi, fj = np.nonzero(np.asarray(result.status) == NodeStatus.FOLDED)
    si, sj = np.sign(fi - i0), np.sign(fj - j0)
    tri = np.stack([nodes[fi - si, fj], nodes[fi - si, fj - sj], nodes[fi, fj - sj]], axis=1)
    return tri[np.all(np.isfinite(tri), axis=(1, 2))]


def _top_view(ax: Axes, result: DrapeResult, tow_every: int, edge: np.ndarray | None) -> None:
    i0, j0 = result.start_index
    if edge is not None and len(edge):
        xy = np.concatenate([edge[:, :, :2], np.full((len(edge), 1, 2), np.nan)], axis=1)
        flat = xy.reshape(-1, 2)
        ax.plot(flat[:, 0], flat[:, 1], color="0.35", lw=1.2, ls="--", label="part edge")
    for family, colour, generator in (("u", U_COLOUR, j0), ("v", V_COLOUR, i0)):
        xy = _polyline_xy(result, family, fibre_lines(result, family, tow_every))
        ax.plot(xy[:, 0], xy[:, 1], color=colour, lw=0.7, label=f"{family} fibres")
        line = _polyline_xy(result, family, [generator])
        ax.plot(line[:, 0], line[:, 1], color=colour, lw=2.2, label=f"{family} generator")
    folds = fold_triangles(result)
    if len(folds):
        # A fold at a wall's corner is a vertical triangle, a line from above: mark it too.
        for tri in folds:
            ax.fill(1e3 * tri[:, 0], 1e3 * tri[:, 1], color=FOLD_COLOUR, alpha=0.8)
        centre = 1e3 * folds.mean(axis=1)
        ax.plot(
            centre[:, 0],
            centre[:, 1],
            "X",
            color=FOLD_COLOUR,
            ms=10,
            mec="k",
            mew=0.6,
            ls="none",
            label="fold (net turns over)",
        )
    start = np.asarray(result.nodes, dtype=float)[i0, j0]
    if result.status[i0, j0] == NodeStatus.PLACED:
        ax.plot(1e3 * start[0], 1e3 * start[1], "o", color="k", ms=5, label="start node")
    ax.set_aspect("equal", adjustable="datalim")
    # Round ticks inside the view only: matplotlib makes a tick object (lines and texts) for
    # every value its locator returns, the ones past the limits too.
    ax.xaxis.set_major_locator(_in_view_locator(8))
    ax.yaxis.set_major_locator(_in_view_locator(8))
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    # y given: matplotlib then skips measuring every tick label to place the title above them
    # (nothing is drawn above this axes); that was a tenth of the figure's drawing time.
    ax.set_title("Fibre pattern, top view (bold: generators)", y=1.0)
    ax.legend(loc="upper right", fontsize="small")


#: Most quads the 3D shear view draws. A finer net is drawn one quad per k × k block of cells
#: (k the smallest that fits, where the whole block is drawn): matplotlib makes one Path per
#: polygon, which was half of a default case's figure time, and at the default 1600 × 800 px the
#: 3D panel is ~700 px across, so a standard 145² net's cells are 3–5 px there, about their
#: outlines' width. A modelling-free drawing choice; measured in benchmarks/README.md (k).
SHEAR_VIEW_MAX_QUADS = 2500


@dataclass(frozen=True)
class ShearViewQuads:
    """What the 3D shear view draws: quads (n, 4, 3) [mm], their signed shear (n,) [deg] and
    whether each is past locking (n,) (None without an energy field); ``block`` cells a side."""

    quads_mm: np.ndarray
    shear_deg: np.ndarray
    locked: np.ndarray | None
    block: int
    #: Whether each quad is past stitch failure (n,) (None without an energy field).
    failed: np.ndarray | None = None


def shear_view_quads(
    result: DrapeResult,
    drawn: np.ndarray,
    past_locking: np.ndarray | None,
    max_quads: int = SHEAR_VIEW_MAX_QUADS,
    past_failure: np.ndarray | None = None,
) -> ShearViewQuads:
    """The quads of the 3D shear view for the cells ``drawn`` (ni-1, nj-1).

    With more drawn cells than ``max_quads``, every k × k block of cells whose cells are all
    drawn becomes one quad through the block's four corner nodes, coloured by the signed shear
    of its cell of largest |γ| (so the extremes the colour bar spans stay visible), past
    locking when any of its cells is, past stitch failure likewise; cells of blocks only partly drawn (along the part's edge,
    next to unplaced nodes) are drawn one by one, so the drawn area keeps its outline.
    """
    nodes_mm = 1e3 * np.asarray(result.nodes, dtype=float)
    shear = np.degrees(np.asarray(result.shear, dtype=float))
    drawn = np.asarray(drawn, dtype=bool)
    k = max(1, math.ceil(math.sqrt(np.count_nonzero(drawn) / max(max_quads, 1))))
    whole_cells = np.zeros_like(drawn)
    block_quads: list[np.ndarray] = []
    block_shear = np.empty(0)
    block_locked = np.empty(0, dtype=bool)
    block_failed = np.empty(0, dtype=bool)
    if k > 1:
        ci_n, cj_n = drawn.shape
        bi_n, bj_n = ci_n // k, cj_n // k  # whole blocks only; the ragged rim goes cell by cell

        def blocks(a: np.ndarray) -> np.ndarray:
            trimmed = a[: bi_n * k, : bj_n * k]
            return (
                trimmed.reshape(bi_n, k, bj_n, k).transpose(0, 2, 1, 3).reshape(bi_n, bj_n, k * k)
            )

        whole = blocks(drawn).all(axis=2)
        whole_cells[: bi_n * k, : bj_n * k] = np.repeat(np.repeat(whole, k, axis=0), k, axis=1)
        bi, bj = np.nonzero(whole)
        in_block = blocks(np.where(drawn, shear, 0.0))[bi, bj]
        block_shear = in_block[np.arange(len(bi)), np.argmax(np.abs(in_block), axis=1)]
        if past_locking is not None:
            locked_blocks = blocks(np.asarray(past_locking, dtype=bool))[bi, bj]
            block_locked = np.asarray(locked_blocks.any(axis=1), dtype=bool)
        if past_failure is not None:
            failed_blocks = blocks(np.asarray(past_failure, dtype=bool))[bi, bj]
            block_failed = np.asarray(failed_blocks.any(axis=1), dtype=bool)
        i0, j0 = k * bi, k * bj
        block_quads = [nodes_mm[i0, j0], nodes_mm[i0 + k, j0], nodes_mm[i0 + k, j0 + k]]
        block_quads.append(nodes_mm[i0, j0 + k])
    ci, cj = np.nonzero(drawn & ~whole_cells)
    cell_quads = np.stack(
        [nodes_mm[ci, cj], nodes_mm[ci + 1, cj], nodes_mm[ci + 1, cj + 1], nodes_mm[ci, cj + 1]],
        axis=1,
    )
    quads = (
        np.concatenate([np.stack(block_quads, axis=1), cell_quads]) if block_quads else cell_quads
    )
    locked = None
    if past_locking is not None:
        locked = np.concatenate([block_locked, np.asarray(past_locking, dtype=bool)[ci, cj]])
    failed = None
    if past_failure is not None:
        failed = np.concatenate([block_failed, np.asarray(past_failure, dtype=bool)[ci, cj]])
    return ShearViewQuads(
        quads.reshape(-1, 4, 3), np.concatenate([block_shear, shear[ci, cj]]), locked, k, failed
    )


#: Where the 3D shear view is seen from [deg]: elevation above the xy-plane and azimuth about +z
#: from +x (mplot3d's default view, the one this panel had when it was drawn by mplot3d). A
#: drawing choice, not a modelling one.
VIEW_ELEVATION_DEG = 30.0
VIEW_AZIMUTH_DEG = -60.0

#: Light grey of the back panes and of their grid lines (RGBA), as mplot3d draws them.
PANE_COLOUR = (0.95, 0.95, 0.95, 1.0)
GRID_COLOUR = (0.8, 0.8, 0.8, 1.0)


def view_axes(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """The orthographic view's unit vectors (3, 3) in model axes (x, y, z): rows are the
    screen's right, the screen's up and the direction towards the viewer (right-handed)."""
    el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
    towards = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    right = np.array([-math.sin(az), math.cos(az), 0.0])
    return np.stack([right, np.cross(towards, right), towards])


def painter_order(polygons: np.ndarray, towards: np.ndarray) -> np.ndarray:
    """Indices that draw ``polygons`` (n, m, 3) farthest first, by the depth of each polygon's
    vertex mean along ``towards`` (3,), the direction to the viewer (mplot3d's "average" sort).
    Drawn in this order, nearer cells paint over the ones they hide, on a convex tool or not."""
    return np.argsort(polygons.mean(axis=1) @ np.asarray(towards, dtype=float), kind="stable")


@functools.cache
def _in_view_locator_type() -> type:
    from matplotlib.ticker import MaxNLocator

    class InViewLocator(MaxNLocator):
        """Round tick values [mm] (1, 2, 2.5, 5 × 10^k apart) within the axis's view."""

        def __call__(self) -> Any:
            lo, hi = sorted(self.axis.get_view_interval())  # type: ignore[union-attr]
            ticks = super().__call__()
            return ticks[(ticks >= lo) & (ticks <= hi)]

    return InViewLocator


def _in_view_locator(bins: int) -> Any:
    return _in_view_locator_type()(bins, steps=[1, 2, 2.5, 5, 10])


def _nice_ticks(lo: float, hi: float, bins: int) -> np.ndarray:
    """At most ``bins`` + 1 round values [mm] within [lo, hi]."""
    from matplotlib.ticker import MaxNLocator

    ticks = np.asarray(MaxNLocator(bins, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi))
    return ticks[(ticks >= lo - 1e-9 * (hi - lo)) & (ticks <= hi + 1e-9 * (hi - lo))]


def _tick_text(value: float) -> str:
    text = f"{value:.6g}"
    return "0" if text == "-0" else text.replace("-", "\N{MINUS SIGN}")


class _Panel:
    """Artists drawn on the figure in their own coordinates [mm on the screen], one scale both
    ways, centred in ``rect`` (left, bottom, width, height) [figure fraction]: what a plain
    axes with its axis off gives, without making an axes (its axis, tick prototypes, spines
    and patch: a twentieth of the figure's time). ``fit`` sets the scale once the drawing's
    extent is known; every artist added before follows it."""

    def __init__(self, fig: Figure, rect: tuple[float, float, float, float]) -> None:
        from matplotlib.transforms import Affine2D

        self.fig = fig
        self.rect = rect
        self.affine = Affine2D()
        self.transform = self.affine + fig.transFigure

    def add(self, artist: Any) -> Any:
        artist.set_transform(self.transform)
        self.fig.add_artist(artist)
        return artist

    def text(self, x: float, y: float, text: str, **style: Any) -> Any:
        from matplotlib.text import Text

        return self.add(Text(x, y, text, **style))

    def annotate(
        self, text: str, xy: tuple[float, float], offset_pt: tuple[float, float], **style: Any
    ) -> Any:
        """``text`` ``offset_pt`` [points] away from ``xy`` (panel coordinates)."""
        from matplotlib.text import Annotation

        note = Annotation(
            text, xy, xycoords=self.transform, xytext=offset_pt, textcoords="offset points", **style
        )
        self.fig.add_artist(note)
        return note

    def title(self, text: str, top: float, gid: str) -> Any:
        """``text`` centred over the panel, 6 points above ``top`` (the drawing's top [figure
        fraction], as ``fit`` returns it), at an axes title's size."""
        from matplotlib.text import Annotation

        left, _, width, _ = self.rect
        note = Annotation(
            text,
            (left + 0.5 * width, top),
            xycoords="figure fraction",
            xytext=(0, 6),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize="large",
            gid=gid,
        )
        self.fig.add_artist(note)
        return note

    def fit(self, x0: float, x1: float, y0: float, y1: float) -> float:
        """Scale [x0, x1] × [y0, y1] to fill the panel's rectangle at one scale, centred;
        returns the top of the drawing [figure fraction]."""
        width_in, height_in = self.fig.get_size_inches()
        left, bottom, width, height = self.rect
        scale = min(width * width_in / (x1 - x0), height * height_in / (y1 - y0))  # in per unit
        sx, sy = scale / width_in, scale / height_in
        cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        self.affine.clear().translate(-cx, -cy).scale(sx, sy)
        self.affine.translate(left + 0.5 * width, bottom + 0.5 * height)
        return bottom + 0.5 * height + sy * (y1 - cy)


def _box_frame(ax: _Panel, lo: np.ndarray, hi: np.ndarray, view: np.ndarray) -> np.ndarray:
    """The 3D axes drawn in 2D: the three back panes of the box [lo, hi] [mm] with grid lines at
    the ticks, and each axis's ticks and label [mm] along a front edge of the box. Returns
    screen points (k, 2) that the frame and its labels reach, for the panel's limits."""
    from matplotlib.collections import LineCollection, PolyCollection

    towards = view[2]
    span = hi - lo
    # About a tick per eighth of the drawing along each axis's edge on the screen (2 to 6 gaps).
    on_screen = span * np.hypot(view[0], view[1])
    bins = np.clip(np.round(8 * on_screen / on_screen.max()), 2, 6).astype(int)
    ticks = [_nice_ticks(lo[a], hi[a], int(bins[a])) for a in range(3)]
    for a in range(3):
        if on_screen[a] < 0.1 * on_screen.max() and len(ticks[a]) > 1:
            # an edge seen nearly end-on (a flat net's z): one tick, its labels would overlap
            middle = 0.5 * (lo[a] + hi[a])
            ticks[a] = ticks[a][[int(np.argmin(np.abs(ticks[a] - middle)))]]
    # The pane of axis a lies on the side of the box away from the viewer.
    back = np.where(towards > 0, lo, hi)
    front = np.where(towards > 0, hi, lo)
    panes, grid = [], []
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        pane = np.empty((4, 3))
        pane[:, a] = back[a]
        pane[:, b] = [lo[b], hi[b], hi[b], lo[b]]
        pane[:, c] = [lo[c], lo[c], hi[c], hi[c]]
        panes.append(pane)
        for along, other in ((b, c), (c, b)):
            for t in ticks[along]:
                line = np.empty((2, 3))
                line[:, a] = back[a]
                line[:, along] = t
                line[:, other] = [lo[other], hi[other]]
                grid.append(line)
    screen = view[:2].T
    ax.add(
        PolyCollection(
            [p @ screen for p in panes], facecolors=PANE_COLOUR, edgecolors="0.6", linewidths=0.6
        )
    )
    ax.add(LineCollection([g @ screen for g in grid], colors=GRID_COLOUR, lw=0.6))
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    reach = [corners @ screen]
    size = float(np.ptp(reach[0], axis=0).max())
    centre = 0.5 * (lo + hi) @ screen
    marks = []
    for a, name in enumerate("xyz"):
        edge = np.empty(3)
        if a == 2:
            # z up the vertical edge farthest right on the screen
            xy = [(x, y) for x in (lo[0], hi[0]) for y in (lo[1], hi[1])]
            edge[:2] = max(xy, key=lambda p: p[0] * view[0, 0] + p[1] * view[0, 1])
        else:
            # x and y along the floor's front edges (the floor: the z pane)
            edge[1 - a] = front[1 - a]
            edge[2] = back[2]
        points = np.repeat(edge[None], len(ticks[a]), axis=0)
        points[:, a] = ticks[a]
        middle = edge.copy()
        middle[a] = 0.5 * (lo[a] + hi[a])
        outward = middle @ screen - centre
        outward /= max(float(np.hypot(*outward)), 1e-12)
        ha = "left" if outward[0] > 0.35 else "right" if outward[0] < -0.35 else "center"
        va = "bottom" if outward[1] > 0.35 else "top" if outward[1] < -0.35 else "center"
        tick_in = points @ screen
        tick_out = tick_in + 0.015 * size * outward
        marks.append(np.stack([tick_in, tick_out], axis=1))
        for (x, y), t in zip(tick_out + 0.01 * size * outward, ticks[a], strict=True):
            ax.text(x, y, _tick_text(float(t)), ha=ha, va=va, fontsize="small", gid=f"{name} tick")
        direction = view[:2, a]
        angle = math.degrees(math.atan2(direction[1], direction[0]))
        angle = (angle + 90.0) % 180.0 - 90.0  # upright text
        label = middle @ screen + 0.12 * size * outward
        ax.text(label[0], label[1], f"{name} [mm]", ha="center", va="center", rotation=angle)
        reach.append(np.array([label + 0.04 * size * outward]))
        reach.append(tick_out + 0.07 * size * outward)
    ax.add(LineCollection(list(np.concatenate(marks)), colors="0.2", lw=0.8))
    return np.concatenate(reach)


def _colour_scale(
    ax: _Panel, norm: Any, cmap: Any, box: tuple[float, float, float, float], label: str
) -> None:
    """A vertical colour bar of ``cmap`` over ``norm``'s range drawn in the panel at ``box``
    (left, bottom, width, height) in its coordinates, with round ticks and ``label``: what
    ``Figure.colorbar`` draws, without the extra Axes (half the shear panel's drawing time)."""
    from matplotlib.collections import LineCollection
    from matplotlib.image import BboxImage
    from matplotlib.patches import Rectangle
    from matplotlib.transforms import Bbox, TransformedBbox

    left, bottom, width, height = box
    image = BboxImage(
        TransformedBbox(Bbox.from_bounds(left, bottom, width, height), ax.transform),
        cmap=cmap,
        norm=norm,
        origin="lower",
        interpolation="nearest",
        gid="colour scale",
    )
    image.set_data(np.linspace(norm.vmin, norm.vmax, 256)[:, None])
    ax.fig.add_artist(image)
    ax.add(Rectangle((left, bottom), width, height, fill=False, lw=0.8, ec="k"))
    ticks = _nice_ticks(norm.vmin, norm.vmax, 6)
    y = bottom + height * (ticks - norm.vmin) / (norm.vmax - norm.vmin)
    right = left + width
    ax.add(LineCollection([[(right, v), (right + 0.25 * width, v)] for v in y], colors="k", lw=0.8))
    for value, v in zip(ticks, y, strict=True):
        ax.annotate(_tick_text(float(value)), (right, v), (6, 0), ha="left", va="center")
    ax.annotate(
        label, (right, bottom + 0.5 * height), (40, 0), ha="center", va="center", rotation=90
    )


def _shear_view(
    fig: Figure,
    rect: tuple[float, float, float, float],
    result: DrapeResult,
    energy: EnergyField | None,
    scale_deg: float | None = SHEAR_SCALE_DEG,
) -> None:
    """The net in 3D, coloured by signed shear, in ``rect`` [figure fraction]: an orthographic
    view projected here and drawn as one 2D collection of polygons in depth order (see
    ``painter_order``), with the box's panes, ticks in mm and a colour scale (``_Panel``)
    spanning ±``scale_deg`` [deg] (None: the largest |γ| drawn)."""
    from matplotlib import colormaps
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import CenteredNorm, to_rgba

    valid = np.asarray(result.cell_status == CellStatus.VALID)
    if result.part_share is not None:
        # Only the part: the net draped past its edge would hide it.
        valid &= np.asarray(result.part_weight) > 0
    locked_cells = None if energy is None else np.asarray(energy.past_locking, dtype=bool)
    failed_cells = None if energy is None else np.asarray(energy.past_failure, dtype=bool)
    view = shear_view_quads(result, valid, locked_cells, past_failure=failed_cells)
    quads, shear_deg = view.quads_mm, view.shear_deg
    # Symmetric colour range centred on zero so positive and negative shear read alike.
    if scale_deg is None:
        half_range = max(float(np.max(np.abs(shear_deg))) if shear_deg.size else 0.0, 1.0)
    else:
        half_range = float(scale_deg)
    cell_shear = np.abs(np.degrees(np.asarray(result.shear, dtype=float)))
    beyond = int(np.count_nonzero(valid & (cell_shear > half_range)))
    norm = CenteredNorm(vcenter=0.0, halfrange=half_range)
    cmap = colormaps["RdBu_r"]
    axes = view_axes(VIEW_ELEVATION_DEG, VIEW_AZIMUTH_DEG)
    screen = axes[:2].T
    ax = _Panel(fig, rect)
    folds = 1e3 * fold_triangles(result)
    if len(quads):
        pts = np.concatenate([quads.reshape(-1, 3), folds.reshape(-1, 3)])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
    else:  # nothing to draw: the frame of a 1 mm box, the colour scale
        lo, hi = np.zeros(3), np.ones(3)
    # A flat net has no z extent: give every axis a little room so the box is not flat.
    pad = 0.01 * float(np.max(hi - lo)) + 1e-9
    lo, hi = lo - pad, hi + pad
    hi = np.maximum(hi, lo + 0.02 * float(np.max(hi - lo)))
    reach = _box_frame(ax, lo, hi, axes)
    if len(quads):
        # One collection: the cells, then the folds' triangles (as quads with a repeated corner).
        polygons = np.concatenate([quads, folds[:, [0, 1, 2, 2]]]) if len(folds) else quads
        faces = np.concatenate(
            [cmap(norm(shear_deg)), np.tile(to_rgba(FOLD_COLOUR), (len(folds), 1))]
        )
        edge = np.tile([0.3, 0.3, 0.3, 0.6], (len(polygons), 1))
        widths = np.full(len(polygons), 0.15)
        if view.locked is not None:
            # Cells past locking get a black outline: that is where wrinkles are expected.
            edge[: len(quads)][view.locked] = (0.0, 0.0, 0.0, 1.0)
            widths[: len(quads)][view.locked] = 0.8
        if view.failed is not None:
            # Past stitch failure (worse than past locking, which it usually is too): its own
            # colour, drawn over the black.
            edge[: len(quads)][view.failed] = to_rgba(FAILURE_COLOUR)
            widths[: len(quads)][view.failed] = 1.2
        order = painter_order(polygons, axes[2])
        cells = PolyCollection(
            polygons[order] @ screen,
            closed=True,
            facecolors=faces[order],
            edgecolors=edge[order],
            linewidths=widths[order],
            gid="shear cells",
        )
        ax.add(cells)
        if len(folds):
            from matplotlib.lines import Line2D

            centre = folds.mean(axis=1) @ screen
            ax.add(
                Line2D(
                    centre[:, 0],
                    centre[:, 1],
                    marker="X",
                    color=FOLD_COLOUR,
                    ms=9,
                    mec="k",
                    mew=0.6,
                    ls="none",
                    gid="fold marks",
                )
            )
    (x0, y0), (x1, y1) = reach.min(axis=0), reach.max(axis=0)
    # The colour scale right of the drawing: 0.7 of its height (as a colour bar shrunk to 0.7),
    # but never shorter than 0.45 of its width (a flat part's panel grows to take it).
    width, height = x1 - x0, y1 - y0
    bar = max(0.7 * height, 0.45 * width)
    middle = 0.5 * (y0 + y1)
    y0, y1 = min(y0, middle - 0.6 * bar), max(y1, middle + 0.6 * bar)
    _colour_scale(
        ax,
        norm,
        cmap,
        (x1 + 0.04 * width, middle - 0.5 * bar, 0.035 * width, bar),
        "signed shear angle γ [deg]",
    )
    top = ax.fit(x0, x1 + 0.3 * width, y0, y1)
    title = "Shear angle" + (" (black outline: past locking)" if energy is not None else "")
    failed = 0 if failed_cells is None else int(np.count_nonzero(failed_cells & valid))
    if failed:
        title += f"\n{failed} cell(s) past stitch failure (magenta outline)"
    if beyond:
        title += f"\n{beyond} cell(s) beyond ±{half_range:g}° (drawn in the end colours)"
    if view.block > 1:
        title += f"\none quad per {view.block} × {view.block} cells (their largest |γ|)"
    ax.title(title, top, gid="shear title")


def percent(fraction: float) -> str:
    """A share in per cent as a title says it: 100 % only when whole (99.96 % is not)."""
    if fraction >= 1.0:
        return "100 %"
    return f"{min(100.0 * fraction, 99.9):.1f} %"


def coverage_words(result: DrapeResult, covered_fraction: float | None) -> str:
    """What the drape covers, for a title: the case's coverage when known, and the nodes on
    the part (placed, a corner of a cell with area in it: the ones the figure draws)."""
    on_part = int(np.count_nonzero(_part_nodes(result)))
    nodes = f"{on_part} nodes on the part"
    if covered_fraction is None:
        return nodes
    # the case's coverage is of the ply's fabric over the tool (preform.drape.judging.verdict)
    return f"covers {percent(float(covered_fraction))} of the ply over the tool, {nodes}"


def fibre_pattern_figure(
    result: DrapeResult,
    energy: EnergyField | None,
    path: str | os.PathLike[str] | None,
    *,
    title: str | None = None,
    tow_every: int = 1,
    size_px: tuple[int, int] = (1600, 800),
    part: Part | None = None,
    covered_fraction: float | None = None,
    shear_scale_deg: float | None = SHEAR_SCALE_DEG,
) -> Figure:
    """Draw a draped net and save it to ``path``: left, the fibres from above; right, the net
    in 3D with cells coloured by signed shear.

    The top view draws every ``tow_every``-th line of nodes of both fibre families (the lines
    through the start node, the generators, always and in bold), broken wherever a node is not
    placed. The 3D view shows the VALID cells coloured on a diverging map centred at 0° with a
    colour scale of ±``shear_scale_deg`` [deg] (the same in every figure, ``SHEAR_SCALE_DEG``,
    so figures of two fabrics compare; None: this drape's largest |γ|); with ``energy``, cells
    past locking are outlined black, cells past stitch failure magenta, and the total energy
    [J] goes into the title. The title says what the drape covers: ``covered_fraction`` (the
    case's coverage, ``preform.drape.judging.verdict``) when given, and the nodes drawn on the part
    (not the nodes of the whole ply, most of which hang past a part's edge). It is an orthographic view from ``VIEW_ELEVATION_DEG``,
    ``VIEW_AZIMUTH_DEG`` projected here and drawn on the figure itself (no axes), the cells as one
    collection farthest first (``painter_order``), the box's back panes, ticks [mm] and the
    colour scale drawn with it: mplot3d's look at a fraction of its cost (benchmarks/README.md,
    section (m)). A net of more than ``SHEAR_VIEW_MAX_QUADS`` cells is drawn one quad per k × k
    block there, and the panel's title says k (``shear_view_quads``). Where the net folded (a
    sharp vertex's shadow), the cell that would turn over is filled orange in both views and
    the count goes into the title. Axes in mm. ``size_px`` is the saved (width, height)
    [pixels]. A net clipped to a part is drawn over the part only (cells with area in it, and
    their nodes); with ``part`` its edge is drawn dashed in the top view.
    Returns the figure (already saved).
    """
    fig = new_figure(size_px)
    edge = part_edge_segments(result, part) if part is not None else None
    _top_view(fig.add_subplot(1, 2, 1), result, tow_every, edge)
    right = fig.add_gridspec(1, 2)[0, 1].get_position(fig)  # where add_subplot(1, 2, 2) goes
    _shear_view(fig, tuple(right.bounds), result, energy, shear_scale_deg)
    summary = f"generator angle {np.degrees(result.generator_angle):.1f}°, " + coverage_words(
        result, covered_fraction
    )
    folded = int(np.count_nonzero(np.asarray(result.status) == NodeStatus.FOLDED))
    if folded:
        summary += f", {folded} fold(s) (orange; the fabric behind them is not placed)"
    if energy is not None:
        summary += f", total shear energy {energy.total_energy:.4g} J"
    fig.suptitle(f"{title}\n{summary}" if title else summary)
    if path is not None:  # None: the figure only (the Python API, a notebook)
        save_figure(fig, path)
    return fig
