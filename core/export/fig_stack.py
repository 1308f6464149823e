"""The stack's figure: its total thickness seen from above, where plies wrinkle marked."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from preform.base.figures import new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from preform.stack.maps import StackMaps


def stack_figure(
    maps: StackMaps, path: str | os.PathLike[str] | None = None, title: str = ""
) -> Figure:
    """A top view of the stack's stations [mm] coloured by total thickness [mm], stations
    where a ply wrinkles marked; saved to ``path`` when given. One panel: the plies present
    per station are in ``stack.csv`` (a second panel would double the figure's time)."""
    from matplotlib.ticker import MaxNLocator

    fig = new_figure((760, 600))
    x, y = maps.points_mm[:, 0], maps.points_mm[:, 1]
    span = max(float(np.ptp(x)) if len(x) else 1.0, float(np.ptp(y)) if len(y) else 1.0, 1e-9)
    # a square marker one station wide: ~460 px of axes span the plot [pt² = (px · 72/dpi)²]
    side_pt = np.sqrt(np.median(maps.area_mm2)) * 460.0 / span * 72.0 / fig.dpi
    size = float(np.clip(1.3 * side_pt**2, 0.5, 60.0))
    axes = fig.add_subplot(1, 1, 1)
    total = maps.total_thickness_mm
    shown = axes.scatter(x, y, c=total, s=size, marker="s", linewidths=0, cmap="viridis")
    bar = fig.colorbar(shown, ax=axes, label="total thickness [mm]")
    bar.locator = MaxNLocator(6)
    bar.update_ticks()
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
    axes.set_title(f"{title}: {what}" if title else what)
    # few ticks: laying out matplotlib's tick labels is most of a figure's time
    axes.xaxis.set_major_locator(MaxNLocator(5))
    axes.yaxis.set_major_locator(MaxNLocator(5))
    axes.set_aspect("equal")
    axes.set_xlabel("x [mm]")
    axes.set_ylabel("y [mm]")
    if path is not None:
        save_figure(fig, path)
    return fig
