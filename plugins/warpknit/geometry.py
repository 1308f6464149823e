"""Geometric model of a warp-knitted (stitch-bonded, NCF) fabric (PHYSICS §1.2), SI units.

Coordinates: x is the machine (stitch, wale) direction, y runs across the needle bed, z is out of
plane with the technical face (where the loops lie) at z = 0. Tow orientations are measured from
x towards y. Needle gap g of a guide bar sits at y = g·D (D = needle distance), so needle n,
between gaps n and n + 1, sits at y = (n + ½)·D; course c is at x = c·l_s (l_s = stitch length).

Stack, face to back: the loops (overlaps) of every thread level, then the tow layers in their
order with the underlaps of thread level q laid just above the last tow layer that has a tow
naming q in the placement matrix (the level "of the first underlap found above" the tow, after
the paper). Thread levels are numbered from 1; their underlaps stack in that order. A tow whose
entry names no existing level (0 or more than L_thread) has nothing above it: it is drawn on top
of the stack and reported as not integrated.

Thread shape [C]: each loop goes down through the stack beside its needle, round the needle on
the face and back up; its two legs sit one thread diameter apart (one needle plus (k - 1)·D
apart for an overlap across k needles). The loop runs forward along x far enough that its length
from leaving the underlap plane to returning to it equals the overlap length. Underlaps are
straight on the back from one course's up-leg to the next course's down-leg.

Unit cell [C]: the stitching repeats every (courses in the sequence) × l_s along x and every
(1 + empty guides)·D across; the tow layers generally do not register with it, so the cell is
the smallest multiple of the stitch repeat (at most ``MAX_REPEATS`` each way) on which every
layer's tow lattice fits with its spacing within ``SPACING_TOLERANCE`` and its orientation
within ``ANGLE_TOLERANCE_DEG`` of the entry, and on which each layer's placement pattern repeats.
The fitted spacing and angle are what the cell draws; the entry's values give the nominal areal
density.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from itertools import pairwise
from math import gcd, lcm
from typing import TYPE_CHECKING, NamedTuple

from preform.geometry.fibres import fibre, fibre_area_m2
from preform.material import Location

from .lapping import LappingSequence

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    # (nor the generic cell: a listing fits the cell but never draws its paths)
    import numpy as np
    from numpy.typing import NDArray

    from preform.geometry.unit_cell import TowPath, UnitCell

    FloatArray = NDArray[np.float64]


INCH_M = 0.0254
#: Relative disagreement between gauge and needle distance tolerated (datasheet rounding).
GAUGE_TOLERANCE = 5e-3
MAX_REPEATS = 24
#: Most tow pieces (per layer) or thread repeats (per level) one unit cell may hold. The cell's
#: paths are built one by one, so a spacing many orders below the needle distance would
#: otherwise hang the build (and exhaust memory) instead of being reported.
MAX_PATHS_PER_CELL = 10_000
SPACING_TOLERANCE = 0.01
ANGLE_TOLERANCE_DEG = 0.5


def _isclose(a: float, b: float) -> bool:
    """``numpy.isclose(a, b, rtol=1e-9)`` for two numbers: |a − b| ≤ 1e-8 + 1e-9·|b|."""
    return abs(a - b) <= 1e-8 + 1e-9 * abs(b)


def polyline_length(points: list[tuple[float, float, float]]) -> float:
    """Length of a polyline [m] without numpy, the same float as
    ``np.linalg.norm(np.diff(points, axis=0), axis=1).sum()`` (numpy's order of operations:
    each segment's squares summed in order, the segments summed pairwise)."""
    segments = [
        math.sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0) + (z1 - z0) * (z1 - z0))
        for (x0, y0, z0), (x1, y1, z1) in pairwise(points)
    ]
    return _pairwise_sum(segments)


def _pairwise_sum(values: list[float]) -> float:
    """Σ values in numpy's order for float arrays: eight running sums over blocks of at most
    128 values, halves of longer runs summed separately (so a length computed here is the same
    float as before numpy left this module's checks)."""
    n = len(values)
    if n < 8:
        total = 0.0
        for v in values:
            total += v
        return total
    if n <= 128:
        sums = values[:8]
        full = n - n % 8
        for i in range(8, full, 8):
            sums = [s + v for s, v in zip(sums, values[i : i + 8], strict=True)]
        total = ((sums[0] + sums[1]) + (sums[2] + sums[3])) + (
            (sums[4] + sums[5]) + (sums[6] + sums[7])
        )
        for v in values[full:]:
            total += v
        return total
    half = n // 2
    half -= half % 8
    return _pairwise_sum(values[:half]) + _pairwise_sum(values[half:])


