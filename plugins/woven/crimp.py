"""Which tow-path arcs wrap each crossover of a woven unit cell: the crimp data of the woven law.

A tow's path (``WovenUnitCell.tow_points``) passes the crossovers along it at the heights the
weaving matrix gives. Between two neighbouring crossovers it rises (or falls) by r over one
crossing pitch p; the law draws this segment as two tangent circular arcs (lenticular, the
paper's tow path), each turning by α = 2·atan(r/p). The arc next to a crossover wraps the crossing
tow there when it bends towards it: the tow lies above the crossing tow and the path falls away
from the crossover, or lies below and rises away. A crossover inside a float has no wrapping arc
(both neighbours level), one at a float's end has one, one where the tow changes side on both
sides (every crossover of a plain weave) has two. The tension T of the tow then presses on the
crossing tow with the resultant of its two ends, 2·T·sin(Σα/2) (``preform.plugins.woven.shear``).
"""

from __future__ import annotations

from dataclasses import replace

from preform.plugins.woven.crossover import CrossoverGeometry
from preform.plugins.woven.geometry import Family, TowKey, WovenUnitCell

#: Rises below this share of the tow's height are level (rounding of stacked heights).
LEVEL_TOLERANCE = 1e-9


def wrap_rises(cell: WovenUnitCell) -> tuple[tuple[tuple[float, ...], ...], ...]:
    """(warp rises, weft rises): per contact of ``cell.contacts()``, the rises [m] of the
    path segments of each of the two tows whose arcs wrap the crossing tow there."""
    contacts = cell.contacts()
    paths: dict[TowKey, list[float]] = {}

    def heights(key: TowKey) -> list[float]:
        if key not in paths:
            paths[key] = [float(z) for z in cell.tow_points(key)[1:-1, 2]]
        return paths[key]

    warp: list[tuple[float, ...]] = []
    weft: list[tuple[float, ...]] = []
    for c in contacts:
        sides: tuple[tuple[Family, int, int, bool, list[tuple[float, ...]]], ...] = (
            ("warp", c.warp_position, c.warp_level, c.warp_over, warp),
            ("weft", c.weft_position, c.weft_level, not c.warp_over, weft),
        )
        for family, position, level, over, out in sides:
            z = heights(TowKey(family, position, level))
            k = c.weft_position if family == "warp" else c.warp_position
            here, n = z[k], len(z)
            scale = cell.tow_type(TowKey(family, position, level)).height
            rises = []
            for neighbour in (z[(k - 1) % n], z[(k + 1) % n]):
                drop = here - neighbour if over else neighbour - here
                if drop > LEVEL_TOLERANCE * scale:
                    rises.append(drop)
            out.append(tuple(rises))
    return tuple(warp), tuple(weft)


def crossover_geometry_with_crimp(cell: WovenUnitCell) -> CrossoverGeometry:
    """The cell's ``CrossoverGeometry`` with its thickness and the wrapping rises of every
    contact, for the weave-derived friction–compaction law."""
    warp, weft = wrap_rises(cell)
    return replace(
        cell.crossover_geometry(),
        thickness=cell.thickness(),
        warp_wrap_rises=warp,
        weft_wrap_rises=weft,
    )
