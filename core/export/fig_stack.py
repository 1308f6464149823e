"""The stack's figure: its total thickness and the number of plies present, seen from above."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from preform.export.figures import new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from preform.stack.maps import StackMaps


def stack_figure(
    maps: StackMaps, path: str | os.PathLike[str] | None = None, title: str = ""
) -> Figure:
    """Two top views of the stack's stations [mm]: total thickness [mm] and plies present,
    wrinkling plies marked; saved to ``path`` when given."""
    fig = new_figure((1200, 560))
    x, y = maps.points_mm[:, 0], maps.points_mm[:, 1]
    # marker area about one station's own area on the page
    span = max(float(np.ptp(x)) if len(x) else 1.0, float(np.ptp(y)) if len(y) else 1.0, 1e-9)
    # a square marker one station wide: ~420 px of axes span the plot [pt² = (px · 72/dpi)²]
    side_pt = np.sqrt(np.median(maps.area_mm2)) * 420.0 / span * 72.0 / fig.dpi
    size = float(np.clip(1.3 * side_pt**2, 0.5, 60.0))
    left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    total = maps.total_thickness_mm
    shown = left.scatter(x, y, c=total, s=size, marker="s", linewidths=0, cmap="viridis")
    fig.colorbar(shown, ax=left, label="total thickness [mm]")
    left.set_title("stack thickness")
    n = len(maps.ply_names)
    count = maps.plies_present
    bounds = np.arange(-0.5, n + 1.0, 1.0)
    from matplotlib.colors import BoundaryNorm

    shown = right.scatter(
        x,
        y,
        c=count,
        s=size,
        marker="s",
        linewidths=0,
        cmap="cividis",
        norm=BoundaryNorm(bounds, 256),
    )
    fig.colorbar(shown, ax=right, label="plies present", ticks=np.arange(0, n + 1))
    wrinkling = maps.plies_wrinkling > 0
    if wrinkling.any():
        right.scatter(x[wrinkling], y[wrinkling], s=size, marker="x", c="#c0392b", linewidths=0.6,
                      label="a ply wrinkles")
        right.legend(loc="upper right", fontsize=8)
    right.set_title(f"plies present (of {n})")
    for axes in (left, right):
        axes.set_aspect("equal")
        axes.set_xlabel("x [mm]")
        axes.set_ylabel("y [mm]")
    if title:
        fig.suptitle(title)
    if path is not None:
        save_figure(fig, path)
    return fig
