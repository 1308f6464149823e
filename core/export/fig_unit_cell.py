"""3D picture of a fabric's unit cell, each tow drawn as a ribbon (the paper's Fig. 5).

A ribbon is a flat strip of the tow's width lying in the fabric plane across the centreline: it
shows crimp, interlacing and tow spacing (the checks a user makes on a new fabric entry) while
staying cheap to draw; tubes would add the tow height, which is small next to the width.
"""

from __future__ import annotations

import os
from collections import Counter
from typing import TYPE_CHECKING, Literal

import numpy as np

from preform.base.figures import new_figure, save_figure
from preform.geometry.unit_cell import TowPath, UnitCell

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


#: Largest in-plane size of a view [mm]: a unit cell wider than this (a warp-knit's repeat of
#: 60 × 71 mm and 214 tows) is shown as a detail of this size from its middle instead of tiled,
#: since tows thinner than a pixel or two read as a texture, not as a construction.
DETAIL_MM = 25.0

#: Smallest visual height of the z box, as a fraction of the in-plane size, before the figure
#: exaggerates z on its own: a crimp of 0.1 mm over a 10 mm cell is otherwise invisible.
MIN_Z_BOX_FRACTION = 0.08


def refine_polyline(points: np.ndarray, max_length: float) -> np.ndarray:
    """``points`` (n, 3) with every segment longer than ``max_length`` [m] split evenly."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(pts) < 2 or max_length <= 0:
        return pts
    lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    pieces = np.maximum(1, np.ceil(lengths / max_length).astype(int))
    parts = [
        a + np.linspace(0.0, 1.0, n, endpoint=False)[:, None] * (b - a)
        for a, b, n in zip(pts[:-1], pts[1:], pieces.tolist(), strict=True)
    ]
    return np.concatenate([*parts, pts[-1:]])


def tow_ribbon(tow: TowPath, max_segment: float | None = None) -> np.ndarray:
    """Quads (m, 4, 3) [m] of a strip of the tow's width centred on its centreline.

    The strip is horizontal across the path (direction z × tangent), so it stays flat where the
    tow crimps; where the path is vertical (a stitch through the thickness) the last in-plane
    direction is kept. One quad per centreline segment (m = n − 1), or more when
    ``max_segment`` [m] splits long segments.
    """
    pts = np.asarray(tow.points, dtype=float).reshape(-1, 3)
    if max_segment is not None:
        pts = refine_polyline(pts, max_segment)
    if len(pts) < 2:
        return np.empty((0, 4, 3))
    tangent = np.gradient(pts, axis=0)
    across = np.column_stack([-tangent[:, 1], tangent[:, 0], np.zeros(len(pts))])
    norm = np.linalg.norm(across, axis=1)
    scale = float(np.max(norm)) if norm.size else 0.0
    flat = norm > 1e-6 * max(scale, np.finfo(float).tiny)
    if not np.any(flat):
        across[:] = (1.0, 0.0, 0.0)
    else:
        # Carry the last in-plane direction over vertical stretches (forward, then the start).
        idx = np.where(flat, np.arange(len(pts)), 0)
        np.maximum.accumulate(idx, out=idx)
        idx[: int(np.argmax(flat))] = int(np.argmax(flat))
        across = across[idx] / norm[idx, None]
    half = 0.5 * tow.width * across
    left, right = pts + half, pts - half
    return np.stack([left[:-1], left[1:], right[1:], right[:-1]], axis=1)


def _group_label(key: object, colour_by: str, tows: list[TowPath], cell: UnitCell) -> str:
    if colour_by == "type":
        return str(key)
    names = cell.labels.get("levels")
    if isinstance(names, dict) and key in names:
        return f"level {key}: {names[key]}"
    kind = Counter(t.kind for t in tows).most_common(1)[0][0]
    return f"level {key} ({kind})"


def unit_cell_figure(
    cell: UnitCell,
    path: str | os.PathLike[str],
    *,
    colour_by: Literal["level", "type"] = "level",
    repeats: tuple[int, int] = (1, 1),
    title: str | None = None,
    size_px: tuple[int, int] = (1400, 700),
    vertical_exaggeration: float | None = None,
    view: tuple[float, float] = (35.0, -60.0),
    detail_mm: float | None = DETAIL_MM,
) -> Figure:
    """Draw ``cell`` (tiled ``repeats`` times) as 3D ribbons and save it to ``path``.

    Tows are coloured by ``level`` (legend "level L (kind)", or the name from
    ``cell.labels["levels"]``) or by ``type`` (tow type name, or the kind when unnamed). Axes are
    in mm with equal scale on x and y; z is drawn ``vertical_exaggeration`` times larger, by
    default (None) just enough for the z box to be ``MIN_Z_BOX_FRACTION`` of the cell (1 when
    the cell is thick enough; the factor is given in the z label; tick values stay true mm).
    ``view`` is (elevation, azimuth) [deg]. ``size_px`` is the saved (width, height) [pixels].

    Two panels: the 3D view (``fig.axes[0]``, with the legend) and a plan view from above
    (``fig.axes[1]``), upper tows drawn over lower ones, which shows a warp-knit's stitching
    and tow angles at a glance. A cell wider than ``detail_mm`` [mm] in plan is shown as a
    ``detail_mm`` square from its middle, untiled (None: always the whole, tiled). Returns the
    figure (already saved).
    """
    if colour_by not in ("level", "type"):
        raise ValueError(f"colour_by must be 'level' or 'type', got {colour_by!r}")
    from matplotlib import colormaps
    from matplotlib.patches import Patch
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    window = _detail_window(cell, detail_mm)
    if window is not None:
        repeats = (1, 1)
    shown = cell.tiled(*repeats) if tuple(repeats) != (1, 1) else cell
    groups: dict[object, list[TowPath]] = {}
    for tow in shown.tows:
        key: object = tow.level if colour_by == "level" else (tow.type_name or tow.kind)
        groups.setdefault(key, []).append(tow)
    keys = sorted(groups, key=lambda k: (str(type(k)), k))
    palette = colormaps["tab10" if len(keys) <= 10 else "tab20"]

    quads: list[np.ndarray] = []
    colours: list[np.ndarray] = []
    handles = []
    for n, key in enumerate(keys):
        colour = np.asarray(palette(n % palette.N))
        for tow in groups[key]:
            # Pieces about as long as the tow is wide: matplotlib depth-sorts whole polygons, so
            # long straight quads would be drawn in front of tows that cross over them.
            ribbon = 1e3 * tow_ribbon(tow, max_segment=tow.width)  # mm on the axes
            if window is not None:
                (x0, y0), (x1, y1) = window
                centre = ribbon.mean(axis=1)
                inside = (
                    (centre[:, 0] >= x0)
                    & (centre[:, 0] <= x1)
                    & (centre[:, 1] >= y0)
                    & (centre[:, 1] <= y1)
                )
                ribbon = ribbon[inside]
            quads.append(ribbon)
            colours.append(np.repeat(colour[None, :], len(ribbon), axis=0))
        handles.append(
            Patch(
                facecolor=tuple(colour),
                edgecolor="k",
                label=_group_label(key, colour_by, groups[key], shown),
            )
        )

    fig = new_figure(size_px)
    # the 3D view first: it is fig.axes[0], the one with the legend
    ax = fig.add_subplot(1, 2, 2, projection="3d")
    plan = fig.add_subplot(1, 2, 1)
    if quads:
        verts = np.concatenate(quads)
        faces = np.concatenate(colours)
        _plan_view(plan, verts, faces)
        # One collection for every tow, so matplotlib depth-sorts crossing tows against each
        # other; edges in the face colour hide the seams between a ribbon's quads.
        ax.add_collection3d(
            Poly3DCollection(verts, facecolors=faces, edgecolors=faces, linewidths=0.3, shade=True)
        )
        lo = verts.reshape(-1, 3).min(axis=0)
        hi = verts.reshape(-1, 3).max(axis=0)
        span = hi - lo
        pad = np.array([0.02, 0.02, 0.0]) * float(max(span[0], span[1], 1e-9)) + 0.05 * span[2]
        lo, hi = lo - pad, hi + pad
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        box = hi - lo
        in_plane = float(max(box[0], box[1]))
        if vertical_exaggeration is None:
            vertical_exaggeration = max(1.0, MIN_Z_BOX_FRACTION * in_plane / max(box[2], 1e-12))
        box[2] *= vertical_exaggeration
        ax.set_box_aspect(tuple(np.maximum(box, 1e-3 * in_plane)), zoom=0.95)
    ax.zaxis.set_major_locator(MaxNLocator(3))
    ax.view_init(elev=view[0], azim=view[1])
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    exaggerated = vertical_exaggeration is not None and vertical_exaggeration > 1.0 + 1e-9
    ax.set_zlabel(f"z [mm], drawn ×{vertical_exaggeration:.3g}" if exaggerated else "z [mm]")
    ax.legend(handles=handles, loc="upper left", title=f"by {colour_by}", fontsize="small")
    extent = _plan_extent(cell)
    if window is not None:
        (x0, y0), (x1, y1) = window
        what = (
            f"detail {x1 - x0:.3g} × {y1 - y0:.3g} mm of a {extent[0]:.3g} × {extent[1]:.3g} mm "
            f"unit cell ({len(cell.tows)} paths)"
        )
    else:
        what = (
            f"unit cell {extent[0]:.3g} × {extent[1]:.3g} mm, {len(cell.tows)} paths, "
            f"{repeats[0]}×{repeats[1]} repeats"
        )
    ax.set_title("3D view")
    fig.suptitle(f"{title}: {what}" if title else what.capitalize())
    fig.tight_layout()
    save_figure(fig, path)
    return fig


def _plan_extent(cell: UnitCell) -> tuple[float, float]:
    """In-plane size of the cell's tow centrelines [mm] (x, y)."""
    pts = np.concatenate([np.asarray(t.points, dtype=float).reshape(-1, 3) for t in cell.tows])
    span = 1e3 * (pts.max(axis=0) - pts.min(axis=0))
    return float(span[0]), float(span[1])


def _detail_window(
    cell: UnitCell, detail_mm: float | None
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The ``detail_mm`` square [mm] in the middle of a cell wider than that, else None."""
    if detail_mm is None or not cell.tows:
        return None
    pts = 1e3 * np.concatenate(
        [np.asarray(t.points, dtype=float).reshape(-1, 3) for t in cell.tows]
    )
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if max(hi[0] - lo[0], hi[1] - lo[1]) <= detail_mm:
        return None
    centre = 0.5 * (lo + hi)
    half = 0.5 * detail_mm
    return (centre[0] - half, centre[1] - half), (centre[0] + half, centre[1] + half)


def _plan_view(ax: Axes, verts: np.ndarray, faces: np.ndarray) -> None:
    """The ribbons seen from above [mm], the highest drawn last (on top)."""
    from matplotlib.collections import PolyCollection

    order = np.argsort(verts[:, :, 2].mean(axis=1), kind="stable")
    ax.add_collection(
        PolyCollection(
            list(verts[order, :, :2]),
            facecolors=faces[order],
            edgecolors=faces[order] * [0.7, 0.7, 0.7, 1.0],
            linewidths=0.2,
        )
    )
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title("Plan view (upper tows drawn over lower ones)")
