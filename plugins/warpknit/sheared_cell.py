"""The warp-knit (NCF) unit cell at a shear angle γ (issue 14; ``preform.geometry.sheared_cell``).

Each tow layer is one tow family, at the spacing the cell was fitted with; its tows narrow past
locking and compact up to the jamming fraction, then thicken (the bundle law of
``preform.plugins.woven.tow_jamming``, shared with the woven cell). The cell at γ is the
geometry rebuilt with the layers' tows at their width and height at γ (the stack and so the
thickness follow the new heights), then mapped in-plane by the pin-jointed stretch about the
fabric's reference direction (``sheared_stack``: every angle of the preform's table in one pass,
the heights arrays over γ). The stitching threads are mapped with the fabric; their own
strain belongs to the stitch shear law, and they are not reinforcement, so no fraction here
counts them.

A pin-jointed net has two fibre families at ±45° to the reference bisector; a layer at another
angle would be stretched by the shear, which inextensible fibres cannot be, so such a cell is
refused (ValueError, in words). SI units.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import ArrayLike

from preform.geometry.fibres import fibre, fibre_area_m2
from preform.geometry.sheared_cell import (
    ShearedCell,
    TowFamily,
    TowState,
    check_shear,
    pin_jointed_stretch,
    sheared_paths,
)
from preform.geometry.unit_cell import FloatArray, UnitCell
from preform.plugins.warpknit.geometry import WarpKnitGeometry
from preform.plugins.woven.tow_jamming import TowCompaction, compaction_for, jamming_fraction

#: How far [deg] a layer may sit from reference ± 45° and still be one of the net's families.
FAMILY_TOLERANCE_DEG = 1e-6


def net_family_of(orientation_deg: float, reference_deg: float) -> int | None:
    """0 for a layer along reference − 45°, 1 along reference + 45° (mod 180°), else None."""
    for index, offset in ((0, -45.0), (1, 45.0)):
        off = (orientation_deg - reference_deg - offset + 90.0) % 180.0 - 90.0
        if abs(off) <= FAMILY_TOLERANCE_DEG:
            return index
    return None


def tow_families(
    geo: WarpKnitGeometry, reference_deg: float, compaction: TowCompaction | None = None
) -> list[TowFamily]:
    """One tow family per layer, as built, at the spacing the cell was fitted with."""
    families = []
    for i, (layer, fitted) in enumerate(zip(geo.tow_layers, geo.cell_fit.layers, strict=True)):
        family = net_family_of(layer.orientation_deg, reference_deg)
        if family is None:
            raise ValueError(
                f"tow layer {i + 1} at {layer.orientation_deg:g}° is not one of the two fibre "
                f"families of the drape net (at {reference_deg - 45:g}° and "
                f"{reference_deg + 45:g}°): the pin-jointed sheared cell cannot stretch its "
                "inextensible tows"
            )
        material = fibre(layer.tow.fibre)
        area = fibre_area_m2(layer.tow.linear_density_tex, material.density_g_cm3)
        v0 = area / (math.pi / 4.0 * layer.tow.width * layer.tow.height)
        try:
            # Stitched, not interlaced: every tow is held by the stitch at its own limit V_c.
            own = compaction or compaction_for(layer.tow.fibre)
            v_jam = jamming_fraction(v0, material.modulus_Pa, own)
        except ValueError as error:
            raise ValueError(f"tow_layers.{i}: {error}") from None
        families.append(
            TowFamily(
                name=f"layer {i + 1} {layer.orientation_deg:+g}°",
                spacing=fitted.spacing,
                width=layer.tow.width,
                height=layer.tow.height,
                fibre_area=area,
                jamming_fraction=v_jam,
                filament_diameter=layer.tow.filament_diameter or material.filament_diameter_m,
                net_family=family,
            )
        )
    return families


def sheared_stack(
    geo: WarpKnitGeometry,
    gamma: ArrayLike,
    reference_deg: float,
    compaction: TowCompaction | None = None,
) -> tuple[list[TowFamily], tuple[TowState, ...], FloatArray]:
    """The layers' tow families (as built), their states at shear angle(s) ``gamma`` [rad]
    about ``reference_deg`` [deg] and the stack's thickness [m] (arrays shaped like γ): every
    angle in one pass (``WarpKnitGeometry.stack_thickness``)."""
    g = np.asarray(gamma, dtype=float)
    check_shear(g)
    families = tow_families(geo, reference_deg, compaction)
    states = tuple(f.state(g) for f in families)
    thickness = geo.stack_thickness([s.height for s in states])
    return families, states, np.asarray(thickness, dtype=float)


def sheared_warp_knit_cell(
    geo: WarpKnitGeometry,
    gamma: float,
    reference_deg: float,
    compaction: TowCompaction | None = None,
) -> ShearedCell:
    """The warp-knit cell at shear angle ``gamma`` [rad] about ``reference_deg`` [deg]: the
    stack of ``sheared_stack`` at that one angle, and the cell it draws on demand."""
    families, states, thickness = sheared_stack(geo, gamma, reference_deg, compaction)
    # Fibre volume per period: each layer's tows fill the period's area at their spacing, so
    # fibre area × (area / spacing) is the layer's fibre area times its tow length per period.
    length, width = geo.cell_fit.size
    area0 = length * width
    volumes = [f.fibre_area * area0 / f.spacing for f in families]
    total = sum(volumes)
    stretch = pin_jointed_stretch(gamma, math.radians(reference_deg))

    def draw() -> UnitCell:
        layers = tuple(
            dataclasses.replace(
                layer,
                tow=dataclasses.replace(layer.tow, width=float(s.width), height=float(s.height)),
            )
            for layer, s in zip(geo.tow_layers, states, strict=True)
        )
        sheared = dataclasses.replace(geo, tow_layers=layers)
        cell = dataclasses.replace(
            sheared.unit_cell(), reference_direction=math.radians(reference_deg)
        )
        return sheared_paths(cell, stretch)

    return ShearedCell(
        shear=float(gamma),
        area=area0 * math.cos(gamma),
        thickness=float(thickness),
        fibre_volume=total,
        families=tuple(families),
        states=states,
        family_shares=tuple(v / total for v in volumes),
        draw=draw,
    )
