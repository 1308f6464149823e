"""A flat pattern a cutter can use: a smooth outline, a seam allowance, fibre marks and a label.

The flat is the fabric before draping: net node (i, j) sits at ((i − i0)·d, (j − j0)·d) with
the start node at the origin, u fibres along x and v fibres along y (the net is a bijection
between flat and draped cells; ``preform.export.flat_pattern``). Coordinates are mm.

The outline is one of:

- **a part outline** (``part_outline_m``: a closed curve on the tool, [m]), mapped to the flat
  point by point through the net: closest point on the draped net, then the same (i + s,
  j + t) in the flat, linear inside each half-cell. This is the outline once scenes have
  parts;
- **the part, clipped in the flat** (``part``: the scene's part, ``preform.drape.engine.part``): the
  part's level function φ at the net's nodes, taken as linear on the two triangles of each
  cell (split along its (i, j)–(i+1, j+1) diagonal), and each cell's region φ ≥ 0 laid out in
  the flat. The outline is then the part's edge interpolated inside the cells it cuts, exact
  where the edge is straight across a flat cell, with the same share of each cell that the
  energy counts (to the O(d²) difference between one diagonal split and their average);
- **without a part, the boundary of the covered net region** (valid cells in the part): the exact
  union of its cells, with the outer boundary of each piece interpolated inside its boundary
  cells: the polygon through the middle of every cell side on the boundary (a staircase
  along 45° becomes its straight line), then smoothed along its length by a Gaussian of
  σ = d, which irons out one-cell jogs at any slope. A convex step loses what a concave step
  gains, so the area stays that of the cells to O(d²) per corner of the outline (measured on
  the hemisphere: 1e-3 at d = 10 mm, 6e-5 at d = 2.5 mm). Holes (cells not draped inside the ply) keep
  their exact staircase: a cutter must not close them.

The seam allowance is the outline offset outwards by ``seam_allowance_mm`` with round joins
(area grows by a·perimeter + O(a²)). Fibre marks are short u (along x) and v (along y) lines
on a grid inside the outline; the label names the ply and how it is laid on the tool, in a few
lines centred inside a piece, its text height fitted to the piece (``_place_in``). Every
piece is labelled that holds its label at ``LABEL_MIN_HEIGHT_MM`` or more (a piece cut loose
must still say which ply it is): when a cut splits the pattern, the largest piece's label says
all with a second line ``piece 1 of n``, the others the ply's name and ``piece k of n`` only
(their blocks stay small and leave their fibre marks standing); the largest piece is always
labelled, a smaller one that cannot hold its two lines is counted (``unlabelled_pieces``), not
drawn over.

Darts and cuts are where the scene puts them (``export.darts``, ``export.cuts``), in the flat
coordinates above, because where a ply must be opened is the designer's decision (a dart
where the drape would fold or shear past locking, a slit to split a ply into pieces):

- **a dart** is the triangle (apex, mouth₁, mouth₂) removed from the outline: the fabric
  inside it is cut away, its two legs butt together when draped. The mouth ends lie on or
  beyond the edge, so the removed area is the triangle's part inside the outline. The seam
  allowance is cut by the same wedge carried on past the mouth (its legs lengthened by the
  allowance and one node spacing): the legs are butt joins and get no allowance;
- **a cut** is a straight slit from one point to the other. Where it crosses the outline
  from edge to edge, the outline is split into pieces along it (shapely); a slit that ends
  inside the fabric leaves the outline whole and is only drawn. A through-cut splits the
  allowance too (the cut line carried across it): its edges are butt joins as well.

Both are drawn on their own layer (DARTS: the open polyline mouth₁–apex–mouth₂; CUTS: the
line), in the SVG and the CSV. A dart or cut that misses the pattern is reported in
``problems``, not silently dropped. To show where a dart is wanted, the net cells sheared past
the law's locking angle are drawn in the flat too (layer PAST_LOCKING: the exact union of
those cells, ``past_locking`` given), so the designer places darts on a drawing of the
problem rather than guessing.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import escape

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import FloatArray
from preform.base.atomic import atomic_open, atomic_path
from preform.drape.engine.result import DrapeResult
from preform.export.flat_pattern import flat_pattern

if TYPE_CHECKING:
    from shapely.geometry import MultiPolygon

    from preform.drape.engine.part import Part

MM_PER_M = 1e3
#: DXF layers, in drawing order.
LAYERS = ("OUTLINE", "ALLOWANCE", "FIBRE_MARKS", "LABELS", "DARTS", "CUTS", "PAST_LOCKING")
#: A point in the flat [mm].
Point2 = tuple[float, float]
#: The label is fitted inside the piece by a box of (characters × LABEL_CHAR_WIDTH) by
#: (lines × LABEL_LINE_PITCH) text heights: wider than a proportional font's average (about
#: 0.6) and a monospaced CAD font's pitch (about 1.0 with its spacing), so the drawn text
#: stays inside whichever font the cutter's software substitutes.
LABEL_CHAR_WIDTH = 1.0
LABEL_LINE_PITCH = 1.6
#: Largest label text height [mm]: a large piece gets legible text, not a poster.
LABEL_MAX_HEIGHT_MM = 10.0
#: Smallest text height [mm] a piece other than the largest is labelled at: a plotted or
#: printed letter much smaller than 2 mm is not read on the cutting table (a practical choice,
#: not a standard's number).
LABEL_MIN_HEIGHT_MM = 2.0


def _require_shapely() -> Any:
    try:
        import shapely
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError('Flat patterns need shapely: pip install "preform[cutting]"') from exc
    return shapely


@dataclass(frozen=True)
class FibreMark:
    """A short line along one fibre family in the flat [mm]."""

    family: str
    start: tuple[float, float]
    end: tuple[float, float]


@dataclass(frozen=True)
class Dart:
    """A dart removed from the pattern [mm]: the triangle apex, mouth[0], mouth[1]."""

    apex: Point2
    mouth: tuple[Point2, Point2]
    #: Fabric area the dart removed from the outline [mm²].
    removed_area_mm2: float


@dataclass(frozen=True)
class Cut:
    """A straight cut in the flat [mm]."""

    start: Point2
    end: Point2
    #: The cut crosses the outline from edge to edge and splits a piece in two (or more).
    splits: bool
    #: Length of the cut inside the outline [mm].
    length_in_fabric_mm: float


@dataclass(frozen=True)
class PieceLabel:
    """A label drawn inside one piece of the pattern: its lines centred on ``at`` [mm],
    ``LABEL_LINE_PITCH`` text heights apart."""

    #: The piece, 1 the largest by area (the order of ``CutPattern.pieces_by_area``).
    piece: int
    lines: tuple[str, ...]
    at: Point2
    text_height_mm: float


@dataclass(frozen=True)
class CutPattern:
    """The ply in the flat, ready to cut: all lengths mm."""

    #: The cutting outline (pieces with holes).
    outline: MultiPolygon
    #: The outline grown by the seam allowance (None without one).
    allowance: MultiPolygon | None
    seam_allowance_mm: float
    marks: tuple[FibreMark, ...]
    label: str
    #: Centre of the label block [mm], inside the largest piece (its pole of inaccessibility).
    label_at: tuple[float, float]
    #: Text height [mm], fitted so the label block lies inside that piece (``LABEL_*``).
    text_height_mm: float
    node_spacing_mm: float
    #: Net cells in the covered region, and the fabric area they stand for (cells · d²) [mm²].
    cell_count: int
    cells_area_mm2: float
    #: "part outline" or "covered net region".
    outline_from: str
    darts: tuple[Dart, ...] = ()
    cuts: tuple[Cut, ...] = ()
    #: Net cells of the pattern sheared past locking, in the flat (None: not known).
    past_locking: MultiPolygon | None = None
    #: Darts or cuts that miss the pattern, said in words.
    problems: tuple[str, ...] = ()
    #: The label as it is drawn: one line each, centred on ``label_at``, ``LABEL_LINE_PITCH``
    #: text heights apart (empty: the label on one line).
    label_lines: tuple[str, ...] = ()
    #: Every piece's label (the largest piece's first: ``label_at``, ``label_lines``); empty:
    #: the one label above.
    piece_labels: tuple[PieceLabel, ...] = ()
    #: Pieces too small for even a one-line label at ``LABEL_MIN_HEIGHT_MM``.
    unlabelled_pieces: int = 0

    @property
    def drawn_label(self) -> tuple[str, ...]:
        """The lines of the largest piece's label."""
        return self.label_lines or (self.label,)

    @property
    def drawn_labels(self) -> tuple[PieceLabel, ...]:
        """The labels the DXF and SVG draw, one per labelled piece, the largest first."""
        if self.piece_labels:
            return self.piece_labels
        return (PieceLabel(1, self.drawn_label, self.label_at, self.text_height_mm),)

    @property
    def pieces_by_area(self) -> list[Any]:
        """The outline's pieces, largest first (piece k is entry k − 1)."""
        return sorted(self.outline.geoms, key=lambda g: -g.area)

    @property
    def area_mm2(self) -> float:
        return float(self.outline.area)

    @property
    def perimeter_mm(self) -> float:
        return float(self.outline.length)

    @property
    def allowance_area_mm2(self) -> float | None:
        return None if self.allowance is None else float(self.allowance.area)

    def summary(self) -> dict[str, Any]:
        return {
            "outline_from": self.outline_from,
            "pieces": len(self.outline.geoms),
            "area_mm2": self.area_mm2,
            "perimeter_mm": self.perimeter_mm,
            "cells_area_mm2": self.cells_area_mm2,
            "seam_allowance_mm": self.seam_allowance_mm,
            "allowance_area_mm2": self.allowance_area_mm2,
            "fibre_marks": len(self.marks),
            "label": self.label,
            "labelled_pieces": len(self.drawn_labels) if not self.outline.is_empty else 0,
            "unlabelled_pieces": self.unlabelled_pieces,
            "darts": len(self.darts),
            "darts_removed_area_mm2": sum(d.removed_area_mm2 for d in self.darts),
            "cuts": len(self.cuts),
            "cuts_splitting": sum(c.splits for c in self.cuts),
            "problems": list(self.problems),
            "past_locking_area_mm2": (
                None if self.past_locking is None else float(self.past_locking.area)
            ),
            "length_unit": "mm",
        }


