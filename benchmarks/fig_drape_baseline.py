"""The fibre-pattern figure (Fig. 11) as it was drawn before issue 15g: the baseline of the
speed ratios in ``bench_figures.py``, measured in the same process.

A frozen copy of ``preform.export.fig_drape`` at commit 529d321 (the 3D view through
mplot3d's ``Axes3D`` and ``Poly3DCollection``) and of ``figures.save_figure`` (matplotlib's own
PNG writer, RGBA at zlib level 6). Reachable only from the benchmarks: never imported by preform
or its tests. The whole module is copied (geometry helpers and ``new_figure`` too) so that later
changes to them do not move the baseline; only the atomic file replacement is imported.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import numpy as np

from preform.base.atomic import atomic_path
from preform.drape.engine.part import Part
from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField, NodeStatus

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.axes3d import Axes3D


def new_figure(size_px: tuple[int, int], dpi: int = 100) -> Figure:
    """``figures.new_figure`` before issue 15g: a bare Figure with an Agg canvas attached."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    width, height = size_px
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, path: str | os.PathLike[str]) -> None:
    """``figures.save_figure`` before issue 15g: matplotlib's savefig, whatever the format."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=fig.dpi, format=tmp.suffix.lstrip(".") or "png")


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
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title("Fibre pattern, top view (bold: generators)")
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


def shear_view_quads(
    result: DrapeResult,
    drawn: np.ndarray,
    past_locking: np.ndarray | None,
    max_quads: int = SHEAR_VIEW_MAX_QUADS,
) -> ShearViewQuads:
    """The quads of the 3D shear view for the cells ``drawn`` (ni-1, nj-1).

    With more drawn cells than ``max_quads``, every k × k block of cells whose cells are all
    drawn becomes one quad through the block's four corner nodes, coloured by the signed shear
    of its cell of largest |γ| (so the extremes the colour bar spans stay visible) and past
    locking when any of its cells is; cells of blocks only partly drawn (along the part's edge,
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
    return ShearViewQuads(
        quads.reshape(-1, 4, 3), np.concatenate([block_shear, shear[ci, cj]]), locked, k
    )


def _shear_view(fig: Figure, ax: Axes3D, result: DrapeResult, energy: EnergyField | None) -> None:
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import CenteredNorm
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    valid = np.asarray(result.cell_status == CellStatus.VALID)
    if result.part_share is not None:
        # Only the part: the net draped past its edge would hide it.
        valid &= np.asarray(result.part_weight) > 0
    locked_cells = None if energy is None else np.asarray(energy.past_locking, dtype=bool)
    view = shear_view_quads(result, valid, locked_cells)
    quads, shear_deg = view.quads_mm, view.shear_deg
    # Symmetric colour range centred on zero so positive and negative shear read alike.
    half_range = max(float(np.max(np.abs(shear_deg))) if shear_deg.size else 0.0, 1.0)
    norm = CenteredNorm(vcenter=0.0, halfrange=half_range)
    cmap = colormaps["RdBu_r"]
    if len(quads):
        edge = np.tile([0.3, 0.3, 0.3, 0.6], (len(quads), 1))
        widths = np.full(len(quads), 0.15)
        if view.locked is not None:
            # Cells past locking get a black outline: that is where wrinkles are expected.
            edge[view.locked] = (0.0, 0.0, 0.0, 1.0)
            widths[view.locked] = 0.8
        ax.add_collection3d(
            Poly3DCollection(
                quads, facecolors=cmap(norm(shear_deg)), edgecolors=edge, linewidths=widths
            )
        )
        folds = fold_triangles(result)
        if len(folds):
            ax.add_collection3d(Poly3DCollection(1e3 * folds, facecolors=FOLD_COLOUR))
            centre = 1e3 * folds.mean(axis=1)
            ax.scatter(*centre.T, marker="X", s=80, color=FOLD_COLOUR, edgecolors="k")
        pts = quads.reshape(-1, 3)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        # A flat net has no z extent: give every axis a little room so the limits are not singular.
        pad = 0.01 * float(np.max(hi - lo)) + 1e-9
        lo, hi = lo - pad, hi + pad
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        span = hi - lo
        ax.set_box_aspect(tuple(np.maximum(span, 0.02 * span.max())), zoom=0.9)
    from matplotlib.ticker import MaxNLocator

    ax.zaxis.set_major_locator(MaxNLocator(4))
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    title = "Shear angle" + (" (black outline: past locking)" if energy is not None else "")
    if view.block > 1:
        title += f"\none quad per {view.block} × {view.block} cells (their largest |γ|)"
    ax.set_title(title)
    colour_bar = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.7, pad=0.12)
    colour_bar.set_label("signed shear angle γ [deg]")


def fibre_pattern_figure(
    result: DrapeResult,
    energy: EnergyField | None,
    path: str | os.PathLike[str] | None,
    *,
    title: str | None = None,
    tow_every: int = 1,
    size_px: tuple[int, int] = (1600, 800),
    part: Part | None = None,
) -> Figure:
    """Draw a draped net and save it to ``path``: left, the fibres from above; right, the net
    in 3D with cells coloured by signed shear.

    The top view draws every ``tow_every``-th line of nodes of both fibre families (the lines
    through the start node, the generators, always and in bold), broken wherever a node is not
    placed. The 3D view shows the VALID cells coloured on a diverging map centred at 0° with a
    colour bar in degrees; with ``energy``, cells past locking are outlined and the total energy
    [J] goes into the title. A net of more than ``SHEAR_VIEW_MAX_QUADS`` cells is drawn one quad
    per k × k block there, and the panel's title says k (``shear_view_quads``). Where the net folded (a sharp vertex's shadow), the cell that would
    turn over is filled orange in both views and the count goes into the title. Axes in mm. ``size_px`` is the saved (width, height) [pixels].
    A net clipped to a part is drawn over the part only (cells with area in it, and their
    nodes); with ``part`` its edge is drawn dashed in the top view.
    Returns the figure (already saved).
    """
    fig = new_figure(size_px)
    edge = part_edge_segments(result, part) if part is not None else None
    _top_view(fig.add_subplot(1, 2, 1), result, tow_every, edge)
    _shear_view(fig, cast("Axes3D", fig.add_subplot(1, 2, 2, projection="3d")), result, energy)
    summary = (
        f"generator angle {np.degrees(result.generator_angle):.1f}°, "
        f"{result.nodes_placed}/{result.nodes_total} nodes placed"
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
