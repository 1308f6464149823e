"""Fibre material constants used to turn linear density into fibre area and compaction stiffness.

Values are typical handbook figures, not measurements of a particular product:
E-glass 2.55 g/cm³ (PHYSICS §1.3) and 72 GPa; carbon (AS4-class) 1.79 g/cm³ and 234 GPa
(Gutowski 1987 quotes 234 GPa for AS4); aramid (Kevlar 49-class) 1.44 g/cm³, 112 GPa;
polyester stitching yarn 1.38 g/cm³, 10 GPa. A tow type may override them.

Filament diameters (for the permeability of the fibre bed, ``preform.geometry.permeability``)
are typical values, illustrative [U]: E-glass rovings 17 µm (made 9–24 µm), standard-modulus
carbon 7 µm, aramid 12 µm, polyester stitching yarn 20 µm.
"""

from __future__ import annotations

from typing import NamedTuple


# A named tuple, not a frozen dataclass: as immutable and compared by value, without execing
# generated methods at every start-up (issue 15l).
class Fibre(NamedTuple):
    name: str
    #: Fibre density [g/cm³].
    density_g_cm3: float
    #: Axial Young's modulus [Pa].
    modulus_Pa: float
    #: Filament (single fibre) diameter [m].
    filament_diameter_m: float = 17e-6


FIBRES: dict[str, Fibre] = {
    "glass": Fibre("glass", 2.55, 72e9, 17e-6),
    "carbon": Fibre("carbon", 1.79, 234e9, 7e-6),
    "aramid": Fibre("aramid", 1.44, 112e9, 12e-6),
    "polyester": Fibre("polyester", 1.38, 10e9, 20e-6),
}


def fibre(name: str) -> Fibre:
    """The named fibre; a KeyError message lists the known ones."""
    try:
        return FIBRES[name]
    except KeyError:
        known = ", ".join(sorted(FIBRES))
        raise KeyError(f"unknown fibre {name!r}; known fibres: {known}") from None


def fibre_area_m2(linear_density_tex: float, density_g_cm3: float) -> float:
    """Cross-sectional fibre area of a tow [m²] from its linear density [tex] and fibre
    density [g/cm³]: A_f [mm²] = tex / (1000 ρ_f) (PHYSICS §1.3)."""
    return linear_density_tex / (1000.0 * density_g_cm3) * 1e-6