def flat_points(result: DrapeResult, points_m: FloatArray) -> FloatArray:
    """Flat positions (k, 2) [mm] of points (k, 3) [m] on or near the draped net: their closest
    point on the net, carried to the flat through the same net coordinates (linear inside each
    half-cell)."""
    from preform.export.fe_mapping import closest_on_net

    hit = closest_on_net(result, MM_PER_M * np.asarray(points_m, dtype=float).reshape(-1, 3))
    i0, j0 = result.start_index
    d_mm = MM_PER_M * result.node_spacing
    return np.column_stack([(hit.a - i0) * d_mm, (hit.b - j0) * d_mm])


def _as_multi(geom: Any) -> MultiPolygon:
    from shapely.geometry import MultiPolygon, Polygon

    if geom.is_empty:
        return MultiPolygon()
    if isinstance(geom, Polygon):
        return MultiPolygon([geom])
    if isinstance(geom, MultiPolygon):
        return geom
    polys = [g for g in getattr(geom, "geoms", []) if isinstance(g, Polygon)]
    return MultiPolygon(polys)


def _cells_region(result: DrapeResult) -> tuple[Any, int]:
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    staircase = flat_pattern(result)
    outers = [
        Polygon(loop)
        for loop, hole in zip(staircase.loops, staircase.holes, strict=True)
        if not hole
    ]
    holes = [
        Polygon(loop) for loop, hole in zip(staircase.loops, staircase.holes, strict=True) if hole
    ]
    region = unary_union(outers).difference(unary_union(holes)) if outers else Polygon()
    return region, staircase.cell_count


