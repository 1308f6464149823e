"""What every preform figure shares: an off-screen matplotlib figure of a known pixel size, saved
atomically.

The figures themselves live in ``fig_unit_cell``, ``fig_drape`` and ``fig_curves``. Figures are
built on ``matplotlib.figure.Figure`` directly, never through pyplot: no global state, no GUI
backend, safe in worker processes. matplotlib is an optional extra (``preform[plot]``).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from preform.export.atomic import atomic_path

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Resolution every figure is saved at [dots per inch]; sizes are given in pixels.
DEFAULT_DPI = 100


def require_matplotlib() -> None:
    """Raise an ImportError that says how to install the plotting extra when it is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError('Figures need matplotlib: pip install "preform[plot]"') from exc


def new_figure(size_px: tuple[int, int], dpi: int = DEFAULT_DPI) -> Figure:
    """A figure that saves to exactly ``size_px`` (width, height) [pixels] at ``dpi``."""
    require_matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    width, height = size_px
    if width < 1 or height < 1:
        raise ValueError(f"figure size must be positive, got {size_px}")
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    FigureCanvasAgg(fig)  # attaches itself: rendering is off-screen whatever the backend
    return fig


def save_figure(fig: Figure, path: str | os.PathLike[str]) -> None:
    """Save ``fig`` to ``path`` atomically, at the figure's own size and dpi.

    The format follows the suffix (.png, .svg, .pdf). No tight bounding box: the pixel size a
    caller asked for is the pixel size they get.
    """
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=fig.dpi, format=tmp.suffix.lstrip(".") or "png")
