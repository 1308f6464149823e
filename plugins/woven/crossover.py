"""What the woven friction–compaction shear law needs from a woven unit cell (SI units).

The woven unit cell produces one of these (``WovenUnitCell.crossover_geometry()``); the shear law
consumes it. Keeping the hand-over in one small dataclass keeps geometry and mechanics apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

from preform.plugins.woven.tow_jamming import TowCompaction, weave_jamming_fraction

if TYPE_CHECKING:  # built when a law is built, which a listing never does
    from preform.geometry.sheared_cell import TowFamily


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
    #: How the warp-wise and weft-wise tows compact (the one tow model of
    #: ``preform.plugins.woven.tow_jamming``; the cell's tow types carry them).
    compaction_warp: TowCompaction = field(default_factory=TowCompaction)
    compaction_weft: TowCompaction = field(default_factory=TowCompaction)
    #: Fibre moduli [Pa] of each family; None: ``fibre_modulus``.
    fibre_modulus_warp: float | None = None
    fibre_modulus_weft: float | None = None
    #: Share of each family's crossings that are interlaced [-] (``WovenUnitCell.
    #: interlaced_shares``); None: interlacings / (2 · crossovers), both families alike.
    interlaced_share_warp: float | None = None
    interlaced_share_weft: float | None = None

    def interlaced_share(self, family: Literal["warp", "weft"]) -> float:
        """Share s ∈ [0, 1] of the family's crossings that are interlaced [-]."""
        given = self.interlaced_share_warp if family == "warp" else self.interlaced_share_weft
        if given is not None:
            return given
        return min(1.0, self.interlacings_per_area / (2.0 * self.crossovers_per_area))

    def tow_family(self, family: Literal["warp", "weft"]) -> TowFamily:
        """The family's tows as the one tow model sees them (the sheared cell's ``TowFamily``,
        with the weave's jamming fraction), from this mean crossover's dimensions (SI)."""
        from preform.geometry.sheared_cell import ELLIPSE, TowFamily

        warp = family == "warp"
        width = self.tow_width_warp if warp else self.tow_width_weft
        height = self.tow_height_warp if warp else self.tow_height_weft
        area = self.fibre_area_warp if warp else self.fibre_area_weft
        spacing = self.tow_spacing_warp if warp else self.tow_spacing_weft
        modulus = (self.fibre_modulus_warp if warp else self.fibre_modulus_weft) or (
            self.fibre_modulus
        )
        compaction = self.compaction_warp if warp else self.compaction_weft
        v0 = area / (ELLIPSE * width * height)
        try:
            jam = weave_jamming_fraction(v0, modulus, compaction, self.interlaced_share(family))
        except ValueError as error:
            raise ValueError(f"{family}-wise tows: {error}") from None
        return TowFamily(
            name=family,
            spacing=spacing,
            width=width,
            height=height,
            fibre_area=area,
            jamming_fraction=jam,
            net_family=0 if warp else 1,
        )