def _densify(ring: FloatArray, step: float) -> FloatArray:
    """The staircase ring with a vertex at every node (every ``step`` along each side)."""
    out = []
    for p, q in zip(ring, np.roll(ring, -1, axis=0), strict=True):
        count = max(1, round(float(np.linalg.norm(q - p)) / step))
        t = np.arange(count)[:, None] / count
        out.append(p + t * (q - p))
    return np.concatenate(out)


def _smooth_ring(ring: FloatArray, step: float, passes: int) -> FloatArray:
    """Midpoints of the staircase's unit sides (the outline through the middle of each
    boundary cell side: a 45° staircase becomes its straight line), then, for ``passes`` > 0,
    resampled every d/2 along its length and filtered with a binomial (≈ Gaussian) kernel of
    standard deviation passes·d/2, which irons out the one-cell jogs of a staircase at any slope
    while moving a curve of radius R inwards by only ≈ σ²/2R."""
    pts = _densify(ring, step)
    pts = 0.5 * (pts + np.roll(pts, -1, axis=0))
    if passes <= 0 or len(pts) < 4:
        return pts
    seg = np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    count = max(8, int(np.ceil(arc[-1] / (0.5 * step))))
    at = np.linspace(0.0, arc[-1], count, endpoint=False)
    closed = np.vstack([pts, pts[:1]])
    pts = np.column_stack([np.interp(at, arc, closed[:, k]) for k in range(2)])
    # k rounds of [1, 2, 1]/4 have variance k/2 samples²: σ = passes·d/2 = passes samples
    for _ in range(2 * passes * passes):
        pts = 0.25 * np.roll(pts, 1, axis=0) + 0.5 * pts + 0.25 * np.roll(pts, -1, axis=0)
    return pts


def _smooth(region: Any, step: float, passes: int) -> Any:
    """Each piece's outer boundary smoothed (module docstring); holes kept exact."""
    import shapely
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    if passes < 0:
        return region
    pieces = []
    for piece in _as_multi(region).geoms:
        ring = np.asarray(piece.exterior.coords, dtype=float)[:-1]
        smooth = shapely.make_valid(Polygon(_smooth_ring(ring, step, passes)))
        holes = [Polygon(r) for r in piece.interiors]
        pieces.append(smooth.difference(unary_union(holes)) if holes else smooth)
    return unary_union(pieces)


def _marks(outline: Any, spacing: float, length: float) -> list[FibreMark]:
    from shapely.geometry import LineString

    if outline.is_empty:
        return []
    x0, y0, x1, y1 = outline.bounds
    xs = np.arange(np.floor(x0 / spacing) * spacing, x1 + spacing, spacing)
    ys = np.arange(np.floor(y0 / spacing) * spacing, y1 + spacing, spacing)
    marks = []
    half = 0.5 * length
    for x in xs.tolist():
        for y in ys.tolist():
            for family, (dx, dy) in (("u", (half, 0.0)), ("v", (0.0, half))):
                seg = ((x - dx, y - dy), (x + dx, y + dy))
                if any(piece.contains(LineString(seg)) for piece in outline.geoms):
                    marks.append(FibreMark(family, seg[0], seg[1]))
    return marks


