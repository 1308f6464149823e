"""The general woven unit cell: levels, weaving matrix and tow types (PHYSICS §1.1, §1.3).

Conventions (SI lengths and areas, m and m²; linear density in tex = g/km):

- x runs along the warp (machine direction), y along the weft. Warp-wise tow ``i`` lies at
  y = (i + ½)·s_warp, weft-wise tow ``j`` at x = (j + ½)·s_weft, where ``s_warp`` is the
  centre-to-centre distance between neighbouring warp-wise tows and ``s_weft`` likewise.
- Levels are numbered warp first (1..L_wp), then weft (L_wp+1..L_wp+L_wt). At every warp
  position ``i`` there is one warp-wise tow per warp-wise level, and at every weft position ``j``
  one weft-wise tow per weft-wise level, so a crossover column (i, j) is met by every level
  exactly once: entry ``matrix[i][j]`` must list every level id exactly once, bottom to top.
- Binder tows (3D weaves) are warp-wise levels flagged in ``binder_levels``; the other warp-wise
  levels of a 3D weave are stuffers.
- Out-of-plane coordinate: the non-binder tows of a column are stacked in matrix order, each
  taking its own height, and the stack is centred on z = 0. A binder does not open the stack
  (the integer-level model has no room for it): it is drawn on the interface between the tows
  below and above it, or just outside the stack at the top or bottom. This keeps stuffers of an
  orthogonal weave straight, as they are in the real fabric.
- Tow cross-section: elliptical, area (π/4)·w·h (a true lenticular section would be (2/3)·w·h).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from itertools import pairwise
from typing import TYPE_CHECKING, Literal, NamedTuple, cast

from preform.geometry.fibres import Fibre, fibre_area_m2
from preform.plugins.woven.tow_jamming import TowCompaction

if TYPE_CHECKING:  # numpy is imported where a method computes: a listing needs none
    # nor the generic cell or the crossover summary, built only for a run or a law
    from preform.geometry.unit_cell import FloatArray, UnitCell
    from preform.plugins.woven.crossover import CrossoverGeometry

    #: A tow height [m]: one value, or an array of them over shear angles.
    Height = float | FloatArray

#: Where a problem is, as a path in the weave description, e.g. ("weave", "matrix", 2, 0).
IssueLocation = tuple[str | int, ...]
Family = Literal["warp", "weft"]


@dataclass(frozen=True)
class TowType:
    """One kind of tow: fibre, linear density and cross-section (SI units)."""

    name: str
    fibre: Fibre
    #: Linear density [tex = g/km].
    linear_density_tex: float
    #: Cross-section width [m], in the fabric plane.
    width: float
    #: Cross-section height [m].
    height: float
    #: How the tow compacts laterally (``preform.plugins.woven.tow_jamming``): one model for
    #: the sheared cell and the shear law.
    compaction: TowCompaction = field(default_factory=TowCompaction)

    @property
    def fibre_area(self) -> float:
        """Cross-sectional area of fibre in the tow [m²]."""
        return fibre_area_m2(self.linear_density_tex, self.fibre.density_g_cm3)

    @property
    def section_area(self) -> float:
        """Elliptical cross-section area (π/4)·w·h of the tow [m²]."""
        return math.pi / 4.0 * self.width * self.height

    @property
    def volume_fraction(self) -> float:
        """Fibre volume fraction inside the tow [-]: fibre area over section area."""
        return self.fibre_area / self.section_area


# Records without cached properties or dataclasses.replace callers are named tuples: immutable
# and compared by value as frozen dataclasses are, but creating a dataclass execs its generated
# methods, which every start-up pays (`materials list` validates the library; issue 15l).
class WeaveDescription(NamedTuple):
    """Levels and weaving matrix of a woven repeat (paper Fig. 1, 2); no dimensions.

    ``matrix[i][j]`` lists the level ids met at crossover column (warp position i, weft
    position j), bottom to top; see the module docstring for what a valid entry is.
    """

    #: Number of warp-wise levels L_wp (stuffers and binders).
    warp_levels: int
    #: Number of weft-wise levels L_wt.
    weft_levels: int
    #: Warp-wise tows in the repeat, RC_wp.
    repeat_warp: int
    #: Weft-wise tows in the repeat, RC_wt.
    repeat_weft: int
    matrix: tuple[tuple[tuple[int, ...], ...], ...]
    #: Warp-wise level ids whose tows are binders (3D weaves only).
    binder_levels: tuple[int, ...] = ()

    @property
    def level_count(self) -> int:
        """Total number of levels L_wp + L_wt."""
        return self.warp_levels + self.weft_levels

    @property
    def is_3d(self) -> bool:
        """True for more than two levels in total (paper: a 3D woven textile)."""
        return self.level_count > 2

    def family(self, level: int) -> Family:
        """Which direction the tows of a level run: "warp" for 1..L_wp, else "weft"."""
        return "warp" if level <= self.warp_levels else "weft"

    def structural_errors(self) -> list[tuple[IssueLocation, str]]:
        """Problems that make the matrix meaningless (sizes, unknown or missing level ids)."""
        errors: list[tuple[IssueLocation, str]] = []
        if self.warp_levels < 1 or self.weft_levels < 1:
            errors.append(
                (("weave",), "a weave needs at least one warp-wise and one weft-wise level")
            )
            return errors
        if len(self.matrix) != self.repeat_warp:
            errors.append(
                (
                    ("weave", "matrix"),
                    f"the weaving matrix has {len(self.matrix)} rows but the repeat has "
                    f"{self.repeat_warp} warp-wise tows (one row per warp-wise tow)",
                )
            )
        for i, row in enumerate(self.matrix):
            if len(row) != self.repeat_weft:
                errors.append(
                    (
                        ("weave", "matrix", i),
                        f"row {i} has {len(row)} entries but the repeat has "
                        f"{self.repeat_weft} weft-wise tows (one entry per weft-wise tow)",
                    )
                )
        all_levels = set(range(1, self.level_count + 1))
        for n, level in enumerate(self.binder_levels):
            if level not in range(1, self.warp_levels + 1):
                errors.append(
                    (
                        ("weave", "binder_levels", n),
                        f"binder level {level} is not a warp-wise level "
                        f"(warp-wise levels are 1..{self.warp_levels})",
                    )
                )
        if self.binder_levels and not self.is_3d:
            errors.append((("weave", "binder_levels"), "binder levels need a 3D weave"))
        for i, row in enumerate(self.matrix):
            for j, entry in enumerate(row):
                where: IssueLocation = ("weave", "matrix", i, j)
                unknown = sorted(set(entry) - all_levels)
                if unknown:
                    errors.append(
                        (
                            where,
                            f"level id(s) {unknown} do not exist: levels are "
                            f"1..{self.level_count} (warp-wise 1..{self.warp_levels}, "
                            f"weft-wise {self.warp_levels + 1}..{self.level_count})",
                        )
                    )
                missing = sorted(all_levels - set(entry))
                if missing:
                    errors.append(
                        (
                            where,
                            f"crossover ({i}, {j}) misses level(s) {missing}: every "
                            "warp-wise and weft-wise level passes every crossover, so each "
                            "entry lists every level id once, bottom to top",
                        )
                    )
                repeated = sorted(k for k, c in Counter(entry).items() if c > 1)
                if repeated:
                    errors.append(
                        (where, f"crossover ({i}, {j}) lists level(s) {repeated} more than once")
                    )
        return errors


class TowKey(NamedTuple):
    """Identifies one tow of the repeat: its family, position in the repeat and level id."""

    family: Family
    position: int
    level: int


class Crossover(NamedTuple):
    """One warp-wise tow crossing one weft-wise tow at column (warp_position, weft_position)."""

    warp_position: int
    weft_position: int
    warp_level: int
    weft_level: int
    #: True when the warp-wise tow lies above the weft-wise tow.
    warp_over: bool


@dataclass(frozen=True)
class WovenUnitCell:
    """A woven repeat with dimensions: the description plus spacings and tow types (SI).

    ``warp_tow_types[k][i]`` is the type of the warp-wise tow of level k+1 at position i;
    ``weft_tow_types[k][j]`` the type of the weft-wise tow of level L_wp+k+1 at position j.
    Nothing is validated on construction so that :meth:`issues` can report every problem;
    geometric results raise ``ValueError`` if the description has errors.
    """

    weave: WeaveDescription
    #: Centre-to-centre distance between neighbouring warp-wise tows [m].
    tow_spacing_warp: float
    #: Centre-to-centre distance between neighbouring weft-wise tows [m].
    tow_spacing_weft: float
    warp_tow_types: tuple[tuple[TowType, ...], ...]
    weft_tow_types: tuple[tuple[TowType, ...], ...]
    labels: dict[str, object] = field(default_factory=dict)

    # -- checks ---------------------------------------------------------------------------
    def errors(self) -> list[tuple[IssueLocation, str]]:
        """Every error of the description, each with the path of the field to blame."""
        errors = self.weave.structural_errors() + self._tow_type_shape_errors()
        if errors:
            return errors
        for family, spacing in (("warp", self.tow_spacing_warp), ("weft", self.tow_spacing_weft)):
            if spacing <= 0:
                errors.append(((family, "tow_spacing"), f"{family}-wise tow spacing must be > 0"))
        errors += self._binding_errors()
        return errors

    def warnings(self) -> list[tuple[IssueLocation, str]]:
        """Suspicious but usable features: tows at least as wide as their spacing."""
        if self.weave.structural_errors() or self._tow_type_shape_errors():
            return []
        found: list[tuple[IssueLocation, str]] = []
        for family, spacing, types in (
            ("warp", self.tow_spacing_warp, self.warp_tow_types),
            ("weft", self.tow_spacing_weft, self.weft_tow_types),
        ):
            for k, level_types in enumerate(types):
                for i, tow_type in enumerate(level_types):
                    if tow_type.width >= spacing:
                        found.append(
                            (
                                (family, "tow_types", k, i),
                                f"{family}-wise tow type {tow_type.name!r} is "
                                f"{tow_type.width * 1e3:g} mm wide but the {family}-wise tows "
                                f"are {spacing * 1e3:g} mm apart: the tows already touch, so "
                                "the fabric is locked before shearing (locking angle 0°)",
                            )
                        )
        return found

    def _tow_type_shape_errors(self) -> list[tuple[IssueLocation, str]]:
        errors: list[tuple[IssueLocation, str]] = []
        for family, types, levels, repeat in (
            ("warp", self.warp_tow_types, self.weave.warp_levels, self.weave.repeat_warp),
            ("weft", self.weft_tow_types, self.weave.weft_levels, self.weave.repeat_weft),
        ):
            if len(types) != levels:
                errors.append(
                    (
                        (family, "tow_types"),
                        f"{len(types)} {family}-wise tow type level(s) given for "
                        f"{levels} {family}-wise level(s)",
                    )
                )
                continue
            for k, level_types in enumerate(types):
                if len(level_types) != repeat:
                    errors.append(
                        (
                            (family, "tow_types", k),
                            f"{len(level_types)} tow type(s) given for {repeat} "
                            f"{family}-wise tows in the repeat",
                        )
                    )
        return errors

    def _binding_errors(self) -> list[tuple[IssueLocation, str]]:
        """Tows that do not interlace and 3D levels that no binder holds."""
        weave = self.weave
        errors: list[tuple[IssueLocation, str]] = []
        sides = self._sides
        if not weave.is_3d:
            for i in range(weave.repeat_warp):
                key = TowKey("warp", i, 1)
                if self._interlacing_count(sides[key]) == 0:
                    over = bool(sides[key][0])
                    errors.append(
                        (
                            ("weave", "matrix", i),
                            f"warp tow {i} floats {'over' if over else 'under'} the whole "
                            f"repeat ({'over' if over else 'under'} all {weave.repeat_weft} "
                            "weft tows): the fabric would not hold together",
                        )
                    )
            for j in range(weave.repeat_weft):
                key = TowKey("weft", j, 2)
                if self._interlacing_count(sides[key]) == 0:
                    errors.append(
                        (
                            ("weave", "matrix"),
                            f"weft tow {j} (column {j} of the matrix) never interlaces: it "
                            f"lies on the same side of all {weave.repeat_warp} warp tows",
                        )
                    )
            return errors
        for level in sorted(weave.binder_levels):
            for i in range(weave.repeat_warp):
                if self._interlacing_count(sides[TowKey("warp", i, level)]) == 0:
                    errors.append(
                        (
                            ("weave", "matrix", i),
                            f"binder (level {level}) at warp position {i} never interlaces: "
                            "it stays on the same side of every weft tow",
                        )
                    )
        for level in range(1, weave.level_count + 1):
            if level in weave.binder_levels:
                continue
            if not any(self._binder_holds(b, level) for b in weave.binder_levels):
                errors.append(
                    (
                        ("weave", "binder_levels"),
                        f"no binder holds level {level} ({weave.family(level)}-wise): a 3D "
                        "level needs a binder that passes above it somewhere in the repeat "
                        "and below it somewhere else",
                    )
                )
        return errors

    def _binder_holds(self, binder: int, level: int) -> bool:
        above = below = False
        for row in self.weave.matrix:
            for entry in row:
                if entry.index(binder) > entry.index(level):
                    above = True
                else:
                    below = True
        return above and below

    @cached_property
    def _error_listing(self) -> str:
        return "; ".join(f"{'.'.join(map(str, loc))}: {msg}" for loc, msg in self.errors())

    def _require_valid(self) -> None:
        if self._error_listing:
            raise ValueError(f"invalid woven unit cell: {self._error_listing}")

    # -- topology -------------------------------------------------------------------------
    def tow_keys(self) -> list[TowKey]:
        """Every tow of the repeat: warp-wise (level, position) then weft-wise."""
        weave = self.weave
        keys = [
            TowKey("warp", i, level)
            for level in range(1, weave.warp_levels + 1)
            for i in range(weave.repeat_warp)
        ]
        keys += [
            TowKey("weft", j, level)
            for level in range(weave.warp_levels + 1, weave.level_count + 1)
            for j in range(weave.repeat_weft)
        ]
        return keys

    def tow_type(self, key: TowKey) -> TowType:
        """Type of one tow."""
        if key.family == "warp":
            return self.warp_tow_types[key.level - 1][key.position]
        return self.weft_tow_types[key.level - self.weave.warp_levels - 1][key.position]

    def tow_type_at(self, family: str, level_index: int, position: int) -> TowType:
        """Type of the tow at ``position`` on the family's ``level_index``-th level (0-based)."""
        types = self.warp_tow_types if family == "warp" else self.weft_tow_types
        return types[level_index][position]

    def _columns_along(self, key: TowKey) -> list[tuple[int, int]]:
        """The crossover columns a tow passes, in order along it."""
        if key.family == "warp":
            return [(key.position, j) for j in range(self.weave.repeat_weft)]
        return [(i, key.position) for i in range(self.weave.repeat_warp)]

    @cached_property
    def _sides(self) -> dict[TowKey, list[frozenset[int]]]:
        """Per tow, per crossover along it: the other family's level ids below the tow.

        A tow changes side between two neighbouring crossovers when this set changes.
        """
        weave = self.weave
        sides: dict[TowKey, list[frozenset[int]]] = {}
        for key in self.tow_keys():
            along: list[frozenset[int]] = []
            for i, j in self._columns_along(key):
                entry = weave.matrix[i][j]
                below = entry[: entry.index(key.level)]
                along.append(frozenset(lv for lv in below if weave.family(lv) != key.family))
            sides[key] = along
        return sides

    @staticmethod
    def _interlacing_count(along: list[frozenset[int]]) -> int:
        n = len(along)
        return sum(along[k] != along[(k + 1) % n] for k in range(n)) if n > 1 else 0

    def contacts(self) -> list[Crossover]:
        """Crossovers where the two tows touch: neighbours in the column's stack."""
        self._require_valid()
        weave = self.weave
        found: list[Crossover] = []
        for i, row in enumerate(weave.matrix):
            for j, entry in enumerate(row):
                for lower, upper in pairwise(entry):
                    if weave.family(lower) == weave.family(upper):
                        continue
                    warp_level, weft_level = (
                        (lower, upper) if weave.family(lower) == "warp" else (upper, lower)
                    )
                    found.append(Crossover(i, j, warp_level, weft_level, upper == warp_level))
        return found

    def interlacings(self) -> dict[TowKey, int]:
        """Interlacings per repeat of each tow (changes of side between neighbouring
        crossovers, counted cyclically along the tow)."""
        self._require_valid()
        return {key: self._interlacing_count(along) for key, along in self._sides.items()}

    def interlaced_shares(self) -> dict[tuple[Family, str], float]:
        """Per (family, tow type name): the share s ∈ [0, 1] of the tows' crossings that are
        interlaced, Σ interlacings / Σ crossings over the tows of that family and type (1/F, F
        the mean float length; plain weave 1, 8HS ¼, a straight stuffer 0). The tow-jamming
        rule reads it (``preform.plugins.woven.tow_jamming``)."""
        self._require_valid()
        counts = self.interlacings()
        crossings: dict[tuple[Family, str], int] = {}
        changes: dict[tuple[Family, str], int] = {}
        for key, along in self._sides.items():
            name = (key.family, self.tow_type(key).name)
            crossings[name] = crossings.get(name, 0) + len(along)
            changes[name] = changes.get(name, 0) + counts[key]
        return {name: min(1.0, changes[name] / crossings[name]) for name in crossings}

    def float_lengths(self) -> dict[TowKey, tuple[int, ...]]:
        """Float lengths of each tow [crossovers]: runs of neighbouring crossovers on the same
        side, cyclic over the repeat; a tow that never interlaces floats the whole repeat."""
        self._require_valid()
        floats: dict[TowKey, tuple[int, ...]] = {}
        for key, along in self._sides.items():
            n = len(along)
            changes = [k for k in range(n) if along[k] != along[(k + 1) % n]]
            if not changes:
                floats[key] = (n,)
                continue
            floats[key] = tuple(
                (changes[(m + 1) % len(changes)] - changes[m]) % n or n for m in range(len(changes))
            )
        return floats

    # -- paths ----------------------------------------------------------------------------
    @property
    def period(self) -> FloatArray:
        """Repeat vectors [m]: a1 along the warp (x), a2 along the weft (y)."""
        import numpy as np

        return np.array(
            [
                [self.weave.repeat_weft * self.tow_spacing_weft, 0.0],
                [0.0, self.weave.repeat_warp * self.tow_spacing_warp],
            ]
        )

    @property
    def area(self) -> float:
        """Area of the repeat [m²]."""
        return (
            self.weave.repeat_weft
            * self.tow_spacing_weft
            * self.weave.repeat_warp
            * self.tow_spacing_warp
        )

    @cached_property
    def _heights_z(self) -> dict[tuple[int, int, int], float]:
        """Centreline z [m] of each level at each column, keyed (i, j, level), as built."""
        return cast(
            dict[tuple[int, int, int], float],
            self.stack_z(lambda key: self.tow_type(key).height),
        )

    def stack_z(self, height: Callable[[TowKey], Height]) -> dict[tuple[int, int, int], Height]:
        """Centreline z [m] of each level at each column, keyed (i, j, level), with the tows'
        heights [m] given by ``height`` (a float, or an array over shear angles: every z is
        then an array of the same shape, one stack per angle in one pass)."""
        weave = self.weave
        z: dict[tuple[int, int, int], Height] = {}
        for i, row in enumerate(weave.matrix):
            for j, entry in enumerate(row):
                h = {lv: height(self._key_at(i, j, lv)) for lv in entry}
                stacked = [lv for lv in entry if lv not in weave.binder_levels]
                # Bottom edge of each stacked tow, the stack centred on z = 0.
                bottom = -sum(h[lv] for lv in stacked) / 2.0
                edge: dict[int, Height] = {}
                for lv in stacked:
                    edge[lv] = bottom
                    bottom = bottom + h[lv]  # never in place: edge[lv] may be this array
                top = bottom
                for k, lv in enumerate(entry):
                    if lv in edge:
                        z[(i, j, lv)] = edge[lv] + h[lv] / 2.0
                        continue
                    below = [b for b in entry[:k] if b in edge]
                    above = [a for a in entry[k + 1 :] if a in edge]
                    if not below:  # under the whole stack
                        z[(i, j, lv)] = edge[stacked[0]] - h[lv] / 2.0 if stacked else 0.0
                    elif not above:  # over the whole stack
                        z[(i, j, lv)] = top + h[lv] / 2.0
                    else:  # on the interface it passes through
                        z[(i, j, lv)] = edge[above[0]]
        return z

    def level_role(self, level: int) -> str:
        """What a level's tows are: "warp" or "weft" (2D), "stuffer", "binder" or "weft" (3D)."""
        if self.weave.family(level) == "weft":
            return "weft"
        if level in self.weave.binder_levels:
            return "binder"
        return "stuffer" if self.weave.is_3d else "warp"

    def _key_at(self, i: int, j: int, level: int) -> TowKey:
        if self.weave.family(level) == "warp":
            return TowKey("warp", i, level)
        return TowKey("weft", j, level)

    def tow_points(self, key: TowKey) -> FloatArray:
        """Centreline polyline of one tow over one period [m], (n, 3).

        Straight vectors between crossover points (the paper's tow-path vectors); the ends sit
        on the period boundary, halfway between the last and first crossover, so tiled cells
        join up.
        """
        import numpy as np

        self._require_valid()
        weave = self.weave
        columns = self._columns_along(key)
        zs = [self._heights_z[(i, j, key.level)] for i, j in columns]
        z_edge = (zs[0] + zs[-1]) / 2.0
        if key.family == "warp":
            pitch = self.tow_spacing_weft
            across = (key.position + 0.5) * self.tow_spacing_warp
            along_end = weave.repeat_weft * pitch
        else:
            pitch = self.tow_spacing_warp
            across = (key.position + 0.5) * self.tow_spacing_weft
            along_end = weave.repeat_warp * pitch
        along = [0.0, *((k + 0.5) * pitch for k in range(len(columns))), along_end]
        zz = [z_edge, *zs, z_edge]
        if key.family == "warp":
            pts = [(a, across, z) for a, z in zip(along, zz, strict=True)]
        else:
            pts = [(across, a, z) for a, z in zip(along, zz, strict=True)]
        return np.array(pts, dtype=float)

    def path_length(self, key: TowKey) -> float:
        """Length of one tow's centreline over one period [m]."""
        import numpy as np

        return float(np.linalg.norm(np.diff(self.tow_points(key), axis=0), axis=1).sum())

    def straight_length(self, key: TowKey) -> float:
        """Length of the period along the tow's direction [m] (its length without crimp)."""
        period = self.period
        return float(period[0, 0] if key.family == "warp" else period[1, 1])

    def to_unit_cell(self) -> UnitCell:
        """The generic :class:`UnitCell` (x along the warp, reference direction +45°)."""
        from preform.geometry.unit_cell import TowPath, UnitCell

        self._require_valid()
        tows = []
        for key in self.tow_keys():
            tow_type = self.tow_type(key)
            kind = (
                "binder"
                if key.level in self.weave.binder_levels
                else ("warp" if key.family == "warp" else "weft")
            )
            tows.append(
                TowPath(
                    points=self.tow_points(key),
                    width=tow_type.width,
                    height=tow_type.height,
                    kind=kind,
                    level=key.level,
                    type_name=tow_type.name,
                    linear_density_tex=tow_type.linear_density_tex,
                )
            )
        levels = {lv: self.level_role(lv) for lv in range(1, self.weave.level_count + 1)}
        return UnitCell(
            period=self.period,
            tows=tuple(tows),
            reference_direction=math.pi / 4.0,
            labels={"architecture": "woven", "levels": levels, **self.labels},
        )

    # -- derived properties ---------------------------------------------------------------
    def family_keys(self, family: Family) -> list[TowKey]:
        """Tows of one family (warp-wise includes binders)."""
        return [k for k in self.tow_keys() if k.family == family]

    def areal_density(self, family: Family | None = None) -> float:
        """Areal mass [g/m²] from the path lengths (crimp included), of one family or all.

        Σ tex·L / A with tex in g/km and L, A in m, m²: the tex/spacing_mm·(1 + crimp) rule of
        PHYSICS §1.3 summed over the tows.
        """
        keys = self.tow_keys() if family is None else self.family_keys(family)
        grams = sum(self.tow_type(k).linear_density_tex * 1e-3 * self.path_length(k) for k in keys)
        return grams / self.area

    def crimp(self, family: Family) -> float:
        """Mean crimp of one family [-]: path length over straight length, minus one."""
        keys = self.family_keys(family)
        path = sum(self.path_length(k) for k in keys)
        straight = sum(self.straight_length(k) for k in keys)
        return path / straight - 1.0

    def thickness(self) -> float:
        """Fabric thickness [m]: envelope of the tow centrelines ± half their heights."""
        return float(self.stack_thickness(lambda key: self.tow_type(key).height))

    def stack_thickness(self, height: Callable[[TowKey], Height]) -> Height:
        """Envelope [m] of the tow centrelines ± half their heights, the tows' heights [m] given
        by ``height`` (floats, or arrays over shear angles: the envelope of each angle's stack,
        all angles in one pass; ``preform.plugins.woven.sheared_cell``)."""
        import numpy as np

        self._require_valid()
        z = self.stack_z(height)
        top: Height | None = None
        bottom: Height | None = None
        # The crossover points bound a tow's centreline: its two ends on the period boundary
        # sit halfway between its last and first crossover, never beyond them.
        for key in self.tow_keys():
            h = height(key)
            for i, j in self._columns_along(key):
                centre = z[(i, j, key.level)]
                up, down = centre + h / 2.0, centre - h / 2.0
                top = up if top is None else np.maximum(top, up)
                bottom = down if bottom is None else np.minimum(bottom, down)
        assert top is not None and bottom is not None  # a valid cell has tows
        return top - bottom

    def tow_volume_fraction(self, family: Family) -> float:
        """Fibre volume fraction inside the tows of one family [-], length-weighted."""
        keys = self.family_keys(family)
        fibre = sum(self.tow_type(k).fibre_area * self.path_length(k) for k in keys)
        section = sum(self.tow_type(k).section_area * self.path_length(k) for k in keys)
        return fibre / section

    def fibre_volume_fraction(self) -> float:
        """Fibre volume fraction of the fabric [-]: fibre volume over area × thickness."""
        fibre = sum(self.tow_type(k).fibre_area * self.path_length(k) for k in self.tow_keys())
        return float(fibre / (self.area * self.thickness()))

    def cover_factor(self) -> float:
        """Fraction of the plan area covered by tows [-] (tows as strips of their width; the
        widest tow at a position is the one seen from above)."""
        import numpy as np

        self._require_valid()
        gaps_warp = [
            max(
                0.0,
                1.0 - max(types[i].width for types in self.warp_tow_types) / self.tow_spacing_warp,
            )
            for i in range(self.weave.repeat_warp)
        ]
        gaps_weft = [
            max(
                0.0,
                1.0 - max(types[j].width for types in self.weft_tow_types) / self.tow_spacing_weft,
            )
            for j in range(self.weave.repeat_weft)
        ]
        open_area = float(np.mean(np.outer(gaps_warp, gaps_weft)))
        return 1.0 - open_area

    def locking_angle(self, family: Family) -> float:
        """Geometric locking angle of one family [rad]: acos(w/Ts), the shear angle at which
        neighbouring tows of a level touch (w the mean width of the two neighbours); the
        smallest over the family's levels; 0 when the tows already touch."""
        self._require_valid()
        if family == "warp":
            types, spacing = self.warp_tow_types, self.tow_spacing_warp
        else:
            types, spacing = self.weft_tow_types, self.tow_spacing_weft
        ratio = (
            max(
                (level_types[k].width + level_types[(k + 1) % len(level_types)].width) / 2.0
                for level_types in types
                for k in range(len(level_types))
            )
            / spacing
        )
        return 0.0 if ratio >= 1.0 else math.acos(ratio)

    def crossover_geometry(self) -> CrossoverGeometry:
        """Mean crossover description for the friction–compaction shear law (SI).

        Tow dimensions come from the warp-wise/weft-wise level pair that is most often in
        contact (neighbours in a column's stack; ties to the lowest level ids), i.e. the only
        pair of a 2D weave. ``crossovers_per_area`` counts every warp/weft contact of the stack,
        since each contributes friction; interlacings are summed over all tows of both
        families; mean floats are over the tows of the chosen pair's levels.
        """
        from preform.plugins.woven.crossover import CrossoverGeometry

        self._require_valid()
        weave = self.weave
        contacts = self.contacts()
        counts = Counter((c.warp_level, c.weft_level) for c in contacts)
        warp_level, weft_level = min(counts, key=lambda pair: (-counts[pair], pair))
        warp_types = self.warp_tow_types[warp_level - 1]
        weft_types = self.weft_tow_types[weft_level - weave.warp_levels - 1]
        interlacings = sum(self.interlacings().values())
        floats = self.float_lengths()
        shares = self.interlaced_shares()

        def mean(values: list[float]) -> float:
            return sum(values) / len(values)

        def mean_float(family: Family, level: int) -> float:
            runs = [
                run
                for k, v in floats.items()
                if k.family == family and k.level == level
                for run in v
            ]
            return mean([float(r) for r in runs])

        return CrossoverGeometry(
            tow_width_warp=mean([t.width for t in warp_types]),
            tow_width_weft=mean([t.width for t in weft_types]),
            tow_spacing_warp=self.tow_spacing_warp,
            tow_spacing_weft=self.tow_spacing_weft,
            tow_height_warp=mean([t.height for t in warp_types]),
            tow_height_weft=mean([t.height for t in weft_types]),
            fibre_area_warp=mean([t.fibre_area for t in warp_types]),
            fibre_area_weft=mean([t.fibre_area for t in weft_types]),
            fibre_modulus=mean([t.fibre.modulus_Pa for t in (*warp_types, *weft_types)]),
            crossovers_per_area=len(contacts) / self.area,
            interlacings_per_area=interlacings / self.area,
            mean_float_warp=mean_float("warp", warp_level),
            mean_float_weft=mean_float("weft", weft_level),
            levels=weave.level_count,
            # The one tow model: the level pair's first tow type's constants (hybrids of one
            # level share a fibre family in practice), its moduli and interlaced shares.
            compaction_warp=warp_types[0].compaction,
            compaction_weft=weft_types[0].compaction,
            fibre_modulus_warp=mean([t.fibre.modulus_Pa for t in warp_types]),
            fibre_modulus_weft=mean([t.fibre.modulus_Pa for t in weft_types]),
            interlaced_share_warp=mean([shares[("warp", t.name)] for t in warp_types]),
            interlaced_share_weft=mean([shares[("weft", t.name)] for t in weft_types]),
        )


def areal_density_g_m2(cell: UnitCell) -> float:
    """Areal mass of any unit cell [g/m²]: Σ tex·length / area over its paths."""
    return sum(t.linear_density_tex * 1e-3 * t.length() for t in cell.tows) / cell.area
