"""What the woven friction–compaction shear law needs from a woven unit cell (SI units).

The woven unit cell produces one of these (``WovenUnitCell.crossover_geometry()``); the shear law
consumes it. Keeping the hand-over in one small dataclass keeps geometry and mechanics apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class CrossoverGeometry:
    """Mean crossover description of a 2D weave, or of one level pair of a 3D weave."""

    #: Initial tow widths [m] of the two crossing families (Tw0).
    tow_width_warp: float
    tow_width_weft: float
    #: Centre-to-centre tow spacings [m] (Ts), constant during shear.
    tow_spacing_warp: float
    tow_spacing_weft: float
    #: Tow heights (thickness of one tow) [m].
    tow_height_warp: float
    tow_height_weft: float
    #: Fibre cross-sectional area per tow [m²] (tex / ρ_f).
    fibre_area_warp: float
    fibre_area_weft: float
    #: Fibre axial modulus [Pa] (mean over the two families for hybrids).
    fibre_modulus: float
    #: Crossovers (tow over tow contacts) per unit undeformed area [1/m²].
    crossovers_per_area: float
    #: Interlacings (a tow changing side between neighbouring crossovers) per unit area [1/m²].
    interlacings_per_area: float
    #: Mean float length [in crossovers] of warp and weft tows (1 for a plain weave).
    mean_float_warp: float = 1.0
    mean_float_weft: float = 1.0
    #: Number of tow levels stacked in the cell (2 for a 2D weave).
    levels: int = 2
    #: Thickness of the unit cell [m] (envelope of its tows), or None: the height the law's
    #: rises and tow heights are scaled from when a free thickness is given.
    thickness: float | None = None
    #: Per contact of the cell (``WovenUnitCell.contacts()`` order): the rises [m] of the
    #: warp-wise tow's path segments whose arcs wrap the crossing tow there (none inside a float,
    #: one at a float's end, two where the tow changes side on both sides). None: every contact
    #: is wrapped on both sides with the rise (h_warp + h_weft)/2, a plain weave.
    warp_wrap_rises: tuple[tuple[float, ...], ...] | None = field(default=None)
    #: The same for the weft-wise tow at each contact.
    weft_wrap_rises: tuple[tuple[float, ...], ...] | None = field(default=None)