def _wedge(apex: Point2, mouth: tuple[Point2, Point2], extra_mm: float) -> Any:
    """The dart triangle with both legs lengthened by ``extra_mm`` past the mouth."""
    from shapely.geometry import Polygon

    a = np.asarray(apex, dtype=float)
    ends = []
    for m in mouth:
        leg = np.asarray(m, dtype=float) - a
        ends.append(a + leg * (1.0 + extra_mm / float(np.linalg.norm(leg))))
    return Polygon([tuple(a), tuple(ends[0]), tuple(ends[1])])


def _extended(start: Point2, end: Point2, extra_mm: float) -> Any:
    from shapely.geometry import LineString

    p, q = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    e = (q - p) / float(np.linalg.norm(q - p))
    return LineString([tuple(p - extra_mm * e), tuple(q + extra_mm * e)])


def _split(geom: MultiPolygon, line: Any) -> MultiPolygon:
    from shapely.geometry import MultiPolygon
    from shapely.ops import split

    pieces = []
    for piece in geom.geoms:
        pieces += list(_as_multi(split(piece, line)).geoms)
    # the pieces share the cut line: a MultiPolygon of them (not unioned back into one) is
    # what a cutter needs, even though GEOS calls pieces that touch along a line invalid
    return MultiPolygon(pieces)


def _apply_darts_and_cuts(
    outline: MultiPolygon,
    allowance: MultiPolygon | None,
    darts_mm: Any,
    cuts_mm: Any,
    extra_mm: float,
) -> tuple[MultiPolygon, MultiPolygon | None, list[Dart], list[Cut], list[str]]:
    from shapely.geometry import LineString, Point

    darts: list[Dart] = []
    cuts: list[Cut] = []
    problems: list[str] = []
    for k, (apex, mouth) in enumerate(darts_mm):
        apex = (float(apex[0]), float(apex[1]))
        mouth = tuple((float(m[0]), float(m[1])) for m in mouth)
        triangle = _wedge(apex, mouth, 0.0)
        if triangle.area <= 0.0:
            raise ValueError(f"dart {k}: apex and mouth lie on one line")
        before = outline.area
        outline = _as_multi(outline.difference(triangle))
        removed = float(before - outline.area)
        if removed <= 0.0:
            problems.append(f"dart {k} (apex at {apex[0]:g}, {apex[1]:g} mm) misses the pattern")
        elif not Point(apex).within(outline.buffer(1e-9)):
            problems.append(f"dart {k}: its apex {apex[0]:g}, {apex[1]:g} mm is not in the fabric")
        if allowance is not None:
            allowance = _as_multi(allowance.difference(_wedge(apex, mouth, extra_mm)))
        darts.append(Dart(apex, mouth, removed))
    for k, (start, end) in enumerate(cuts_mm):
        start = (float(start[0]), float(start[1]))
        end = (float(end[0]), float(end[1]))
        if start == end:
            raise ValueError(f"cut {k}: its two ends are the same point")
        line = LineString([start, end])
        inside = float(line.intersection(outline).length)
        count = len(outline.geoms)
        outline = _split(outline, line)
        splits = len(outline.geoms) > count
        if inside <= 0.0:
            problems.append(f"cut {k} misses the pattern")
        if splits and allowance is not None:
            allowance = _split(allowance, _extended(start, end, extra_mm))
        cuts.append(Cut(start, end, splits, inside))
    return outline, allowance, darts, cuts, problems