def needle_distance_from_gauge(gauge_needles_per_inch: float) -> float:
    """Needle distance D [m] of a machine of gauge E [needles per inch]: D = 25.4 mm / E."""
    return INCH_M / gauge_needles_per_inch


def thread_diameter(linear_density_tex: float, density_g_cm3: float) -> float:
    """Diameter [m] of a thread taken as a solid round section of its fibre area [C]."""
    return math.sqrt(4.0 * fibre_area_m2(linear_density_tex, density_g_cm3) / math.pi)


@dataclass(frozen=True)
class TowType:
    """Reinforcement tow: fibre name, linear density [tex], width and height [m]."""

    fibre: str
    linear_density_tex: float
    width: float
    height: float
    #: Filament diameter [m]; None: the fibre's typical value.
    filament_diameter: float | None = None

    @property
    def name(self) -> str:
        return f"{self.fibre} {self.linear_density_tex:g} tex"


@dataclass(frozen=True)
class TowLayer:
    """One non-interlacing layer of parallel tows (one of the L_tow levels)."""

    #: Tow direction [deg from the machine direction towards the cross direction].
    orientation_deg: float
    #: Centre-to-centre distance between neighbouring tows, normal to them [m].
    spacing: float
    tow: TowType
    #: Normal distance of tow 0's centreline from the cell origin [m].
    offset: float = 0.0

    @property
    def areal_density_g_m2(self) -> float:
        """Nominal areal mass of the layer [g/m²] = tex / spacing[mm] (PHYSICS §1.3)."""
        return self.tow.linear_density_tex / (self.spacing * 1e3)


# Records without cached properties or dataclasses.replace callers are named tuples: immutable
# and compared by value as frozen dataclasses are, but creating a dataclass execs its generated
# methods, which every start-up pays (`materials list` validates the library; issue 15l).
class ThreadLevel(NamedTuple):
    """One level of stitching threads, knitted by one guide bar (one of the L_thread levels)."""

    sequence: LappingSequence
    #: Thread length of one loop, from leaving the underlap plane to returning to it [m].
    overlap_length: float
    #: Course spacing along the machine direction [m].
    stitch_length: float
    linear_density_tex: float
    #: Needle distance D [m], or None to take it from the gauge.
    needle_distance: float | None = None
    #: Machine gauge E [needles per inch], or None to take it from the needle distance.
    gauge_needles_per_inch: float | None = None
    #: Empty guides between two loaded guides (0 = fully threaded).
    empty_guides: int = 0
    fibre: str = "polyester"

    @property
    def needle_pitch(self) -> float:
        """Needle distance D [m] from whichever of D and the gauge is given (D if both)."""
        if self.needle_distance is not None:
            return self.needle_distance
        if self.gauge_needles_per_inch is not None:
            return needle_distance_from_gauge(self.gauge_needles_per_inch)
        raise ValueError("a thread level needs a needle distance or a machine gauge")

    @property
    def thread_pitch(self) -> float:
        """Distance across the bed between neighbouring threads of the level [m]."""
        return (1 + self.empty_guides) * self.needle_pitch

    @property
    def repeat_length(self) -> float:
        """Length of one repeat of the sequence along the machine direction [m]."""
        return self.sequence.course_count * self.stitch_length

    @property
    def diameter(self) -> float:
        """Thread diameter [m] (``thread_diameter``)."""
        return thread_diameter(self.linear_density_tex, fibre(self.fibre).density_g_cm3)


class StitchPath(NamedTuple):
    """One thread of a level over one repeat of its sequence, starting at the cell origin."""

    #: Loop polylines, one per course, each (5, 3) [m]: top of down-leg, face, loop tip, face,
    #: top of up-leg.
    overlaps: tuple[FloatArray, ...]
    #: Underlap segments (courses, 2, 3) [m]: start and end of each course's underlap.
    underlaps: FloatArray
    #: The whole thread as one polyline [m], closing on the next repeat's first point.
    points: FloatArray

    @property
    def underlap_vectors(self) -> FloatArray:
        """In-plane underlap vectors (courses, 2) [m]."""
        import numpy as np

        return np.asarray(self.underlaps[:, 1, :2] - self.underlaps[:, 0, :2])


