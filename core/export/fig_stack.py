"""The stack's figure: its total thickness seen from above, where plies wrinkle marked.

Drawn on the figure itself, as fig_drape's shear view is (``fig_drape._Panel``: no axes, whose
ticks, spines and layout were most of the figure's time), with the frame, round ticks [mm] and
the colour scale drawn here. Given the stations' net (the reference ply's nodes and the cells
the stations are), the stations are drawn as those cells, one quad mesh (one call into Agg);
without it, as one square marker a station (benchmarks/README.md, section (q)).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.figures import new_figure, save_figure
from preform.export.fig_drape import _colour_scale, _nice_ticks, _Panel, _tick_text

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
    from matplotlib import colormaps
    from matplotlib.collections import PathCollection
    from matplotlib.colors import Normalize
    from matplotlib.lines import Line2D
    from matplotlib.markers import MarkerStyle
    from matplotlib.transforms import IdentityTransform

    fig = new_figure((760, 600))
    width_in, height_in = fig.get_size_inches()
    x, y = maps.points_mm[:, 0], maps.points_mm[:, 1]
    total = maps.total_thickness_mm
    finite = np.isfinite(total)
    low = float(total[finite].min()) if finite.any() else 0.0
    high = float(total[finite].max()) if finite.any() else 1.0
    if not high > low:  # one thickness everywhere: a scale around it
        low, high = low - max(abs(low), 1.0) * 0.01, high + max(abs(high), 1.0) * 0.01
    norm, cmap = Normalize(low, high), colormaps["viridis"]
    panel = _Panel(fig, (0.1, 0.09, 0.66, 0.76))
    cells = _station_cells(net, total) if net is not None else None
    if cells is not None:
        mesh, (x0, x1, y0, y1) = cells
        mesh.set_cmap(cmap)
        mesh.set_norm(norm)
        panel.add(mesh)
    else:
        x0, x1 = (float(x.min()), float(x.max())) if len(x) else (0.0, 1.0)
        y0, y1 = (float(y.min()), float(y.max())) if len(y) else (0.0, 1.0)
    pad = 0.03 * max(x1 - x0, y1 - y0, 1e-9)
    x0, x1, y0, y1 = x0 - pad, x1 + pad, y0 - pad, y1 + pad
    top = panel.fit(x0, x1, y0, y1)
    # a station's side in points: the panel's scale [in/mm] × sqrt(its area) [mm] × 72 pt/in
    mm_in = min(0.66 * width_in / (x1 - x0), 0.76 * height_in / (y1 - y0))
    side_pt = float(np.sqrt(np.median(maps.area_mm2))) * mm_in * 72.0 if len(x) else 1.0
    size = float(np.clip(1.3 * side_pt**2, 0.5, 60.0))
    if cells is None and len(x):
        square = MarkerStyle("s")
        squares = PathCollection(
            [square.get_path().transformed(square.get_transform())],
            sizes=[size],
            offsets=np.column_stack([x, y]),
            offset_transform=panel.transform,
            linewidths=0,
            cmap=cmap,
            norm=norm,
        )
        squares.set_array(total)
        squares.set_transform(IdentityTransform())  # sizes in points, as scatter's
        fig.add_artist(squares)
    wrinkling = maps.plies_wrinkling > 0
    if wrinkling.any():
        panel.add(
            Line2D(
                x[wrinkling],
                y[wrinkling],
                marker="x",
                ms=float(np.sqrt(size)),
                mew=0.5,
                color="#c0392b",
                ls="none",
                gid="wrinkling",
            )
        )
    _frame(panel, (x0, x1, y0, y1))
    scale = _Panel(fig, (0.8, 0.1, 0.2, 0.8))
    scale.fit(0.0, 0.2 * width_in, 0.0, 0.8 * height_in)  # panel units: inches
    _colour_scale(
        scale, norm, cmap, (0.15, 0.5, 0.18, 0.8 * height_in - 1.0), "total thickness [mm]"
    )
    count = maps.plies_present
    n = len(maps.ply_names)
    least = int(count[count > 0].min()) if np.any(count > 0) else 0
    what = f"stack thickness ({least}–{int(count.max(initial=0))} of {n} plies)"
    text = f"{title}: {what}" if title else what
    if wrinkling.any():
        text += "\n× (red): a ply wrinkles (past jamming or stitch failure)"
    panel.title(text, top, gid="stack title")
    if path is not None:
        save_figure(fig, path)
    return fig


def _frame(panel: _Panel, limits: tuple[float, float, float, float]) -> None:
    """The plot's frame, round ticks [mm] along its left and bottom edges with their values,
    and the axes' names: what an axes draws, as a few artists."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Rectangle

    x0, x1, y0, y1 = limits
    panel.add(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, lw=0.8, ec="k"))
    xt, yt = _nice_ticks(x0, x1, 5), _nice_ticks(y0, y1, 5)
    tick = 0.012 * max(x1 - x0, y1 - y0)
    marks = [[(v, y0), (v, y0 - tick)] for v in xt] + [[(x0, v), (x0 - tick, v)] for v in yt]
    panel.add(LineCollection(marks, colors="k", lw=0.8))
    for v in xt:
        panel.annotate(_tick_text(float(v)), (float(v), y0), (0, -7), ha="center", va="top")
    for v in yt:
        panel.annotate(_tick_text(float(v)), (x0, float(v)), (-7, 0), ha="right", va="center")
    panel.annotate("x [mm]", (0.5 * (x0 + x1), y0), (0, -24), ha="center", va="top")
    panel.annotate("y [mm]", (x0, 0.5 * (y0 + y1)), (-40, 0), ha="right", va="center", rotation=90)


def _station_cells(
    net: tuple[np.ndarray, np.ndarray], total: np.ndarray
) -> tuple[Any, tuple[float, float, float, float]] | None:
    """The stations as their cells, coloured by ``total`` [mm]: one QuadMesh of the net's rows
    and columns that hold a station, and the cells' extent (x0, x1, y0, y1) [mm]; None when
    ``net`` does not match the stations."""
    from matplotlib.collections import QuadMesh

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
    # a node no station uses may be unplaced (NaN): put it on a station's node; the cells
    # around it are masked, so it draws nothing
    xy[~corners] = xy[corners][0]
    colour = np.full(cells.shape, np.nan)
    colour[cells] = total
    mesh = QuadMesh(xy, antialiased=False, linewidth=0, shading="flat")
    mesh.set_array(np.ma.masked_invalid(colour))
    lo, hi = xy[corners].min(axis=0), xy[corners].max(axis=0)
    return mesh, (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))