def cut_pattern(
    result: DrapeResult,
    *,
    seam_allowance_mm: float = 0.0,
    ply_name: str = "ply",
    smoothing: int = 3,
    part_outline_m: FloatArray | None = None,
    mark_spacing_mm: float | None = None,
    darts_mm: Sequence[tuple[Point2, tuple[Point2, Point2]]] = (),
    cuts_mm: Sequence[tuple[Point2, Point2]] = (),
    past_locking: NDArray[np.bool_] | None = None,
    part: Part | None = None,
) -> CutPattern:
    """The cutting pattern of a drape (module docstring). ``seam_allowance_mm`` ≥ 0;
    ``smoothing``: 0 the exact staircase of the cells, 1 the polygon through the middles of
    its sides, n > 1 that polygon smoothed over (n − 1)·d/2 (default 3: σ = d);
    ``part_outline_m`` (k, 3) [m] a closed curve on the tool to use as the outline;
    ``mark_spacing_mm`` the grid of fibre marks (default: about a fifth of the pattern);
    ``darts_mm`` (apex, (mouth₁, mouth₂)) and ``cuts_mm`` (start, end) in the flat [mm]
    (module docstring); ``past_locking`` a cell mask (the net's cell shape) of cells sheared
    past locking, drawn in the flat where they lie in the pattern's region; ``part`` the
    scene's part, whose region in the flat becomes the outline (module docstring)."""
    shapely = _require_shapely()
    from shapely.geometry import LineString, Polygon

    if not np.isfinite(seam_allowance_mm) or seam_allowance_mm < 0:
        raise ValueError(f"seam_allowance_mm must be ≥ 0, got {seam_allowance_mm!r}")
    if int(smoothing) != smoothing or smoothing < 0:
        raise ValueError(f"smoothing must be a whole number ≥ 0, got {smoothing!r}")
    d_mm = MM_PER_M * result.node_spacing
    cells, cell_count = _cells_region(result)
    if part_outline_m is not None:
        flat = flat_points(result, part_outline_m)
        outline = shapely.make_valid(Polygon(flat))
        source = "part outline"
    elif part is not None:
        outline = part_region_in_flat(result, part)
        source = "part, clipped in the flat"
    else:
        outline = _smooth(cells, d_mm, smoothing - 1)
        source = "covered net region"
    outline = _as_multi(outline)
    allowance = None
    if seam_allowance_mm > 0 and not outline.is_empty:
        allowance = _as_multi(outline.buffer(seam_allowance_mm, quad_segs=16))
    locking = None
    if past_locking is not None:
        locking = _cells_in_flat(result, np.asarray(past_locking, dtype=bool), d_mm)
    outline, allowance, darts, cuts, problems = _apply_darts_and_cuts(
        outline, allowance, darts_mm, cuts_mm, seam_allowance_mm + d_mm
    )
    if outline.is_empty:
        size = d_mm
    else:
        x0, y0, x1, y1 = outline.bounds
        size = max(x1 - x0, y1 - y0)
    spacing = mark_spacing_mm if mark_spacing_mm is not None else max(d_mm, size / 5.0)
    marks = _marks(outline, spacing, 0.4 * spacing)
    orientation = float(np.degrees(result.orientation))
    alpha = float(np.degrees(result.generator_angle))
    label = (
        f"{ply_name}: u fibres along x here, laid at {orientation:.1f} deg to the tool x axis "
        f"(v at {alpha:.1f} deg from u at the start); d = {d_mm:g} mm; units mm"
    )
    lines: tuple[str, ...] = (
        f"{ply_name}",
        f"u fibres along x, laid at {orientation:.1f} deg to the tool x axis",
        f"v at {alpha:.1f} deg from u at the start",
        f"d = {d_mm:g} mm; units mm",
    )
    labels, unlabelled = _piece_labels(outline, lines, marks)
    label_at, height, lines = labels[0].at, labels[0].text_height_mm, labels[0].lines
    # fibre marks through a label would strike its text out: the labels' blocks keep clear
    for placed in labels:
        h = placed.text_height_mm
        block = _label_block(placed.at, h, placed.lines, margin=0.5 * h)
        marks = [m for m in marks if not block.intersects(LineString([m.start, m.end]))]
    return CutPattern(
        outline=outline,
        allowance=allowance,
        seam_allowance_mm=float(seam_allowance_mm),
        marks=tuple(marks),
        label=label,
        label_at=label_at,
        text_height_mm=height,
        label_lines=lines,
        piece_labels=labels,
        unlabelled_pieces=unlabelled,
        node_spacing_mm=d_mm,
        cell_count=cell_count,
        cells_area_mm2=cell_count * d_mm * d_mm,
        outline_from=source,
        darts=tuple(darts),
        cuts=tuple(cuts),
        problems=tuple(problems),
        past_locking=locking,
    )


def _label_block(at: Point2, height: float, lines: Sequence[str], margin: float = 0.0) -> Any:
    """The box [mm] a label of ``lines`` at text height ``height`` centred at ``at`` takes
    (``LABEL_CHAR_WIDTH``, ``LABEL_LINE_PITCH``), grown by ``margin`` [mm]."""
    from shapely.geometry import box

    half_w = 0.5 * height * LABEL_CHAR_WIDTH * max(len(line) for line in lines) + margin
    half_h = 0.5 * height * LABEL_LINE_PITCH * len(lines) + margin
    return box(at[0] - half_w, at[1] - half_h, at[0] + half_w, at[1] + half_h)


def _piece_labels(
    outline: MultiPolygon, lines: tuple[str, ...], marks: Sequence[FibreMark] = ()
) -> tuple[tuple[PieceLabel, ...], int]:
    """The label of every piece that holds one (module docstring), the largest piece's first,
    and the count of pieces too small for any. A smaller piece's label goes where it clears
    the fibre marks when it can (at ``LABEL_MIN_HEIGHT_MM`` or more): a small piece has few
    marks, and a label over them would take them away."""
    from shapely.geometry import LineString

    segments = [LineString([m.start, m.end]) for m in marks]
    if outline.is_empty:
        return (PieceLabel(1, lines, (0.0, 0.0), 1.0),), 0
    pieces = sorted(outline.geoms, key=lambda g: -g.area)
    n = len(pieces)
    labels: list[PieceLabel] = []
    unlabelled = 0
    for k, piece in enumerate(pieces, 1):
        if n == 1:
            tries = [lines]
        else:
            # the largest piece says all; the others name the ply and the piece, so their
            # labels stay small and leave their fibre marks standing
            which = f"piece {k} of {n}"
            tries = [(lines[0], which, *lines[1:])] if k == 1 else [(lines[0], which)]
        for text in tries:
            at, height = _place_in(piece, text)
            if k > 1 and segments:
                clear_at, clear_height = _place_in(piece, text, avoid=segments)
                if clear_height >= LABEL_MIN_HEIGHT_MM:
                    at, height = clear_at, clear_height
            if k == 1 or height >= LABEL_MIN_HEIGHT_MM:
                labels.append(PieceLabel(k, tuple(text), at, height))
                break
        else:
            unlabelled += 1
    return tuple(labels), unlabelled