class FittedLayer(NamedTuple):
    """How one tow layer is drawn on the unit cell (see the module docstring)."""

    #: Tow lattice indices: the tow family's phase advances by -k_machine over the cell's
    #: machine-direction period and by k_cross over its cross period.
    k_machine: int
    k_cross: int
    spacing: float
    orientation_deg: float

    @property
    def tows_in_cell(self) -> int:
        """Distinct tows in one cell."""
        return gcd(abs(self.k_machine), abs(self.k_cross))


class CellFit(NamedTuple):
    """The unit cell: stitch-repeat multiples and the fitted tow layers."""

    stitch_repeat: tuple[float, float]
    repeats: tuple[int, int]
    layers: tuple[FittedLayer, ...]
    #: True when every layer meets the tolerances and its placement pattern repeats in the cell.
    within_tolerance: bool

    @property
    def size(self) -> tuple[float, float]:
        """Cell lengths along and across the machine direction [m]."""
        return (
            self.repeats[0] * self.stitch_repeat[0],
            self.repeats[1] * self.stitch_repeat[1],
        )


#: Worst-layer scores of two cells within this relative difference are the same score to
#: ``cell_fit`` when no cell fits (rounding, not geometry, separates them).
_SCORE_TIE = 1e-9

#: The candidate cells (m_x, m_y) stitch repeats, in the order ``cell_fit`` prefers them:
#: smallest area first, then fewest repeats along the stitch.
_CELLS_BY_AREA = sorted(
    ((m_x, m_y) for m_x in range(1, MAX_REPEATS + 1) for m_y in range(1, MAX_REPEATS + 1)),
    key=lambda cell: (cell[0] * cell[1], cell[0], cell[1]),
)


class _LayerLattice:
    """One tow layer drawn on candidate cells of m_x × m_y stitch repeats: the tow lattice
    indices nearest its spacing and angle, and how far from them the drawn tows are (a score
    ≤ 1 is within ``SPACING_TOLERANCE`` and ``ANGLE_TOLERANCE_DEG``)."""

    def __init__(self, layer: TowLayer, length: float, width: float, row_length: int) -> None:
        self.layer = layer
        self.row_length = row_length
        theta = math.radians(layer.orientation_deg)
        sin, cos = math.sin(theta), math.cos(theta)
        # The index along one axis depends on that axis's repeats only: (k, k / period) per m.
        self._along = [self._index(m * length, sin) for m in range(1, MAX_REPEATS + 1)]
        self._across = [self._index(m * width, cos) for m in range(1, MAX_REPEATS + 1)]

    def _index(self, period: float, direction: float) -> tuple[int, float]:
        k = float(round(period * direction / self.layer.spacing))  # half to even, as rint
        return int(k), k / period

    def _drawn(self, m_x: int, m_y: int) -> tuple[float, float]:
        """Spacing [m] and angle [deg] of the tows as drawn on the cell."""
        (_, u), (_, v) = self._along[m_x - 1], self._across[m_y - 1]
        q = math.hypot(u, v)
        return (1.0 / q if q > 0 else math.inf), math.degrees(math.atan2(u, v))

    def score(self, m_x: int, m_y: int) -> float:
        k_x, k_y = self._along[m_x - 1][0], self._across[m_y - 1][0]
        tows = gcd(abs(k_x), abs(k_y))
        if tows == 0 or tows % self.row_length != 0:  # the placement pattern must repeat
            return math.inf
        spacing, angle = self._drawn(m_x, m_y)
        d_angle = (angle - self.layer.orientation_deg + 90.0) % 180.0 - 90.0
        return max(
            abs(spacing / self.layer.spacing - 1.0) / SPACING_TOLERANCE,
            abs(d_angle) / ANGLE_TOLERANCE_DEG,
        )

    def fitted(self, m_x: int, m_y: int) -> FittedLayer:
        spacing, angle = self._drawn(m_x, m_y)
        return FittedLayer(
            k_machine=self._along[m_x - 1][0],
            k_cross=self._across[m_y - 1][0],
            spacing=spacing,
            orientation_deg=angle,
        )


