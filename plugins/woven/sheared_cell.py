"""The woven unit cell at a shear angle γ (issue 14; ``preform.geometry.sheared_cell``).

Each (family, tow type) pair is one tow family: its tows narrow past locking and compact up to
the weave's jamming fraction V_J (its own compaction constants and the share of its crossings
that are interlaced, ``WovenUnitCell.interlaced_shares``), then thicken
(``preform.plugins.woven.tow_jamming``: the one tow model the shear law uses too). The cell at γ is the
woven cell rebuilt with every tow's width and height at γ (so the crimp and the stack follow the
new heights; the thickness is the stack's envelope, ``WovenUnitCell.stack_thickness``), then
mapped in-plane by the pin-jointed stretch about the +45° bisector of warp and weft. SI units.

Only the tows' heights move the stack, so ``sheared_stack`` builds it for a whole grid of angles
in one pass, the heights arrays over γ (the preform's table over |γ|, issue 15); the cell at one
angle is that pass at one angle, and the rebuilt cell is drawn only when asked for.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from preform.geometry.sheared_cell import (
    ShearedCell,
    TowFamily,
    TowState,
    check_shear,
    pin_jointed_stretch,
    sheared_paths,
)
from preform.geometry.unit_cell import FloatArray, UnitCell
from preform.plugins.woven.geometry import Family, TowType, WovenUnitCell
from preform.plugins.woven.tow_jamming import TowCompaction, weave_jamming_fraction

#: Reference bisector of a woven cell [rad from the warp]: the cell's x axis is the warp.
REFERENCE = math.pi / 4.0


def tow_families(
    cell: WovenUnitCell, compaction: TowCompaction | None = None
) -> dict[tuple[Family, str], TowFamily]:
    """The cell's tow families, one per (family, tow type name), as built. ``compaction``
    replaces every tow's own compaction constants (``TowType.compaction``) when given."""
    found: dict[tuple[Family, str], TowFamily] = {}
    shares = cell.interlaced_shares()
    for key in cell.tow_keys():
        tow = cell.tow_type(key)
        name = (key.family, tow.name)
        if name in found:
            continue
        spacing = cell.tow_spacing_warp if key.family == "warp" else cell.tow_spacing_weft
        v0 = tow.volume_fraction
        try:
            v_jam = weave_jamming_fraction(
                v0, tow.fibre.modulus_Pa, compaction or tow.compaction, shares[name]
            )
        except ValueError as error:
            raise ValueError(f"tow_types.{tow.name} ({key.family}-wise): {error}") from None
        found[name] = TowFamily(
            name=f"{key.family} {tow.name}",
            spacing=spacing,
            width=tow.width,
            height=tow.height,
            fibre_area=tow.fibre_area,
            jamming_fraction=v_jam,
            filament_diameter=tow.fibre.filament_diameter_m,
            net_family=0 if key.family == "warp" else 1,
        )
    return found


@dataclass(frozen=True)
class ShearedStack:
    """The woven cell's tow families (as built) and, at shear angles γ, their states and the
    stack's thickness [m] (arrays shaped like γ)."""

    families: dict[tuple[Family, str], TowFamily]
    states: dict[tuple[Family, str], TowState]
    thickness: FloatArray


def sheared_stack(
    cell: WovenUnitCell, gamma: ArrayLike, compaction: TowCompaction | None = None
) -> ShearedStack:
    """The woven cell's stack at shear angle(s) ``gamma`` [rad] (both senses; |γ| ≤ 89°): every
    angle in one pass, the tows' heights arrays over γ (``WovenUnitCell.stack_thickness``).
    Only the heights move the stack: the widths narrow in the plane."""
    g = np.asarray(gamma, dtype=float)
    check_shear(g)
    families = tow_families(cell, compaction)
    states = {name: fam.state(g) for name, fam in families.items()}
    thickness = cell.stack_thickness(
        lambda key: states[(key.family, cell.tow_type(key).name)].height
    )
    return ShearedStack(families, states, np.asarray(thickness, dtype=float))


def sheared_woven_cell(
    cell: WovenUnitCell, gamma: float, compaction: TowCompaction | None = None
) -> ShearedCell:
    """The woven cell at shear angle ``gamma`` [rad] (both senses; |γ| ≤ 89°): the stack of
    ``sheared_stack`` at that one angle, and the cell it draws on demand."""
    stack = sheared_stack(cell, gamma, compaction)
    families, states = stack.families, stack.states

    def at_gamma(family: Family, tow: TowType) -> TowType:
        state = states[(family, tow.name)]
        return dataclasses.replace(tow, width=float(state.width), height=float(state.height))

    # Fibre volume: fibre area × fibre length, the length at γ = 0 (inextensible fibres).
    volumes = dict.fromkeys(families, 0.0)
    for key in cell.tow_keys():
        tow = cell.tow_type(key)
        volumes[(key.family, tow.name)] += tow.fibre_area * cell.path_length(key)
    total = sum(volumes.values())
    stretch = pin_jointed_stretch(gamma, REFERENCE)

    def draw() -> UnitCell:
        sheared = dataclasses.replace(
            cell,
            warp_tow_types=tuple(
                tuple(at_gamma("warp", t) for t in level) for level in cell.warp_tow_types
            ),
            weft_tow_types=tuple(
                tuple(at_gamma("weft", t) for t in level) for level in cell.weft_tow_types
            ),
        )
        return sheared_paths(sheared.to_unit_cell(), stretch)

    return ShearedCell(
        shear=float(gamma),
        area=cell.area * math.cos(gamma),
        thickness=float(stack.thickness),
        fibre_volume=total,
        families=tuple(families.values()),
        states=tuple(states[name] for name in families),
        family_shares=tuple(volumes[name] / total for name in families),
        draw=draw,
    )