def _place_in(piece: Any, lines: Sequence[str], avoid: Sequence[Any] = ()) -> tuple[Point2, float]:
    """Where the label block goes and its text height [mm]: the block, ``LABEL_CHAR_WIDTH``
    text heights a character wide and ``LABEL_LINE_PITCH`` a line tall, at the largest
    height (at most ``LABEL_MAX_HEIGHT_MM``) at which it lies inside ``piece``, its holes
    kept out. Centres tried: the piece's pole of inaccessibility (the point farthest from its
    edges: best on a round piece) and a 12 × 12 grid over it (a long strip's best place is
    anywhere along its middle); the height at each by bisection. A label that ran past the
    piece would be cut through or printed on the scrap. With ``avoid`` (shapely lines), a
    centre counts only where the block, grown by half a text height, touches none of them
    (height 0 when no centre does)."""
    import shapely
    from shapely.geometry import Point
    from shapely.ops import polylabel

    shapely.prepare(piece)
    x0, y0, x1, y1 = piece.bounds
    width = LABEL_CHAR_WIDTH * max(len(line) for line in lines)
    height = LABEL_LINE_PITCH * len(lines)
    pole = polylabel(piece, tolerance=1e-3 * max(x1 - x0, y1 - y0))
    grid = [
        Point(x, y)
        for x in np.linspace(x0, x1, 14)[1:-1].tolist()
        for y in np.linspace(y0, y1, 14)[1:-1].tolist()
    ]
    most = min(LABEL_MAX_HEIGHT_MM, (x1 - x0) / width, (y1 - y0) / height)

    def fits(c: Any, h: float) -> bool:
        return bool(piece.contains(_label_block((c.x, c.y), h, lines)))

    best, best_h = pole, 0.0
    for centre in [pole, *(p for p in grid if piece.contains(p))]:
        # the circle the centre holds bounds the height from below: the block's half-diagonal
        low = float(piece.boundary.distance(centre)) / (0.5 * float(np.hypot(width, height)))
        low, high = min(low, most), most
        if high <= best_h or not fits(centre, low):
            continue
        if fits(centre, high):
            low = high
        else:
            for _ in range(30):
                middle = 0.5 * (low + high)
                low, high = (middle, high) if fits(centre, middle) else (low, middle)
                if high - low < 1e-4 * high:
                    break
        if avoid:
            block = _label_block((centre.x, centre.y), low, lines, margin=0.5 * low)
            if any(block.intersects(line) for line in avoid):
                continue
        if low > best_h:
            best, best_h = centre, low
    return (float(best.x), float(best.y)), best_h


def _inside_of_triangle(corners: FloatArray, phi: FloatArray) -> FloatArray:
    """The polygon of a flat triangle where the linear function with corner values ``phi`` is
    ≥ 0 (Sutherland–Hodgman against one half-plane): 0, 3 or 4 vertices."""
    out = []
    for k in range(3):
        a, b = corners[k], corners[(k + 1) % 3]
        fa, fb = phi[k], phi[(k + 1) % 3]
        if fa >= 0:
            out.append(a)
        if (fa >= 0) != (fb >= 0):
            out.append(a + (b - a) * (fa / (fa - fb)))
    return np.asarray(out, dtype=float)


def part_region_in_flat(result: DrapeResult, part: Part) -> MultiPolygon:
    """The region of the flat ply that the part takes [mm] (module docstring): whole cells
    with every corner inside, and the inside of each triangle of a cell the part's edge cuts."""
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    d_mm = MM_PER_M * result.node_spacing
    ni, nj = result.shape
    phi = np.asarray(part.level(np.asarray(result.nodes, dtype=float).reshape(-1, 3)))
    phi = phi.reshape(ni, nj)
    corners = np.stack([phi[:-1, :-1], phi[1:, :-1], phi[:-1, 1:], phi[1:, 1:]])
    valid = np.asarray(result.valid, dtype=bool) & np.all(np.isfinite(corners), axis=0)
    inside = valid & np.all(corners >= 0, axis=0)
    cut = valid & ~inside & np.any(corners > 0, axis=0)
    pieces = [_cells_in_flat(result, inside, d_mm)] if inside.any() else []
    i0, j0 = result.start_index
    for i, j in zip(*np.nonzero(cut), strict=True):
        x0, y0 = (i - i0) * d_mm, (j - j0) * d_mm
        p00, p10 = np.array([x0, y0]), np.array([x0 + d_mm, y0])
        p01, p11 = np.array([x0, y0 + d_mm]), np.array([x0 + d_mm, y0 + d_mm])
        f00, f10, f01, f11 = corners[0, i, j], corners[1, i, j], corners[2, i, j], corners[3, i, j]
        for tri, f in (
            ((p00, p10, p11), (f00, f10, f11)),
            ((p00, p11, p01), (f00, f11, f01)),
        ):
            poly = _inside_of_triangle(np.asarray(tri), np.asarray(f))
            if len(poly) >= 3:
                pieces.append(Polygon(poly))
    if not pieces:
        return _as_multi(Polygon())
    # the pieces share edges exactly; a tiny buffer round trip would only blur the outline
    return _as_multi(unary_union(pieces))