@dataclass(frozen=True)
class WarpKnitGeometry:
    """A warp-knit fabric: tow layers, thread levels and the placement matrix (PHYSICS §1.2).

    ``placement[i]`` lists, for the tows of layer i in order across the cell, the thread level
    (from 1) of the first underlap above each tow; a shorter list repeats. None places every
    tow under thread level 1 (between the loops and the first underlaps).
    """

    tow_layers: tuple[TowLayer, ...]
    thread_levels: tuple[ThreadLevel, ...]
    placement: tuple[tuple[int, ...], ...] | None = None

    # -- placement --------------------------------------------------------------------------
    def placement_rows(self) -> tuple[tuple[int, ...], ...]:
        """The placement matrix with the default filled in, one row per tow layer."""
        if self.placement is None:
            return tuple((1,) for _ in self.tow_layers)
        return self.placement

    def placement_of(self, layer: int, tow: int) -> int:
        """Thread level of the first underlap above tow ``tow`` of layer ``layer`` (both 0-based)."""
        rows = self.placement_rows()
        row = rows[layer] if layer < len(rows) and rows[layer] else (0,)
        return row[tow % len(row)]

    def _is_level(self, level: int) -> bool:
        return 1 <= level <= len(self.thread_levels)

    # -- self-checks ------------------------------------------------------------------------
    def problems(self) -> list[tuple[Location, str]]:
        """Consistency errors, each with the entry field to blame (YAML field names)."""
        out: list[tuple[Location, str]] = []
        if not self.tow_layers:
            out.append((("tow_layers",), "a warp-knit needs at least one tow layer"))
        if not self.thread_levels:
            out.append((("threads",), "a warp-knit needs at least one thread level"))
            return out
        machine = self._machine_problems()
        out += machine
        out += self._placement_problems()
        if not any(len(loc) == 2 for loc, _ in machine):  # every level has a needle distance
            out += self._overlap_problems()
            out += self._size_problems()
        return out

    def _size_problems(self) -> list[tuple[Location, str]]:
        out: list[tuple[Location, str]] = []
        fit = self.cell_fit
        length, width = fit.size
        for i, fitted in enumerate(fit.layers):
            # A layer's tows cross the cell edges |k_machine| + |k_cross| times in all; each
            # crossing is one straight piece of the cell's tow paths.
            pieces = abs(fitted.k_machine) + abs(fitted.k_cross)
            if pieces > MAX_PATHS_PER_CELL:
                out.append(
                    (
                        ("tow_layers", i, "spacing_mm"),
                        f"this layer's tows run {pieces} times through one unit cell "
                        f"({length * 1e3:.4g} × {width * 1e3:.4g} mm), more than "
                        f"{MAX_PATHS_PER_CELL}: check the spacing against the stitch",
                    )
                )
        for k, level in enumerate(self.thread_levels):
            repeats = round(length / level.repeat_length) * round(width / level.thread_pitch)
            if repeats > MAX_PATHS_PER_CELL:
                out.append(
                    (
                        ("threads", k, "stitch_length_mm"),
                        f"{repeats} stitch repeats in one unit cell ({length * 1e3:.4g} × "
                        f"{width * 1e3:.4g} mm), more than {MAX_PATHS_PER_CELL}: check the "
                        "stitch length and gauge against the tow spacings",
                    )
                )
        return out

    def _machine_problems(self) -> list[tuple[Location, str]]:
        out: list[tuple[Location, str]] = []
        pitches: list[float | None] = []
        for k, level in enumerate(self.thread_levels):
            d, e = level.needle_distance, level.gauge_needles_per_inch
            if d is None and e is None:
                out.append(
                    (
                        ("threads", k),
                        "give the needle distance or the machine gauge (one is enough)",
                    )
                )
                pitches.append(None)
                continue
            if d is not None and e is not None:
                from_gauge = needle_distance_from_gauge(e)
                if abs(d - from_gauge) > GAUGE_TOLERANCE * from_gauge:
                    out.append(
                        (
                            ("threads", k, "gauge_needles_per_inch"),
                            f"gauge E{e:g} means a needle distance of {from_gauge * 1e3:.4g} mm "
                            f"(25.4 mm / E) but needle_distance_mm is {d * 1e3:.4g} mm",
                        )
                    )
            pitches.append(level.needle_pitch)
        first = self.thread_levels[0]
        for k, level in enumerate(self.thread_levels[1:], start=1):
            p0, pk = pitches[0], pitches[k]
            if p0 is not None and pk is not None and not _isclose(p0, pk):
                out.append(
                    (
                        ("threads", k, "needle_distance_mm"),
                        f"guide bars of one machine share its needles: thread level {k + 1} has "
                        f"a needle distance of {pk * 1e3:.4g} mm, level 1 has {p0 * 1e3:.4g} mm",
                    )
                )
            if not _isclose(level.stitch_length, first.stitch_length):
                out.append(
                    (
                        ("threads", k, "stitch_length_mm"),
                        f"all guide bars knit the same courses: thread level {k + 1} has a stitch "
                        f"length of {level.stitch_length * 1e3:.4g} mm, level 1 has "
                        f"{first.stitch_length * 1e3:.4g} mm",
                    )
                )
        return out

    def _placement_problems(self) -> list[tuple[Location, str]]:
        out: list[tuple[Location, str]] = []
        if self.placement is None:
            return out
        n_levels = len(self.thread_levels)
        if len(self.placement) != len(self.tow_layers):
            out.append(
                (
                    ("placement",),
                    f"the placement matrix has {len(self.placement)} rows but there are "
                    f"{len(self.tow_layers)} tow layers (one row per layer)",
                )
            )
            return out
        for i, row in enumerate(self.placement):
            if not row:
                out.append((("placement", i), "a placement row needs at least one entry"))
            for j, level in enumerate(row):
                if level == 0:
                    out.append(
                        (
                            ("placement", i, j),
                            f"tow {j + 1} of layer {i + 1} is not integrated: 0 puts it above "
                            "every underlap, so no stitch holds it from above",
                        )
                    )
                elif not self._is_level(level):
                    out.append(
                        (
                            ("placement", i, j),
                            f"tow {j + 1} of layer {i + 1} names thread level {level} but the "
                            f"fabric has {n_levels} (numbered from 1): the tow is not integrated",
                        )
                    )
        # Layers are stacked in order and underlaps in level order, so a tow can only name a
        # level at or above the highest level named by any layer below it.
        highest_below = 0
        for i, row in enumerate(self.placement):
            valid = [(lv, j) for j, lv in enumerate(row) if self._is_level(lv)]
            for level, j in valid:
                if level < highest_below:
                    out.append(
                        (
                            ("placement", i, j),
                            f"tow {j + 1} of layer {i + 1} names thread level {level}, but a "
                            f"lower tow layer lies under level {highest_below}; underlaps stack "
                            f"in level order, so level {level}'s underlaps pass below that layer "
                            "and this tow would lie outside them",
                        )
                    )
            highest_below = max([highest_below, *(lv for lv, _ in valid)])
        return out

    def _overlap_problems(self) -> list[tuple[Location, str]]:
        out: list[tuple[Location, str]] = []
        for k, level in enumerate(self.thread_levels):
            depth = self._leg_depth(k)
            widest = max(abs(c.overlap_shift) for c in level.sequence.courses)
            needed = 2.0 * depth + self._leg_separation(level, widest)
            if level.overlap_length < needed:
                out.append(
                    (
                        ("threads", k, "overlap_length_mm"),
                        f"a loop of {level.overlap_length * 1e3:.4g} mm cannot pass twice "
                        f"through the {depth * 1e3:.3g} mm between the face and this level's "
                        f"underlaps and round the needle: it needs at least {needed * 1e3:.3g} mm",
                    )
                )
        return out

    def warnings(self) -> list[tuple[Location, str]]:
        """Suspicious but valid features, each with the entry field to look at."""
        out: list[tuple[Location, str]] = []
        for k, level in enumerate(self.thread_levels):
            if any(abs(c.overlap_shift) > 1 for c in level.sequence.courses):
                out.append(
                    (
                        ("threads", k, "knitting_sequence"),
                        "an overlap wraps more than one needle; a guide normally laps one",
                    )
                )
        if self.problems():
            return out
        fit = self.cell_fit
        if not fit.within_tolerance:
            out.append(
                (
                    ("tow_layers",),
                    "the tow layers do not fit a unit cell of up to "
                    f"{MAX_REPEATS}x{MAX_REPEATS} stitch repeats within tolerance; the cell "
                    "draws them at the nearest spacing and angle it can",
                )
            )
        out += self._unheld_tows()
        return out

    def _unheld_tows(self) -> list[tuple[Location, str]]:
        """Tows parallel to the stitching that no thread of the level above crosses or pierces."""
        out: list[tuple[Location, str]] = []
        fit = self.cell_fit
        _, width = fit.size
        for i, (layer, fitted) in enumerate(zip(self.tow_layers, fit.layers, strict=True)):
            if fitted.k_machine != 0:
                continue  # the tows cross the wales, so every level's stitches cross them
            for j in range(fitted.tows_in_cell):
                level_no = self.placement_of(i, j)
                if not self._is_level(level_no):
                    continue
                level = self.thread_levels[level_no - 1]
                across = [y for _, y, _ in self._stitch_points(level_no - 1)]
                lo, hi = min(across), max(across)
                centre = (layer.offset + j * fitted.spacing) % width
                half = layer.tow.width / 2.0
                pitch = level.thread_pitch
                # Nearest thread copy below the tow's upper edge, and whether it reaches the tow.
                n = math.floor((centre + half - lo) / pitch)
                reaches = lo + n * pitch <= centre + half and hi + n * pitch >= centre - half
                if not reaches:
                    out.append(
                        (
                            ("tow_layers", i),
                            f"tow {j + 1} of layer {i + 1} runs between the wales of thread "
                            f"level {level_no}: no stitch crosses or pierces it",
                        )
                    )
        return out

    # -- stack ------------------------------------------------------------------------------
    @cached_property
    def _stack(self) -> tuple[tuple[float, ...], tuple[float, ...], float]:
        """Centre heights of tow layers and of each level's underlaps, and the loop height [m]."""
        loop_band = max(t.diameter for t in self.thread_levels)
        n_levels = len(self.thread_levels)
        lowest: list[int] = []
        for i in range(len(self.tow_layers)):
            named = [self.placement_of(i, j) for j in range(self._row_length(i))]
            valid = [lv for lv in named if self._is_level(lv)]
            lowest.append(min(valid) if valid else n_levels + 1)
        tow_z = [0.0] * len(self.tow_layers)
        underlap_z = [0.0] * n_levels
        z = loop_band
        placed = 0  # thread levels already laid
        for i, layer in enumerate(self.tow_layers):
            while placed < n_levels and placed + 1 < lowest[i]:
                underlap_z[placed] = z + self.thread_levels[placed].diameter / 2.0
                z += self.thread_levels[placed].diameter
                placed += 1
            tow_z[i] = z + layer.tow.height / 2.0
            z += layer.tow.height
        while placed < n_levels:
            underlap_z[placed] = z + self.thread_levels[placed].diameter / 2.0
            z += self.thread_levels[placed].diameter
            placed += 1
        return tuple(tow_z), tuple(underlap_z), loop_band / 2.0

    def _row_length(self, layer: int) -> int:
        rows = self.placement_rows()
        return max(1, len(rows[layer])) if layer < len(rows) else 1

    @property
    def thickness(self) -> float:
        """Stack height from the face to the top of the back [m]."""
        return float(self.stack_thickness([t.tow.height for t in self.tow_layers]))

    def stack_thickness(self, tow_heights: Sequence[float | FloatArray]) -> float | FloatArray:
        """Stack height [m] with the tow layers' heights [m] given in layer order (floats, or
        arrays over shear angles: every angle's stack in one pass, the sheared cell's table)."""
        loop_band = max(t.diameter for t in self.thread_levels)
        return loop_band + sum(tow_heights) + sum(t.diameter for t in self.thread_levels)

    def _leg_depth(self, k: int) -> float:
        _, underlap_z, loop_z = self._stack
        return underlap_z[k] - loop_z

    @staticmethod
    def _leg_separation(level: ThreadLevel, needles: int) -> float:
        return (needles - 1) * level.needle_pitch + level.diameter

    # -- stitching --------------------------------------------------------------------------
    def stitch_path(self, k: int) -> StitchPath:
        """The path of one thread of level k (0-based) over one repeat of its sequence [m]."""
        import numpy as np

        points = np.array(self._stitch_points(k), dtype=float)
        courses = len(self.thread_levels[k].sequence.courses)
        overlaps = tuple(points[5 * c : 5 * c + 5].copy() for c in range(courses))
        underlaps = np.array(
            [[points[5 * c + 4], points[5 * c + 5]] for c in range(courses)], dtype=float
        )
        return StitchPath(overlaps=overlaps, underlaps=underlaps, points=points)

    def _stitch_points(self, k: int) -> list[tuple[float, float, float]]:
        """``stitch_path(k).points`` as plain floats: the library's checks (listing the library)
        need the thread's extent and length, not numpy. Five points per course's loop (top of
        the down-leg, face, loop tip, face, top of the up-leg), then the first point again one
        repeat further on."""
        level = self.thread_levels[k]
        d_needle = level.needle_pitch
        _, underlap_z, loop_z = self._stack
        z_top = underlap_z[k]
        depth = z_top - loop_z
        points: list[tuple[float, float, float]] = []
        for c, course in enumerate(level.sequence.courses):
            a, b = course.overlap
            x = c * level.stitch_length
            centre = 0.5 * (a + b) * d_needle
            half_sep = self._leg_separation(level, abs(b - a)) / 2.0
            side = (a > b) - (a < b)  # the sign of a - b
            y_a = centre + side * half_sep
            y_b = centre + -side * half_sep
            half_arc = max(level.overlap_length / 2.0 - depth, half_sep)
            reach = math.sqrt(max(half_arc**2 - half_sep**2, 0.0))
            points += [
                (x, y_a, z_top),
                (x, y_a, loop_z),
                (x + reach, centre, loop_z),
                (x, y_b, loop_z),
                (x, y_b, z_top),
            ]
        x0, y0, z0 = points[0]
        points.append((x0 + level.repeat_length, y0, z0))
        return points

    def thread_length_per_repeat(self, k: int) -> float:
        """Length of one thread of level k over one repeat of its sequence [m]."""
        return polyline_length(self._stitch_points(k))

    def stitch_areal_density_g_m2(self, k: int) -> float:
        """Areal mass of thread level k [g/m²]: thread length per area × tex."""
        level = self.thread_levels[k]
        area = level.repeat_length * level.thread_pitch
        return level.linear_density_tex * 1e-3 * self.thread_length_per_repeat(k) / area

    def areal_density_g_m2(self) -> float:
        """Nominal areal mass of the fabric [g/m²]: tow layers plus stitch yarn."""
        tows = sum(t.areal_density_g_m2 for t in self.tow_layers)
        stitch = sum(self.stitch_areal_density_g_m2(k) for k in range(len(self.thread_levels)))
        return tows + stitch

    # -- unit cell --------------------------------------------------------------------------
    def stitch_repeat(self) -> tuple[float, float]:
        """Smallest cell on which every thread level repeats: along x and across [m]."""
        first = self.thread_levels[0]
        courses = lcm(*(t.sequence.course_count for t in self.thread_levels))
        guides = lcm(*(1 + t.empty_guides for t in self.thread_levels))
        return courses * first.stitch_length, guides * first.needle_pitch

    @cached_property
    def cell_fit(self) -> CellFit:
        """The unit cell the tow layers fit on (module docstring).

        Plain Python (the library's validation asks for it, and listing the library imports no
        numpy): the candidate cells are tried smallest area first, then fewest repeats along
        the stitch, and the first within tolerance is taken; when none is, the one whose worst
        layer scores least, the smallest sum over the layers deciding between equal ones."""
        length, width = self.stitch_repeat()
        layers = [
            _LayerLattice(layer, length, width, self._row_length(i))
            for i, layer in enumerate(self.tow_layers)
        ]

        def fits(m_x: int, m_y: int) -> bool:  # stops at the first layer that does not fit
            return all(lattice.score(m_x, m_y) <= 1.0 for lattice in layers)

        # Most fabrics fit one of the first cells: the scan stops there.
        chosen = next((cell for cell in _CELLS_BY_AREA if fits(*cell)), None)
        within = chosen is not None
        if chosen is None:
            # None fits: the smallest worst-layer score. Cells whose worst layer is the same
            # (to rounding: a layer's score often does not depend on the other axis's repeats)
            # are told apart by the sum over the layers, so that the other layers are drawn
            # as near their spacing and angle as they can be; then the first in (m_x, m_y)
            # order. Without the sum, the last bit of the rounding picked among them.
            chosen, best = (1, 1), (math.inf, math.inf)
            for m_x in range(1, MAX_REPEATS + 1):
                for m_y in range(1, MAX_REPEATS + 1):
                    scores = [lattice.score(m_x, m_y) for lattice in layers]
                    worst, total = max(scores, default=0.0), sum(scores)
                    if not math.isfinite(worst):
                        continue
                    tied = math.isclose(worst, best[0], rel_tol=_SCORE_TIE, abs_tol=0.0)
                    if (worst < best[0] and not tied) or (tied and total < best[1]):
                        chosen, best = (m_x, m_y), (worst, total)
        return CellFit(
            stitch_repeat=(length, width),
            repeats=chosen,
            layers=tuple(lattice.fitted(*chosen) for lattice in layers),
            within_tolerance=within,
        )

    def tow_paths(self) -> list[TowPath]:
        """Every tow of the cell as straight pieces wrapped into the cell [m]."""
        import numpy as np

        from preform.geometry.unit_cell import TowPath

        fit = self.cell_fit
        size = np.array(fit.size)
        tow_z, _, _ = self._stack
        top = self.thickness
        paths: list[TowPath] = []
        for i, (layer, fitted) in enumerate(zip(self.tow_layers, fit.layers, strict=True)):
            g = fitted.tows_in_cell
            if g == 0:
                continue
            along = np.array([fitted.k_cross * size[0], fitted.k_machine * size[1]]) / g
            normal = np.array([-along[1], along[0]]) / np.linalg.norm(along)
            for j in range(g):
                level = self.placement_of(i, j)
                z = tow_z[i] if self._is_level(level) else top + layer.tow.height / 2.0
                start = normal * (layer.offset + j * fitted.spacing)
                for p, q in _wrap_segment(start, start + along, size):
                    paths.append(
                        TowPath(
                            points=np.array([[*p, z], [*q, z]]),
                            width=layer.tow.width,
                            height=layer.tow.height,
                            kind="tow",
                            level=i + 1,
                            type_name=layer.tow.name,
                            linear_density_tex=layer.tow.linear_density_tex,
                        )
                    )
        return paths

    def thread_paths(self) -> list[TowPath]:
        """Every stitching thread of the cell, one polyline per thread and repeat [m]."""
        import numpy as np

        from preform.geometry.unit_cell import TowPath

        fit = self.cell_fit
        length, width = fit.size
        paths: list[TowPath] = []
        for k, level in enumerate(self.thread_levels):
            base = self.stitch_path(k).points
            along = round(length / level.repeat_length)
            across = round(width / level.thread_pitch)
            for r in range(along):
                for t in range(across):
                    shift = np.array([r * level.repeat_length, t * level.thread_pitch, 0.0])
                    paths.append(
                        TowPath(
                            points=base + shift,
                            width=level.diameter,
                            height=level.diameter,
                            kind="stitch",
                            level=len(self.tow_layers) + k + 1,
                            type_name=f"{level.fibre} {level.linear_density_tex:g} tex stitch",
                            linear_density_tex=level.linear_density_tex,
                        )
                    )
        return paths

    def unit_cell(self) -> UnitCell:
        """The repeating cell: tows (kind "tow", levels 1..L_tow) and threads (kind "stitch",
        levels L_tow + 1 ...); x is the stitch direction, the reference for signed shear."""
        import numpy as np

        from preform.geometry.unit_cell import UnitCell

        length, width = self.cell_fit.size
        levels: dict[int, str] = {}
        for i, layer in enumerate(self.tow_layers):
            levels[i + 1] = f"tow layer {i + 1}: {layer.orientation_deg:+g} deg {layer.tow.name}"
        for k, level in enumerate(self.thread_levels):
            levels[len(self.tow_layers) + k + 1] = (
                f"thread level {k + 1}: {level.sequence.describe()}"
            )
        return UnitCell(
            period=np.array([[length, 0.0], [0.0, width]]),
            tows=tuple(self.tow_paths() + self.thread_paths()),
            reference_direction=0.0,
            labels={"levels": levels, "stitch_direction_deg": 0.0},
        )


