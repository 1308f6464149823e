"""The sheared unit cell: tow spacing, width, height and fibre fractions at a shear angle γ.

Architecture-independent part of issue 14's sheared cell (docs/physics.md, "Sheared unit
cell"); the woven and warp-knit plugins build their cells on it. SI units: lengths m, areas m²,
angles rad.

Kinematics [L: pin-jointed net, PHYSICS §7]: the fibres are inextensible and the two fibre
families rotate about their crossings. In the cell's plane the deformation is the pure stretch

    F = λ_b b bᵀ + λ_n n nᵀ,  λ_b = √2 cos(45° − γ/2),  λ_n = √2 sin(45° − γ/2),

about the reference bisector b (n ⟂ b): the families at b ± 45° close to b ± (45° − γ/2), the
angle between them is 90° − γ (positive γ lengthens the fabric along b, the sign convention of
``FabricBase.reference_direction_deg``), lengths along both families are kept, and the cell's
area becomes A₀·cos γ (det F = cos γ). The normal distance between neighbouring tows of one
family becomes Ts·cos γ.

Lateral compaction, one tow family [C, after paper Eqn 3]: the tow keeps its width Tw₀ until
its neighbours touch, at the locking angle γ_L = acos(Tw₀/Ts); then its width is Ts·cos γ.
Its fibre area A_f is fixed, its cross-section is an ellipse (π/4)·w·h, so its fibre fraction is
V = A_f / ((π/4)·w·h). A narrowed tow first compacts at constant height, V = V₀·Tw₀/w (the
paper's assumption), until V reaches the *jamming fraction* V_j; beyond it the fibre bed does
not compact further and the tow thickens instead, h = A_f / ((π/4)·w·V_j). The plugins take V_j
from the Cai–Gutowski bundle law (``preform.plugins.woven.compaction``): the fraction at which
the tow's lateral compaction stress equals the through-thickness pressure that holds it flat,
never above that law's packing cap V_a(1 − ε) < π/4. So the tow fraction never passes V_j, and
the fabric's fraction (fibre volume over cell area × thickness) never passes it either, at any
angle below 90°.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from preform.geometry.unit_cell import FloatArray, TowPath, UnitCell

#: Largest |γ| [rad] a sheared cell is built for: the cell's area vanishes at 90°.
MAX_SHEAR = math.radians(89.0)
#: Elliptical tow section: area = ELLIPSE · width · height (as the woven and warp-knit cells).
ELLIPSE = math.pi / 4.0


def pin_jointed_stretch(gamma: float, reference_direction: float) -> FloatArray:
    """F (2, 2) of a pin-jointed shear γ [rad] about the bisector at ``reference_direction``
    [rad from the cell's x axis] (module docstring). det F = cos γ."""
    c, s = math.cos(reference_direction), math.sin(reference_direction)
    b = np.array([c, s])
    n = np.array([-s, c])
    half = math.pi / 4.0 - gamma / 2.0
    along, across = math.sqrt(2.0) * math.cos(half), math.sqrt(2.0) * math.sin(half)
    return np.asarray(along * np.outer(b, b) + across * np.outer(n, n), dtype=float)


def check_shear(gamma: ArrayLike) -> None:
    """Refuse a shear angle [rad] the cell cannot take, in words; for an array of angles, the
    first such angle."""
    angles = np.asarray(gamma, dtype=float)
    refused = ~(np.abs(angles) <= MAX_SHEAR)  # NaN compares False: refused too
    if refused.any():
        first = float(angles[refused].flat[0])
        raise ValueError(
            f"shear angle {math.degrees(first):g}° is outside ±{math.degrees(MAX_SHEAR):g}°: "
            "a pin-jointed cell has no area at 90°"
        )


@dataclass(frozen=True)
class TowFamily:
    """One family (or layer) of parallel tows of one type, as built (γ = 0). SI units."""

    #: What the family is ("warp", "weft", "layer 1 +45°", ...), for messages and tables.
    name: str
    #: Normal distance between neighbouring tows at γ = 0 [m].
    spacing: float
    #: Tow width [m] and height [m] at γ = 0.
    width: float
    height: float
    #: Fibre cross-sectional area of one tow [m²].
    fibre_area: float
    #: Jamming fraction V_j [-]: the tow compacts up to it, then thickens.
    jamming_fraction: float
    #: Filament diameter [m] (for the permeability of the fibre bed).
    filament_diameter: float = 17e-6
    #: Which fibre family of the drape net the tows belong to: 0 the first (warp; the layer
    #: at the reference direction − 45°), 1 the second (weft; reference + 45°).
    net_family: int = 0

    @property
    def initial_fraction(self) -> float:
        """V₀ = A_f / ((π/4)·w₀·h₀) [-]."""
        return self.fibre_area / (ELLIPSE * self.width * self.height)

    @property
    def locking_angle(self) -> float:
        """γ_L = acos(Tw₀/Ts) [rad]; 0 when the tows touch already."""
        return math.acos(min(1.0, self.width / self.spacing))

    @property
    def jamming_angle(self) -> float:
        """|γ| [rad] at which the tow reaches V_j and starts to thicken (≥ γ_L)."""
        ratio = self.initial_fraction * self.width / (self.jamming_fraction * self.spacing)
        return math.acos(min(1.0, ratio))

    def state(self, gamma: ArrayLike) -> TowState:
        """Width, height, fibre fraction and normal spacing at shear angle(s) γ [rad]."""
        g = np.abs(np.asarray(gamma, dtype=float))
        normal = self.spacing * np.cos(g)
        width = np.minimum(self.width, normal)
        at_constant_height = self.initial_fraction * self.width / width
        jammed = at_constant_height > self.jamming_fraction
        fraction = np.where(jammed, self.jamming_fraction, at_constant_height)
        height = self.fibre_area / (ELLIPSE * width * fraction)
        return TowState(normal, width, height, fraction, width < self.width, jammed)


@dataclass(frozen=True)
class TowState:
    """A family's tows at a shear angle (arrays broadcast like γ). SI units."""

    #: Normal distance between neighbouring tows, Ts·cos γ [m].
    spacing: FloatArray
    #: Tow width [m] and height [m].
    width: FloatArray
    height: FloatArray
    #: Fibre volume fraction inside the tow [-].
    fraction: FloatArray
    #: Past locking (the tow is narrowed) / past jamming (the tow thickens).
    locked: NDArray[np.bool_]
    jammed: NDArray[np.bool_]


@dataclass(frozen=True)
class ShearedCell:
    """A fabric's unit cell at shear angle ``shear``: the cell drawn, and its properties.

    ``fibre_volume`` is the reinforcement's fibre volume in one period [m³], the same at every
    angle (inextensible fibres: Σ A_f·L over the tows, L the tow's length at γ = 0); stitching
    threads are not reinforcement and are left out of every fraction here.
    """

    #: Shear angle γ [rad].
    shear: float
    #: Period area at γ [m²] (A₀·cos γ).
    area: float
    #: Fabric thickness at γ [m]: the cell's stack, with the tows' heights at γ.
    thickness: float
    #: Reinforcement fibre volume in one period [m³].
    fibre_volume: float
    #: The tow families, as built, and their state at γ (same order).
    families: tuple[TowFamily, ...]
    states: tuple[TowState, ...]
    #: Fibre volume share of each family [-] (sums to 1).
    family_shares: tuple[float, ...]
    #: Builds the cell drawn at γ (tow paths with their widths and heights at γ), on demand:
    #: a warp-knit's cell holds hundreds of paths, and tables of properties need none.
    draw: Callable[[], UnitCell] = field(repr=False, compare=False)

    def unit_cell(self) -> UnitCell:
        """The cell drawn at γ [m]."""
        return self.draw()

    @property
    def filament_radius(self) -> float:
        """Fibre-volume-weighted mean filament radius [m] of the reinforcement."""
        return 0.5 * sum(
            f.filament_diameter * share
            for f, share in zip(self.families, self.family_shares, strict=True)
        )

    def net_family_shares(self) -> tuple[float, float]:
        """Fibre volume share [-] of the drape net's first and second fibre family."""
        shares = [0.0, 0.0]
        for family, share in zip(self.families, self.family_shares, strict=True):
            shares[family.net_family] += share
        return shares[0], shares[1]

    @property
    def fibre_volume_fraction(self) -> float:
        """Fabric fibre volume fraction [-]: fibre volume over period area × thickness."""
        return self.fibre_volume / (self.area * self.thickness)

    @property
    def tow_volume_fractions(self) -> tuple[float, ...]:
        """Fibre fraction inside the tows of each family [-]."""
        return tuple(float(s.fraction) for s in self.states)

    @property
    def locking_angle(self) -> float:
        """Smallest locking angle over the families [rad]."""
        return min(f.locking_angle for f in self.families)

    @property
    def jamming_angle(self) -> float:
        """Smallest angle [rad] at which a family starts to thicken."""
        return min(f.jamming_angle for f in self.families)

    @property
    def locked(self) -> bool:
        """True when any family is past its locking angle."""
        return any(bool(s.locked) for s in self.states)

    @property
    def jammed(self) -> bool:
        """True when any family has reached its jamming fraction (thickens)."""
        return any(bool(s.jammed) for s in self.states)

    def summary(self) -> dict[str, float | bool | list[float]]:
        """Scalars for tables and the console, units in the keys."""
        return {
            "shear_deg": math.degrees(self.shear),
            "thickness_mm": self.thickness * 1e3,
            "fibre_volume_fraction": self.fibre_volume_fraction,
            "tow_volume_fractions": list(self.tow_volume_fractions),
            "tow_widths_mm": [float(s.width) * 1e3 for s in self.states],
            "tow_heights_mm": [float(s.height) * 1e3 for s in self.states],
            "tow_spacings_mm": [float(s.spacing) * 1e3 for s in self.states],
            "area_mm2": self.area * 1e6,
            "locking_angle_deg": math.degrees(self.locking_angle),
            "jamming_angle_deg": math.degrees(self.jamming_angle),
            "locked": self.locked,
            "jammed": self.jammed,
        }


def thickness_per_angle(
    sheared_cell: Callable[[float], ShearedCell | None], shear: ArrayLike
) -> FloatArray | None:
    """Thickness [m] of ``sheared_cell(γ)`` at each shear angle γ [rad], one cell per angle;
    None when the architecture has no sheared cell. (An architecture whose stack takes every
    angle in one pass says so by its own ``FabricBase.sheared_thickness``.)"""
    angles = np.asarray(shear, dtype=float)
    thickness = np.empty(angles.shape)
    for index, gamma in np.ndenumerate(angles):
        cell = sheared_cell(float(gamma))
        if cell is None:
            return None
        thickness[index] = cell.thickness
    return thickness


def sheared_paths(cell: UnitCell, stretch: FloatArray, z_shift: float = 0.0) -> UnitCell:
    """``cell`` with every point's (x, y) mapped by ``stretch`` (2, 2) and z moved by
    ``z_shift`` [m]; the period vectors are mapped too, so tiling still joins up."""
    f = np.asarray(stretch, dtype=float)
    tows = []
    for tow in cell.tows:
        pts = np.array(tow.points, dtype=float, copy=True)
        pts[:, :2] = pts[:, :2] @ f.T
        pts[:, 2] += z_shift
        tows.append(
            TowPath(
                points=pts,
                width=tow.width,
                height=tow.height,
                kind=tow.kind,
                level=tow.level,
                type_name=tow.type_name,
                linear_density_tex=tow.linear_density_tex,
            )
        )
    period = np.asarray(cell.period, dtype=float) @ f.T
    return UnitCell(
        period=period,
        tows=tuple(tows),
        reference_direction=cell.reference_direction,
        labels=dict(cell.labels),
    )
