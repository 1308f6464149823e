"""The stack's figure: its total thickness seen from above, where plies wrinkle marked.

Given the stations' net (the reference ply's nodes and the cells the stations are), the stations
are drawn as those cells, one quad mesh (one call into Agg); without it, as one square marker a
station, which costs Agg a path each (about 0.1 s for the bundled layup's 11 000 stations at
``standard``, more than a ply's drape: benchmarks/README.md, section (q)).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.export.fig_drape import _colour_scale, _in_view_locator, _Panel
from preform.export.figures import new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from preform.stack.maps import StackMaps


def stack_figure(
    maps: StackMaps,
    path: str | os.PathLike[str] | None = None,
    title: str = "",
    net: tuple[np.ndarray, np.ndarray] | None = None,
) -> Figure:
    """A top view of the stack's stations [mm] coloured by total thickness [mm], stations
    where a ply wrinkles marked; saved to ``path`` when given. One panel: the plies present
    per station are in ``stack.csv`` (a second panel would double the figure's time).

    ``net``: (nodes [mm] (ni, nj, 3), cells (ni − 1, nj − 1) bool) of the ply whose cells the
    stations are, its True cells in row-major order being ``maps``' points in order
    (``preform.stack.maps.stations``): the stations are drawn as those cells. Without it (or
    when it does not match the stations), as square markers one station wide."""
    fig = new_figure((760, 600))
    x, y = maps.points_mm[:, 0], maps.points_mm[:, 1]
    span = max(float(np.ptp(x)) if len(x) else 1.0, float(np.ptp(y)) if len(y) else 1.0, 1e-9)
    # a square marker one station wide: ~460 px of axes span the plot [pt² = (px · 72/dpi)²]
    side_pt = np.sqrt(np.median(maps.area_mm2)) * 460.0 / span * 72.0 / fig.dpi
    size = float(np.clip(1.3 * side_pt**2, 0.5, 60.0))
    # the axes where add_subplot would put it beside a colour bar; the bar itself is drawn on
    # the figure (fig_drape's colour scale): a colour bar's own axes was a third of the time
    axes = fig.add_axes((0.09, 0.1, 0.7, 0.8))
    total = maps.total_thickness_mm
    shown = _station_cells(axes, net, total) if net is not None else None
    if shown is None:
        shown = axes.scatter(x, y, c=total, s=size, marker="s", linewidths=0, cmap="viridis")
    low, high = (float(v) for v in shown.get_clim())
    if not high > low:  # one thickness everywhere: a bar around it
        low, high = low - max(abs(low), 1.0) * 0.01, high + max(abs(high), 1.0) * 0.01
        shown.set_clim(low, high)
    scale = _Panel(fig, (0.8, 0.1, 0.2, 0.8))
    width_in, height_in = fig.get_size_inches()
    scale.fit(0.0, 0.2 * width_in, 0.0, 0.8 * height_in)  # panel units: inches
    _colour_scale(
        scale,
        shown.norm,
        shown.get_cmap(),
        (0.15, 0.5, 0.18, 0.8 * height_in - 1.0),
        "total thickness [mm]",
    )
    wrinkling = maps.plies_wrinkling > 0
    if wrinkling.any():
        axes.scatter(
            x[wrinkling],
            y[wrinkling],
            s=size,
            marker="x",
            c="#c0392b",
            linewidths=0.5,
            label="a ply wrinkles (past jamming or stitch failure)",
        )
        axes.legend(loc="upper right", fontsize=8)
    count = maps.plies_present
    n = len(maps.ply_names)
    low = int(count[count > 0].min()) if np.any(count > 0) else 0
    what = f"stack thickness ({low}–{int(count.max(initial=0))} of {n} plies)"
    # y given: the title's place is not worked out from the tick labels' sizes
    axes.set_title(f"{title}: {what}" if title else what, y=1.0)
    # few ticks: laying out matplotlib's tick labels is most of a figure's time
    axes.xaxis.set_major_locator(_in_view_locator(5))
    axes.yaxis.set_major_locator(_in_view_locator(5))
    axes.set_aspect("equal")
    axes.set_xlabel("x [mm]")
    axes.set_ylabel("y [mm]")
    if path is not None:
        save_figure(fig, path)
    return fig


def _station_cells(axes: Any, net: tuple[np.ndarray, np.ndarray], total: np.ndarray) -> Any:
    """The stations as their cells, coloured by ``total`` [mm], in one QuadMesh (the net's
    rows and columns that hold a station only); None when ``net`` does not match them."""
    nodes_mm, cells = (np.asarray(a) for a in net)
    if (
        cells.ndim != 2
        or nodes_mm.shape[:2] != (cells.shape[0] + 1, cells.shape[1] + 1)
        or int(np.count_nonzero(cells)) != total.size
        or total.size == 0
    ):
        return None
    rows, cols = np.flatnonzero(cells.any(axis=1)), np.flatnonzero(cells.any(axis=0))
    r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    cells = cells[r0:r1, c0:c1]
    xy = nodes_mm[r0 : r1 + 1, c0 : c1 + 1, :2].astype(float)
    corners = np.zeros(xy.shape[:2], dtype=bool)  # the nodes of a station's cell
    for di in (0, 1):
        for dj in (0, 1):
            corners[di : di + cells.shape[0], dj : dj + cells.shape[1]] |= cells
    if not np.all(np.isfinite(xy[corners])):
        return None
    # a node no station uses may be unplaced (NaN), which pcolormesh refuses: put it on a
    # station's node; the cells around it are masked, so it draws nothing
    xy[~corners] = xy[corners][0]
    colour = np.full(cells.shape, np.nan)
    colour[cells] = total
    shown = axes.pcolormesh(
        xy[..., 0],
        xy[..., 1],
        np.ma.masked_invalid(colour),
        cmap="viridis",
        shading="flat",
        linewidth=0,
        antialiased=False,
    )
    lo, hi = xy[corners].min(axis=0), xy[corners].max(axis=0)
    pad = 0.02 * float(np.max(hi - lo)) + 1e-9
    axes.set_xlim(lo[0] - pad, hi[0] + pad)
    axes.set_ylim(lo[1] - pad, hi[1] + pad)
    return shown