def _cells_in_flat(result: DrapeResult, mask: NDArray[np.bool_], d_mm: float) -> MultiPolygon:
    """The exact union of the masked cells of the pattern's region, in the flat [mm]: cell
    (i, j) is the square from ((i − i0)·d, (j − j0)·d) to one d further in x and y."""
    from shapely.geometry import Polygon, box
    from shapely.ops import unary_union

    region = np.asarray(result.valid & result.in_part, dtype=bool)
    if mask.shape != region.shape:
        raise ValueError(f"past_locking must have the net's cell shape {region.shape}")
    i0, j0 = result.start_index
    squares = [
        box((i - i0) * d_mm, (j - j0) * d_mm, (i - i0 + 1) * d_mm, (j - j0 + 1) * d_mm)
        for i, j in zip(*np.nonzero(mask & region), strict=True)
    ]
    # none: an empty drawing (a zero-size box would be a stray polyline at the origin)
    return _as_multi(unary_union(squares)) if squares else _as_multi(Polygon())


def _rings(geom: MultiPolygon | None) -> list[tuple[int, int, FloatArray]]:
    """(piece, ring, vertices without the closing repeat); ring 0 is the outer boundary."""
    out: list[tuple[int, int, FloatArray]] = []
    if geom is None:
        return out
    for p, piece in enumerate(geom.geoms):
        for r, ring in enumerate([piece.exterior, *piece.interiors]):
            out.append((p, r, np.asarray(ring.coords, dtype=float)[:-1]))
    return out


