"""The error map of a comparison: the measured points coloured by their angle error, from
above (with the draped net's fibres) and in 3D. Axes in mm, errors in degrees."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from preform.base.figures import new_figure, save_figure
from preform.compare.comparison import Comparison
from preform.compare.vtu import largest_angle_error
from preform.drape.engine.result import DrapeResult

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MM_PER_M = 1e3
#: Every how many node lines of the net the plan view draws, at most this many per family.
NET_LINES = 40


def _net_lines(ax: object, result: DrapeResult) -> None:
    nodes = np.asarray(result.nodes) * MM_PER_M
    ni, nj = result.shape
    for axis, count in ((0, ni), (1, nj)):
        every = max(1, count // NET_LINES)
        for k in range(0, count, every):
            line = nodes[k] if axis == 0 else nodes[:, k]
            ax.plot(line[:, 0], line[:, 1], color="0.8", lw=0.4, zorder=0)  # type: ignore[attr-defined]


def error_map_figure(
    comparison: Comparison,
    result: DrapeResult | None,
    path: str | os.PathLike[str] | None,
    *,
    title: str | None = None,
    size_px: tuple[int, int] = (1600, 760),
    max_error_deg: float | None = None,
) -> Figure:
    """Draw the error map and save it to ``path`` (None: return the figure only). Left, plan
    view: the net's node lines (grey) and the compared points coloured by the larger |angle
    error| of the two families (|shear error| where only shear was measured) [deg]; points
    not compared are grey crosses. Right: the same points in 3D. The colour scale runs from 0
    to ``max_error_deg`` (default: the 98th percentile)."""
    fig = new_figure(size_px)
    error = largest_angle_error(comparison)
    shown = np.isfinite(error)
    top = max_error_deg
    if top is None:
        top = float(np.percentile(error[shown], 98)) if shown.any() else 1.0
    top = max(top, 1e-3)
    p = comparison.point_mm
    left = fig.add_subplot(1, 2, 1)
    if result is not None:
        _net_lines(left, result)
    sc = left.scatter(p[shown, 0], p[shown, 1], c=error[shown], cmap="viridis", vmin=0.0,
                      vmax=top, s=14, zorder=2)  # fmt: skip
    left.scatter(p[~shown, 0], p[~shown, 1], marker="x", color="0.5", s=14, zorder=1,
                 label="not compared (off the tool or the net)")  # fmt: skip
    if (~shown).any():
        left.legend(loc="lower left", fontsize=8)
    left.set_aspect("equal")
    left.set_xlabel("x [mm]")
    left.set_ylabel("y [mm]")
    left.set_title("plan view")
    right = fig.add_subplot(1, 2, 2, projection="3d")
    right.scatter(p[shown, 0], p[shown, 1], p[shown, 2], c=error[shown], cmap="viridis",
                  vmin=0.0, vmax=top, s=10)  # fmt: skip
    right.scatter(p[~shown, 0], p[~shown, 1], p[~shown, 2], marker="x", color="0.5", s=10)
    finite = np.all(np.isfinite(p), axis=1)
    if finite.any():
        # equal scales on the three axes: the tool's shape as it is
        right.set_box_aspect(tuple(np.maximum(np.ptp(p[finite], axis=0), 1e-6)))
    right.set_xlabel("x [mm]")
    right.set_ylabel("y [mm]")
    right.set_zlabel("z [mm]")
    right.set_title("3D")
    fig.colorbar(sc, ax=[left, right], shrink=0.8, label="|angle error| [deg]")
    words = comparison.words()
    fig.suptitle(f"{title}\n{words}" if title else words)
    if path is not None:
        save_figure(fig, path)
    return fig
