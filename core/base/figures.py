"""What every preform figure shares: an off-screen matplotlib figure of a known pixel size, saved
atomically.

The figures themselves live in ``fig_unit_cell``, ``fig_drape`` and ``fig_curves``. Figures are
built on ``matplotlib.figure.Figure`` directly, never through pyplot: no global state, no GUI
backend, safe in worker processes. matplotlib is an optional extra (``preform[plot]``).
"""

from __future__ import annotations

import os
import struct
import threading
import zlib
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.atomic import atomic_path

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Resolution every figure is saved at [dots per inch]; sizes are given in pixels.
DEFAULT_DPI = 100

#: zlib level of the PNG files [0-9]. The rows are stored unfiltered (PNG filter type 0): on
#: these flat-coloured figures that compresses better than the adaptive filters matplotlib's
#: writer (Pillow) tries row by row, and at level 1 the fibre-pattern figure encodes in ~0.4 of
#: its time into a file ~13 % smaller (benchmarks/README.md, section (m)).
PNG_COMPRESS_LEVEL = 1

#: Settings every figure is drawn with. FreeType's hinting off: the glyphs keep their own
#: outlines instead of being snapped to the pixel grid, which reads as well at 100 dpi and
#: nearly halves the cost of drawing text, the largest part of a figure's drawing (section (m)).
DRAW_RC: dict[str, Any] = {"text.hinting": "no_hinting"}

#: Renderers kept per thread, one per figure size (a run draws Fig. 11 and Fig. 10 at two sizes).
KEPT_RENDERERS = 3
_renderers = threading.local()


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


def _renderer(width: int, height: int, dpi: float) -> Any:
    """This thread's Agg renderer of that pixel size, kept between figures: matplotlib caches
    the sizes of drawn strings per renderer, and a run's figures repeat most of theirs (tick
    labels, axis labels, legends); a new renderer would also allocate and clear a new buffer."""
    from matplotlib.backends.backend_agg import RendererAgg

    cache: dict[tuple[int, int, float], Any] = _renderers.__dict__.setdefault("by_size", {})
    key = (width, height, float(dpi))
    if key not in cache:
        if len(cache) >= KEPT_RENDERERS:  # a buffer is width × height × 4 bytes
            del cache[next(iter(cache))]
        cache[key] = RendererAgg(width, height, dpi)
    return cache[key]


def png_bytes(rgb: np.ndarray, level: int = PNG_COMPRESS_LEVEL) -> bytes:
    """An 8-bit RGB image (height, width, 3) as the bytes of a PNG file: one IDAT chunk of the
    unfiltered rows (each row prefixed by filter type 0), zlib at ``level``."""
    image = np.asarray(rgb)
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        raise ValueError(f"expected an (h, w, 3) uint8 image, got {image.shape} {image.dtype}")
    height, width = image.shape[:2]
    rows = np.zeros((height, 1 + 3 * width), dtype=np.uint8)
    rows[:, 1:] = image.reshape(height, -1)

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8 bits, RGB, no interlace
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(rows.tobytes(), level))
        + chunk(b"IEND", b"")
    )


def save_figure(fig: Figure, path: str | os.PathLike[str]) -> None:
    """Save ``fig`` to ``path`` atomically, at the figure's own size and dpi.

    The format follows the suffix (.png, .svg, .pdf). No tight bounding box: the pixel size a
    caller asked for is the pixel size they get. A PNG is drawn on this thread's kept renderer
    and written opaque RGB (the figure's background is white; an alpha channel would only add a
    constant byte a pixel) by :func:`png_bytes`; other formats go through matplotlib's savefig.
    """
    import matplotlib

    with atomic_path(path) as tmp, matplotlib.rc_context(DRAW_RC):  # type: ignore[arg-type]
        fmt = tmp.suffix.lstrip(".").lower() or "png"
        if fmt != "png":
            fig.savefig(tmp, dpi=fig.dpi, format=fmt)
            return
        width, height = (int(v) for v in fig.bbox.size)  # as FigureCanvasAgg sizes its buffer
        renderer = _renderer(width, height, fig.dpi)
        renderer.clear()
        fig.draw(renderer)
        rgba = np.asarray(renderer.buffer_rgba())
        tmp.write_bytes(png_bytes(rgba[..., :3]))