def write_cut_pattern_csv(pattern: CutPattern, path: str | os.PathLike[str]) -> None:
    """CSV: ``layer`` (outline / allowance / past_locking / dart / cut), ``piece`` (for darts and cuts: their
    number), ``ring`` (0 outer, ≥ 1 holes; 0 for darts and cuts), ``vertex``, ``x_mm``,
    ``y_mm``; one row per vertex (a dart: mouth₁, apex, mouth₂; a cut: its two ends)."""
    with atomic_open(path, "w", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(["layer", "piece", "ring", "vertex", "x_mm", "y_mm"])
        for layer, geom in (
            ("outline", pattern.outline),
            ("allowance", pattern.allowance),
            ("past_locking", pattern.past_locking),
        ):
            for piece, ring, pts in _rings(geom):
                for v, (x, y) in enumerate(pts.tolist()):
                    writer.writerow([layer, piece, ring, v, f"{x:.6f}", f"{y:.6f}"])
        for k, dart in enumerate(pattern.darts):
            for v, (x, y) in enumerate(_dart_polyline(dart)):
                writer.writerow(["dart", k, 0, v, f"{x:.6f}", f"{y:.6f}"])
        for k, cut in enumerate(pattern.cuts):
            for v, (x, y) in enumerate((cut.start, cut.end)):
                writer.writerow(["cut", k, 0, v, f"{x:.6f}", f"{y:.6f}"])


def _dart_polyline(dart: Dart) -> list[Point2]:
    """The dart as the cutter follows it: one mouth end, the apex, the other mouth end."""
    return [dart.mouth[0], dart.apex, dart.mouth[1]]


def _label_line_centres(label: PieceLabel) -> list[Point2]:
    """The middle of each line of ``label`` [mm], first line on top, the block centred."""
    cx, cy = label.at
    pitch = LABEL_LINE_PITCH * label.text_height_mm
    top = cy + 0.5 * pitch * (len(label.lines) - 1)
    return [(cx, top - k * pitch) for k in range(len(label.lines))]


def write_cut_pattern_dxf(pattern: CutPattern, path: str | os.PathLike[str]) -> None:
    """DXF (R2010, units mm) with layers OUTLINE, ALLOWANCE, FIBRE_MARKS, LABELS, DARTS,
    CUTS and PAST_LOCKING: closed LWPOLYLINEs for every ring (none on a layer with nothing to
    draw), LINEs for the fibre marks, one TEXT per label line (centred, inside its piece:
    every piece that holds its label, ``CutPattern.drawn_labels``), an open LWPOLYLINE (mouth₁, apex, mouth₂) per dart and a LINE per cut."""
    try:
        import ezdxf
        from ezdxf import units
        from ezdxf.enums import TextEntityAlignment
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError('DXF output needs ezdxf: pip install "preform[cutting]"') from exc
    doc = ezdxf.new("R2010")
    doc.units = units.MM
    doc.header["$MEASUREMENT"] = 1  # metric
    for name, colour in zip(LAYERS, (7, 1, 5, 3, 6, 4, 2), strict=True):
        doc.layers.add(name, color=colour)
    msp = doc.modelspace()
    for layer, geom in (
        ("OUTLINE", pattern.outline),
        ("ALLOWANCE", pattern.allowance),
        ("PAST_LOCKING", pattern.past_locking),
    ):
        for _, _, pts in _rings(geom):
            msp.add_lwpolyline(pts.tolist(), close=True, dxfattribs={"layer": layer})
    for mark in pattern.marks:
        msp.add_line(mark.start, mark.end, dxfattribs={"layer": "FIBRE_MARKS"})
    for dart in pattern.darts:
        msp.add_lwpolyline(_dart_polyline(dart), close=False, dxfattribs={"layer": "DARTS"})
    for cut in pattern.cuts:
        msp.add_line(cut.start, cut.end, dxfattribs={"layer": "CUTS"})
    for label in pattern.drawn_labels:
        for (x, y), line in zip(_label_line_centres(label), label.lines, strict=True):
            text = msp.add_text(line, height=label.text_height_mm, dxfattribs={"layer": "LABELS"})
            text.set_placement((x, y), align=TextEntityAlignment.MIDDLE_CENTER)
    with atomic_path(path) as tmp:
        doc.saveas(tmp)


def write_cut_pattern_svg(pattern: CutPattern, path: str | os.PathLike[str]) -> None:
    """SVG at 1:1 (mm; y negated so it looks as the DXF): the outline filled, the allowance
    dashed, cells past locking shaded red (``id="past-locking"``), fibre marks in blue (u)
    and red (v), darts (class ``dart``, a polyline) and cuts
    (class ``cut``, a line) in magenta, each piece's label as text."""
    from shapely.geometry import MultiPoint

    geoms: list[Any] = [
        g for g in (pattern.allowance, pattern.outline) if g is not None and not g.is_empty
    ]
    geoms += [MultiPoint(_dart_polyline(d)) for d in pattern.darts]
    geoms += [MultiPoint([c.start, c.end]) for c in pattern.cuts]
    margin = 5.0
    if geoms:
        bounds = np.array([g.bounds for g in geoms])
        x0, y0 = bounds[:, 0].min(), bounds[:, 1].min()
        x1, y1 = bounds[:, 2].max(), bounds[:, 3].max()
    else:
        x0 = y0 = x1 = y1 = 0.0
    width, height = x1 - x0 + 2 * margin, y1 - y0 + 2 * margin
    stroke = max(0.1, 0.05 * pattern.node_spacing_mm)

    def path_d(geom: MultiPolygon | None) -> str:
        parts = []
        for _, _, pts in _rings(geom):
            parts.append("M " + " L ".join(f"{x:.4f},{-y:.4f}" for x, y in pts.tolist()) + " Z")
        return " ".join(parts)

    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.4f}mm" height="{height:.4f}mm" '
        f'viewBox="{x0 - margin:.4f} {-y1 - margin:.4f} {width:.4f} {height:.4f}">',
        f"  <title>{escape(pattern.label)}</title>",
    ]
    if pattern.allowance is not None:
        lines.append(
            f'  <path id="allowance" d="{path_d(pattern.allowance)}" fill="none" '
            f'stroke="#666666" stroke-dasharray="{4 * stroke:.3f}" stroke-width="{stroke:.4f}"/>'
        )
    lines.append(
        f'  <path id="outline" d="{path_d(pattern.outline)}" fill="#d9e6f2" '
        f'fill-rule="evenodd" stroke="#1f3b57" stroke-width="{stroke:.4f}"/>'
    )
    if pattern.past_locking is not None and not pattern.past_locking.is_empty:
        lines.append(
            f'  <path id="past-locking" d="{path_d(pattern.past_locking)}" fill="#f2b8b0" '
            f'fill-rule="evenodd" stroke="#c0392b" stroke-width="{stroke:.4f}"/>'
        )
    for mark in pattern.marks:
        colour = "#1f3b73" if mark.family == "u" else "#9a2a1f"
        (ax, ay), (bx, by) = mark.start, mark.end
        lines.append(
            f'  <line class="fibre-{mark.family}" x1="{ax:.4f}" y1="{-ay:.4f}" x2="{bx:.4f}" '
            f'y2="{-by:.4f}" stroke="{colour}" stroke-width="{stroke:.4f}"/>'
        )
    for dart in pattern.darts:
        pts = " ".join(f"{x:.4f},{-y:.4f}" for x, y in _dart_polyline(dart))
        lines.append(
            f'  <polyline class="dart" points="{pts}" fill="none" stroke="#b0179a" '
            f'stroke-width="{2 * stroke:.4f}"/>'
        )
    for cut in pattern.cuts:
        (ax, ay), (bx, by) = cut.start, cut.end
        lines.append(
            f'  <line class="cut" x1="{ax:.4f}" y1="{-ay:.4f}" x2="{bx:.4f}" y2="{-by:.4f}" '
            f'stroke="#b0179a" stroke-width="{2 * stroke:.4f}"/>'
        )
    for label in pattern.drawn_labels:
        for (lx, ly), line in zip(_label_line_centres(label), label.lines, strict=True):
            lines.append(
                f'  <text class="label" data-piece="{label.piece}" x="{lx:.4f}" y="{-ly:.4f}" '
                f'font-size="{label.text_height_mm:.3f}" text-anchor="middle" '
                f'dominant-baseline="central">{escape(line)}</text>'
            )
    lines.append("</svg>")
    with atomic_open(path, "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines) + "\n")