def cell_areal_density_g_m2(cell: UnitCell, kind: str | None = None) -> float:
    """Areal mass of a unit cell [g/m²]: Σ tex × path length / cell area, over paths of
    ``kind`` (all paths when None)."""
    grams = sum(
        t.linear_density_tex * 1e-3 * t.length()
        for t in cell.tows
        if kind is None or t.kind == kind
    )
    return grams / cell.area


def _wrap_segment(
    start: FloatArray, end: FloatArray, size: FloatArray
) -> list[tuple[FloatArray, FloatArray]]:
    """Split the segment start→end at the cell's edges and shift each piece into the cell."""
    import numpy as np

    delta = end - start
    cuts = {0.0, 1.0}
    for axis in range(2):
        if delta[axis] == 0.0:
            continue
        lo, hi = sorted((start[axis], end[axis]))
        for n in range(int(np.ceil(lo / size[axis])), int(np.floor(hi / size[axis])) + 1):
            s = (n * size[axis] - start[axis]) / delta[axis]
            if 0.0 < s < 1.0:
                cuts.add(float(s))
    params = sorted(cuts)
    pieces = []
    for s0, s1 in pairwise(params):
        if s1 - s0 < 1e-12:
            continue
        p, q = start + s0 * delta, start + s1 * delta
        shift = np.floor((p + q) / 2.0 / size) * size
        pieces.append((p - shift, q - shift))
    return pieces
