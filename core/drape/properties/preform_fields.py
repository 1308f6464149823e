"""The draped preform's properties per cell: thickness, fibre volume fraction, permeability.

Each valid cell of a drape takes its properties from the fabric's sheared unit cell at the
cell's shear (``FabricBase.sheared_cell``, ``preform.geometry.sheared_cell``): its thickness
and fabric fibre volume fraction, and from those an in-plane permeability tensor for liquid
moulding (``preform.geometry.permeability``: Gebart's fibre bed per fibre family, the families
as parallel layers) whose principal directions follow the cell's draped fibres. The cell's
thickness and fraction do not depend on the sense of shear, so they are tabulated once over
|γ| (``PreformResponse``, the locking and jamming angles on the grid) and read per cell by
linear interpolation. Past the table's end (89°: a pin-jointed cell has no area at 90°) the
values are held at the end and the cells are counted (``beyond_table``), never extrapolated.

The drape's u fibres are the cell's first family (warp; the layer at the reference direction
− 45°), v the second; the shares weight each family's Gebart bed by its fibre volume. SI units.

Only a scene asking for the ``permeability`` output computes this (``preform.drape.preform_steps``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.result import DrapeResult
from preform.geometry.permeability import Arrangement, fabric_permeability
from preform.geometry.sheared_cell import MAX_SHEAR, thickness_per_angle

#: Grid step of the table over |γ| [deg]; the locking and jamming angles are added to it.
TABLE_STEP_DEG = 0.25
#: Fibre arrangement of Gebart's constants [C]: hexagonal, whose closing fraction π/(2√3) is
#: above every fraction the sheared cell reaches (it stays below π/4).
ARRANGEMENT: Arrangement = "hexagonal"


@dataclass(frozen=True)
class PreformResponse:
    """A fabric's sheared-cell thickness and fraction over |γ| (SI)."""

    #: |γ| grid [rad], increasing, from 0 to ``MAX_SHEAR``.
    shear: FloatArray
    #: Fabric thickness [m] and fibre volume fraction [-] on the grid.
    thickness: FloatArray
    fibre_volume_fraction: FloatArray
    #: Fibre volume shares of the drape's u and v families [-].
    shares: tuple[float, float]
    #: Mean filament radius [m].
    filament_radius: float
    #: Smallest locking and jamming angles of the cell [rad].
    locking_angle: float
    jamming_angle: float

    @classmethod
    def from_fabric(cls, fabric: Any, step_deg: float = TABLE_STEP_DEG) -> PreformResponse | None:
        """Tabulate ``fabric.sheared_cell``; None when the architecture has no sheared cell.
        A cell that cannot be sheared raises its ValueError (in words)."""
        flat = fabric.sheared_cell(0.0)
        if flat is None:
            return None
        grid = np.radians(np.arange(0.0, math.degrees(MAX_SHEAR), step_deg))
        marks = [flat.locking_angle, flat.jamming_angle, MAX_SHEAR]
        grid = np.unique(np.concatenate([grid, [m for m in marks if 0.0 <= m <= MAX_SHEAR]]))
        # Before the first family locks no tow changes: the thickness is the flat cell's and
        # the fraction grows as 1/cos γ over the shrinking area (exact in the sheared cell),
        # so only the angles from locking on need the cell itself, all in one call (an
        # architecture without a vectorised stack builds one cell per angle).
        free = grid < flat.locking_angle
        locked = grid[~free]
        thickness_over = getattr(fabric, "sheared_thickness", None)
        if callable(thickness_over):
            sheared = thickness_over(locked)
        else:  # a fabric object that only has the per-angle cell
            sheared = thickness_per_angle(fabric.sheared_cell, locked)
        thickness = np.full(grid.shape, flat.thickness)
        fraction = flat.fibre_volume_fraction / np.cos(grid)
        thickness[~free] = sheared
        # the sheared cell's own fraction: fibre volume over (area₀ cos γ) × thickness
        fraction[~free] = flat.fibre_volume / (flat.area * np.cos(locked) * sheared)
        return cls(
            shear=grid,
            thickness=thickness,
            fibre_volume_fraction=fraction,
            shares=flat.net_family_shares(),
            filament_radius=flat.filament_radius,
            locking_angle=flat.locking_angle,
            jamming_angle=flat.jamming_angle,
        )

    def at(self, shear: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Thickness [m] and fibre fraction [-] at shear angles γ [rad] (either sign), held
        at the table's end beyond it."""
        g = np.abs(np.asarray(shear, dtype=float))
        return (
            np.interp(g, self.shear, self.thickness),
            np.interp(g, self.shear, self.fibre_volume_fraction),
        )


@dataclass(frozen=True)
class PreformField:
    """Per-cell properties of a draped preform, arrays of the net's cell shape (ni−1, nj−1);
    NaN where a cell is not VALID. SI units."""

    #: Thickness [m] and fabric fibre volume fraction [-].
    thickness: FloatArray
    fibre_volume_fraction: FloatArray
    #: In-plane permeability tensor [m²] in the tool's (x, y, z) axes, (..., 3, 3).
    permeability: FloatArray
    #: Principal in-plane permeabilities k1 ≥ k2 [m²], (..., 2).
    principal_permeability: FloatArray
    #: Unit direction of k1 (..., 3).
    principal_direction: FloatArray
    #: Cells past the sheared cell's jamming angle (the tows thicken).
    past_jamming: BoolArray
    #: Cells sheared beyond the table (|γ| > 89°): values held at 89°.
    beyond_table: BoolArray
    #: What the permeability is, in words (model, arrangement, filament radius).
    model: str


def preform_field(
    result: DrapeResult, response: PreformResponse, arrangement: Arrangement = ARRANGEMENT
) -> PreformField:
    """The per-cell properties of a drape (module docstring)."""
    valid = np.asarray(result.valid, dtype=bool)
    shear = np.where(valid, np.asarray(result.shear, dtype=float), 0.0)
    thickness, fraction = response.at(shear)
    u = np.asarray(result.fibre_u, dtype=float)
    v = np.asarray(result.fibre_v, dtype=float)
    normal = np.cross(u, v)
    length = np.linalg.norm(normal, axis=-1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    # the families' directions are unit where valid; give invalid cells a harmless frame
    u = np.where(valid[..., None], u, (1.0, 0.0, 0.0))
    v = np.where(valid[..., None], v, (0.0, 1.0, 0.0))
    normal = np.where(valid[..., None], normal, (0.0, 0.0, 1.0))
    k = fabric_permeability(
        fraction, (u, v), response.shares, normal, response.filament_radius, arrangement
    )
    values, vectors = np.linalg.eigh(k)  # ascending: the normal's 0 first, then k2, k1
    principal = values[..., [2, 1]]
    direction = vectors[..., :, 2]
    nan = np.where(valid, 1.0, np.nan)
    return PreformField(
        thickness=thickness * nan,
        fibre_volume_fraction=fraction * nan,
        permeability=k * nan[..., None, None],
        principal_permeability=principal * nan[..., None],
        principal_direction=direction * nan[..., None],
        past_jamming=valid & (np.abs(shear) > response.jamming_angle),
        beyond_table=valid & (np.abs(shear) > response.shear[-1]),
        model=(
            f"Gebart (1992) {arrangement} fibre bed per family at the sheared cell's fabric Vf, "
            f"families as parallel layers; filament radius {response.filament_radius * 1e6:g} µm"
        ),
    )


def preform_summary(result: DrapeResult, field: PreformField) -> dict[str, object]:
    """Ranges over the part's cells (every valid cell when none lies in the part), units in
    the keys: thickness [mm], fibre volume fraction, principal permeabilities [m²]."""
    counted = np.asarray(result.valid & result.in_part, dtype=bool)
    if not counted.any():
        counted = np.asarray(result.valid, dtype=bool)
    out: dict[str, object] = {
        "permeability_model": field.model,
        "cells_past_jamming": int(np.count_nonzero(field.past_jamming)),
    }
    if not counted.any():
        return out
    k1 = field.principal_permeability[..., 0][counted]
    k2 = field.principal_permeability[..., 1][counted]
    for name, values in (
        ("preform_thickness_mm", 1e3 * field.thickness[counted]),
        ("fibre_volume_fraction", field.fibre_volume_fraction[counted]),
        ("permeability_k1_m2", k1),
        ("permeability_k2_m2", k2),
    ):
        out[f"{name}_min"] = float(values.min())
        out[f"{name}_max"] = float(values.max())
    if np.all(k2 > 0):
        out["permeability_anisotropy_max"] = float((k1 / k2).max())
    return out
