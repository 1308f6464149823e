"""The woven ``friction_compaction`` shear law: crossover friction, then tow compaction [P].

Paper (Souter, Long et al., Nottingham, "Mechanical model for fabric shear"), Eqns 1–5: each
crossover resists rotation with the torque T = μ·F_c·R_eff, R_eff the mean distance from the
centre of the parallelogram where the two tows touch; tow widths stay Tw0 until neighbouring tows
meet at the locking angle γ_L = acos(Tw0/Ts), then follow Tw = Ts·cos γ; the contact force comes
from the fabric pre-tension, plus, after lateral contact, a force from inter-tow compaction.
Torque per unit area C(γ) = (crossovers per area)·T. The law is symmetric in γ.

Modelling choices [C] (the paper does not pin these down; every one is a parameter):

* One geometry: tow widths, spacings, fibre areas, heights and the tow paths come from the
  fabric's unit cell (``WovenUnitCell``). ``fabric_thickness_mm``, when given, is a *free*
  (uncompressed) fabric thickness, such as the one the paper fitted for its Table 1 fabrics:
  the relaxed fabric's crimp is the cell's expanded through its thickness by t_free / t_cell,
  so the path rises that wrap the crossovers are the cell's times that ratio. It changes the
  crimp force only: the tows themselves are the cell's (issue 24, one tow).
* Pre-tension contact force, from the weave: ``pretension_N`` is the clamping-frame tension
  across a fabric width ``pretension_width_mm``, shared by the tows of each family, so one tow
  carries T = pretension·Ts/width. Between two neighbouring crossovers the tow path rises by r
  (from the cell's tow path) over one crossing pitch Ts'; drawn as two tangent circular arcs each
  arc turns by α = 2·atan(r/Ts'). The arcs next to a crossover that bend towards the crossing tow
  wrap it (``preform.plugins.woven.crimp``): none inside a float, one at a float's end, two where
  the tow changes side on both sides. The tow presses on the crossing tow with the resultant of
  its tension at the two ends of the wrapping arcs, 2T·sin(Σα/2). The contact force is the mean
  of the two tows' values, averaged over the contacts of the cell. A plain weave's crossovers are
  all wrapped twice with r = h: F_pre = T_wp sin α_wp + T_wt sin α_wt, the paper's model.
* Compaction: one tow model (``preform.plugins.woven.tow_jamming``, the sheared cell's too):
  past locking a tow narrows to Ts·cos γ and compacts at constant height, V_f = V_f0·Tw0/Tw,
  V_f0 = A_f/((π/4)·Tw0·h) of the cell's elliptical tow; its lateral stress is the Cai–Gutowski
  bundle stress with the tow's own constants (``tow_types.*.compaction``), up to the tow's
  limit V_c (stress = the confining pressure), then constant while the floats nest up to the
  weave's jamming fraction V_J. The stress presses on the crossing tow over the crossover
  parallelogram A = Tw_wp·Tw_wt/cos γ (the paper's area), the mean of the two families'
  stresses, at the interlaced crossings only [C]: a share s of the contacts (mean of the two
  families' interlaced shares, 1 for a plain weave, ½ for a 2/2 twill, ¼ for an 8HS), since
  along a float the squeezed tows press on each other side by side, in the plane.
* Jamming: the fabric is jammed at the first angle where a tow family reaches V_J; a dry
  fabric that cannot shear further in its plane leaves it (wrinkles). Past that angle the law
  holds the torque it reached (the energy grows linearly, by C_J per radian) instead of
  following the compaction pole, whose energies (1e7–1e9 J/m²) are no fabric's;
  ``packing_angle`` reports the jamming angle and drape results count the cells past it as
  wrinkled, not as a physical energy.
* Friction mobilisation (``friction_mobilisation_deg``, γ_m, default 0): the paper's Coulomb
  crossover slips with the full torque from the first degree; measured picture-frame curves of
  dry weaves rise from zero instead (Cao et al. 2008, Figs 24-28). The law multiplies the
  crossover torque by Dahl's mobilisation 1 − exp(−|γ|/γ_m) (P.R. Dahl, "A solid friction
  model", Aerospace Corp. TOR-0158(3107-18)-1, 1968): a crossover turns first by the tows' own
  compliance and slides fully only after a few γ_m. γ_m is a fitted constant, not a
  prediction: no published value exists for any fabric; ``preform calibrate`` fits it.
* Angles are clamped to |γ| ≤ 90° − 1e-9 rad (the picture frame and the parallelogram are
  singular at 90°).

The same rules serve twill, satin, basket and 3D weaves: their floats leave crossovers unwrapped,
so the crimp force and the compaction force fall with the share of interlacings and the jam
comes later; for 3D weaves crossovers_per_area counts every tow-on-tow contact of the stack. No
weave-specific constant enters.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import BaseModel, Field, model_validator

from preform.material import ParamsModel, Plausible
from preform.plugins.woven.tow_jamming import (
    TowCompaction,
    bundle_law,
    jamming_angle,
    jamming_fraction,
    lateral_stress,
)
from preform.shear.energy import QuadratureBranch
from preform.shear.law import ShearLaw
from preform.shear.laws import SignedShearLaw

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

    # built from a fabric's cell when a law is built, which a listing never does
    from preform.plugins.woven.compaction import BundleCompaction
    from preform.plugins.woven.crossover import CrossoverGeometry

    FloatArray = NDArray[np.float64]


#: Largest shear-angle magnitude [rad] the law evaluates; the crossover is singular at 90°.
MAX_SHEAR = math.pi / 2 - 1e-9


def _strip_edge_integral(distance: FloatArray, s_lo: FloatArray, s_hi: FloatArray) -> FloatArray:
    """∫ r dA over the triangle (centre, edge) for an edge on a line at ``distance`` p from the
    centre, running from s_lo to s_hi along the line (s from the foot of the perpendicular).

    In polar coordinates about the centre, ∫∫ r·r dr dt = (p³/3)∫ sec³t dt, and with x = tan t,
    ∫ sec³ = [x√(1+x²) + asinh x]/2.
    """

    import numpy as np

    def g(x: FloatArray) -> FloatArray:
        return np.asarray(x * np.sqrt(1.0 + x * x) + np.arcsinh(x), dtype=float)

    return np.asarray(distance**3 / 6.0 * (g(s_hi / distance) - g(s_lo / distance)), dtype=float)


def contact_mean_radius(width_1: ArrayLike, width_2: ArrayLike, gamma: ArrayLike) -> FloatArray:
    """R_eff [m]: mean distance from the centre over the crossover contact parallelogram.

    Two straight tow strips of widths ``width_1``, ``width_2`` [m] crossing at 90° − γ (γ [rad])
    overlap in a parallelogram of area w1·w2/cos γ. Closed form: the parallelogram is split into
    the four triangles (centre, edge). For a square of side w it gives w(√2 + ln(1+√2))/6.
    Broadcasts over all arguments.
    """
    import numpy as np

    w1 = np.asarray(width_1, dtype=float)
    w2 = np.asarray(width_2, dtype=float)
    g = np.clip(np.abs(np.asarray(gamma, dtype=float)), 0.0, MAX_SHEAR)
    cos_g, sin_g = np.cos(g), np.sin(g)
    # Edges along strip 1 lie at distance w1/2 and run between s = (w1 sin γ ± w2)/(2 cos γ);
    # edges along strip 2 likewise with the roles swapped. Each pair appears twice (symmetry).
    p1, p2 = 0.5 * w1, 0.5 * w2
    along_1 = _strip_edge_integral(
        p1, (w1 * sin_g - w2) / (2 * cos_g), (w1 * sin_g + w2) / (2 * cos_g)
    )
    along_2 = _strip_edge_integral(
        p2, (w2 * sin_g - w1) / (2 * cos_g), (w2 * sin_g + w1) / (2 * cos_g)
    )
    area = w1 * w2 / cos_g
    return np.asarray(2.0 * (along_1 + along_2) / area, dtype=float)


def tow_width(gamma: ArrayLike, initial_width: float, spacing: float) -> FloatArray:
    """Tow width Tw [m] at shear angle γ [rad] (paper Eqn 3): Tw0 up to γ_L, then Ts·cos γ."""
    import numpy as np

    g = np.clip(np.abs(np.asarray(gamma, dtype=float)), 0.0, MAX_SHEAR)
    return np.asarray(np.minimum(initial_width, spacing * np.cos(g)), dtype=float)


def locking_angle(initial_width: float, spacing: float) -> float:
    """γ_L = acos(Tw0/Ts) [rad] (paper Eqn 4): neighbouring tows meet. 0 if Tw0 ≥ Ts."""
    return math.acos(min(1.0, initial_width / spacing))


def crimp_angle(crossing_height: float, crossing_spacing: float) -> float:
    """θ [rad] of a lenticular (two-arc) tow path over tows of height h at spacing Ts' [m]."""
    return 2.0 * math.atan(crossing_height / crossing_spacing)


# Plausible ranges of the law's parameters; reasons in docs/ranges.md.
FRICTION = Plausible(
    0.0,
    2.0,
    "",
    "a tow-on-tow friction coefficient",
    "fibre–fibre friction is 0.1–0.6 (paper: 0.3)",
)
PRETENSION = Plausible(
    0.0,
    1e4,
    "N",
    "a frame pre-tension",
    "the paper uses 50–100 N; a fabric in a picture frame tears long before 10 kN",
)
FABRIC_THICKNESS = Plausible(
    0.01,
    100.0,
    "mm",
    "a free (uncompressed) fabric thickness",
    "spread-tow fabrics ≈ 0.03 mm thick, thick 3D weaves ≈ 50 mm",
)
FRAME_WIDTH = Plausible(1.0, 5000.0, "mm", "a frame width", "picture frames are 100–300 mm a side")
MOBILISATION = Plausible(
    0.0,
    90.0,
    "deg",
    "a friction mobilisation angle",
    "0 is Coulomb's sudden slip; 90° means the crossovers never reach full slip in any test",
)


class FrictionCompactionParams(ParamsModel):
    """Parameters of the woven ``friction_compaction`` law (YAML ``shear_law`` block)."""

    law: Literal["friction_compaction"] = Field(description="Selects this law.")
    friction_coefficient: Annotated[float, FRICTION] = Field(
        default=0.3, ge=0.0, description="Tow-on-tow friction coefficient μ at crossovers [-]."
    )
    pretension_N: Annotated[float, PRETENSION] = Field(
        ge=0.0,
        description=(
            "Clamping-frame pre-tension of the fabric [N] across pretension_width_mm, per "
            "family; one tow carries pretension·Ts/width and presses the crossing tows through "
            "its crimp [C]."
        ),
    )
    fabric_thickness_mm: Annotated[float | None, FABRIC_THICKNESS] = Field(
        default=None,
        gt=0.0,
        description=(
            "Free (uncompressed) fabric thickness [mm], e.g. the paper's fitted Table 1 value; "
            "the law then expands the unit cell's crimp (the path rises that wrap the "
            "crossovers) by thickness / (cell thickness) [C]. The tows stay the cell's. "
            "Default: none, the unit cell's own crimp."
        ),
    )
    pretension_width_mm: Annotated[float, FRAME_WIDTH] = Field(
        default=150.0,
        gt=0.0,
        description="Fabric width [mm] sharing pretension_N (the frame side) [C].",
    )
    friction_mobilisation_deg: Annotated[float, MOBILISATION] = Field(
        default=0.0,
        ge=0.0,
        description=(
            "Friction mobilisation angle γ_m [deg]: the crossovers' friction torque builds up "
            "as 1 − exp(−|γ|/γ_m) (Dahl's friction model) while the tows' own compliance lets "
            "a crossover turn before it slips [C]. 0 (default): Coulomb's model, the full "
            "friction torque from the first degree. Not predicted: fit it to a measured curve "
            "(preform calibrate)."
        ),
    )

    @model_validator(mode="before")
    @classmethod
    def _moved_fields(cls, data: Any) -> Any:
        # Issue 24: one compaction model per tow. Say where a removed field went, instead of
        # pydantic's "extra inputs are not permitted".
        if isinstance(data, dict):
            for name, where in MOVED_FIELDS.items():
                if name in data:
                    raise ValueError(f"shear_law.{name} is no longer a law parameter: {where}")
        return data


#: Law fields removed by issue 24 and where their physics lives now.
MOVED_FIELDS: dict[str, str] = {
    "fibre_wave_ratio": "give it per tow, as tow_types.<name>.compaction.fibre_wave_ratio",
    "max_volume_fraction": "give it per tow, as tow_types.<name>.compaction.max_volume_fraction",
    "coupling_compliance_per_GPa": (
        "give it per tow, as tow_types.<name>.compaction.coupling_compliance_per_GPa"
    ),
    "onset_volume_fraction": (
        "the compaction starts at the tow's as-built fraction (from its width and height)"
    ),
    "tow_volume_fraction": (
        "the tow's fraction is its unit cell's, fibre area over (π/4)·width_mm·height_mm: "
        "change the tow's height_mm"
    ),
    "packing_margin": "the pole guard is fixed at 1 % below the maximum fraction",
    "jamming_force_N_per_mm": (
        "the fabric jams where its tows reach the weave's jamming fraction "
        "(tow_types.<name>.compaction; docs/physics.md, 'One tow')"
    ),
}


class FrictionCompactionLaw(SignedShearLaw):
    """Symmetric friction–compaction law of a woven fabric, built from its crossover geometry.

    ``geometries``: one ``CrossoverGeometry`` (2D weave) or several (e.g. level pairs of a 3D
    weave), whose torques add. Torque [N·m/m²], energy [J/m²], angles [rad]. Also offers the
    intermediate quantities per crossover for inspection and tests. ``packing_angle`` [rad] is
    the jamming angle past which the torque is held (module docstring).
    """

    def __init__(
        self,
        geometries: CrossoverGeometry | Sequence[CrossoverGeometry],
        params: FrictionCompactionParams,
    ) -> None:
        from preform.plugins.woven.crossover import CrossoverGeometry

        self.geometries: tuple[CrossoverGeometry, ...] = (
            (geometries,) if isinstance(geometries, CrossoverGeometry) else tuple(geometries)
        )
        if not self.geometries:
            raise ValueError("need at least one crossover geometry")
        self.params = params
        self._parts = [_CrossoverPart(g, params) for g in self.geometries]
        locks = [a for part in self._parts for a in part.locking_angles]
        jams = [a for part in self._parts for a in part.jamming_angles]
        first = min(jams)
        #: Jamming angle [rad]: the first tow family of any level pair reaches its V_J.
        self.packing_angle: float | None = None if first >= MAX_SHEAR - 1e-12 else first
        self._jam = MAX_SHEAR if self.packing_angle is None else self.packing_angle
        # Kinks: the locking angles and the tows' own limits before the jam, and the jam
        # itself (the torque is held).
        limits = [a for part in self._parts for a in part.own_limit_angles]
        #: Angles [rad] before the jam where the torque's slope jumps: a tow family reaches its
        #: own compaction limit and its lateral stress stops rising (a table must hold them).
        self.kink_angles: tuple[float, ...] = tuple(
            sorted({a for a in limits if 0.0 < a < self._jam})
        )
        #: Friction mobilisation angle γ_m [rad] (0: Coulomb).
        self.mobilisation_angle = math.radians(params.friction_mobilisation_deg)
        # The mobilisation's boundary layer is resolved by panels ending at γ_m and 4·γ_m
        # (smooth there, but the quadrature's panels are 0.5° wide).
        layer = [k * self.mobilisation_angle for k in (1.0, 4.0)] if self.mobilisation_angle else []
        breaks = sorted({a for a in (*locks, *limits, *layer) if 0.0 < a < self._jam})
        if self.packing_angle is not None:
            breaks.append(self.packing_angle)
        branch = QuadratureBranch(self.torque_magnitude, breakpoints=breaks)
        super().__init__(branch, None, locking_angle=min(locks), failure_angle=None)

    def _free_torque(self, u: FloatArray) -> FloatArray:
        import numpy as np

        total = np.zeros(np.shape(u))
        for part in self._parts:
            total = total + part.torque_per_area(u)
        return total

    def mobilisation(self, u: ArrayLike) -> FloatArray:
        """Share of the full (sliding) friction torque mobilised at |γ| = u [rad]: Dahl's
        1 − exp(−u/γ_m) (Dahl 1968, a friction force reaching its Coulomb value over a
        characteristic displacement), 1 everywhere when γ_m = 0 (Coulomb) [-]."""
        import numpy as np

        v = np.abs(np.asarray(u, dtype=float))
        if self.mobilisation_angle <= 0.0:
            return np.ones_like(v)
        return np.asarray(-np.expm1(-v / self.mobilisation_angle), dtype=float)

    def torque_magnitude(self, u: FloatArray) -> FloatArray:
        """Torque per area |C| [N·m/m²] at shear-angle magnitudes u [rad]: the crossovers'
        friction torque times its mobilised share; held past jamming."""
        import numpy as np

        held = np.minimum(np.asarray(u, dtype=float), self._jam)
        return np.asarray(self._free_torque(held) * self.mobilisation(held), dtype=float)

    def tow_volume_fractions(self, gamma: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Fibre fraction inside the warp-wise and weft-wise tows [-] of the first geometry at
        γ [rad]: the one tow model's (the sheared cell's), up to the weave's jamming fraction."""
        import numpy as np

        g = np.asarray(gamma, dtype=float)
        warp, weft = self._parts[0].families
        return warp.state(g).fraction, weft.state(g).fraction

    def contact_force(self, gamma: ArrayLike) -> FloatArray:
        """Mean contact force per crossover F_c [N] of the first geometry."""
        import numpy as np

        return self._parts[0].contact_force(np.asarray(gamma, dtype=float))

    def pretension_force(self) -> float:
        """Mean pre-tension (crimp) contact force per crossover [N] of the first geometry."""
        return self._parts[0].pretension_force

    def effective_radius(self, gamma: ArrayLike) -> FloatArray:
        """R_eff [m] of the first geometry's crossover at γ [rad]."""
        import numpy as np

        return self._parts[0].effective_radius(np.asarray(gamma, dtype=float))


def wrapped_contact_force(tension: float, rises: Sequence[float], pitch: float) -> float:
    """Force [N] a tow of tension T [N] presses on a crossing tow with, its path segments of
    rises r [m] over pitch Ts' [m] wrapping it: 2T·sin(Σα/2), α = 2·atan(r/Ts') per arc."""
    turn = sum(crimp_angle(r, pitch) for r in rises)
    return 2.0 * tension * math.sin(0.5 * turn)


class _CrossoverPart:
    """The crossovers described by one ``CrossoverGeometry``, with SI quantities precomputed."""

    def __init__(self, geometry: CrossoverGeometry, params: FrictionCompactionParams) -> None:
        g = geometry
        self.geometry = g
        self.mu = params.friction_coefficient
        heights = (g.tow_height_warp, g.tow_height_weft)
        if params.fabric_thickness_mm is not None:
            # Free thickness: the relaxed cell's crimp, expanded through its thickness.
            cell_thickness = g.thickness if g.thickness is not None else g.levels * max(heights)
            expand = params.fabric_thickness_mm * 1e-3 / cell_thickness
        else:
            expand = 1.0
        width = params.pretension_width_mm * 1e-3
        tension_wp = params.pretension_N * g.tow_spacing_warp / width
        tension_wt = params.pretension_N * g.tow_spacing_weft / width
        plain_rise = 0.5 * (g.tow_height_warp + g.tow_height_weft)
        if g.warp_wrap_rises is None or g.weft_wrap_rises is None:
            if g.interlacings_per_area < 2.0 * g.crossovers_per_area * (1 - 1e-9):
                raise ValueError(
                    "a weave with floats needs the rises of the tow paths at its contacts "
                    "(CrossoverGeometry.warp_wrap_rises, weft_wrap_rises; built from the unit "
                    "cell by preform.plugins.woven.crimp)"
                )
            warp_rises: tuple[tuple[float, ...], ...] = ((plain_rise, plain_rise),)
            weft_rises: tuple[tuple[float, ...], ...] = ((plain_rise, plain_rise),)
        else:
            warp_rises, weft_rises = g.warp_wrap_rises, g.weft_wrap_rises
        forces = [
            0.5
            * (
                wrapped_contact_force(tension_wp, [r * expand for r in wp], g.tow_spacing_weft)
                + wrapped_contact_force(tension_wt, [r * expand for r in wt], g.tow_spacing_warp)
            )
            for wp, wt in zip(warp_rises, weft_rises, strict=True)
        ]
        #: Pre-tension contact force per crossover, mean over the contacts [N].
        self.pretension_force = sum(forces) / len(forces) if forces else 0.0
        self.locking_angles = (
            locking_angle(g.tow_width_warp, g.tow_spacing_warp),
            locking_angle(g.tow_width_weft, g.tow_spacing_weft),
        )
        # The one tow model: the same families the sheared cell builds.
        self.families = (g.tow_family("warp"), g.tow_family("weft"))
        self.compactions = (g.compaction_warp, g.compaction_weft)
        self.bundles = tuple(
            _bundle(f.initial_fraction, g.fibre_modulus, c, f.name)
            for f, c in zip(self.families, self.compactions, strict=True)
        )
        self.own_limits = tuple(
            jamming_fraction(f.initial_fraction, g.fibre_modulus, c)
            for f, c in zip(self.families, self.compactions, strict=True)
        )
        self.jamming_angles = tuple(f.jamming_angle for f in self.families)
        self.own_limit_angles = tuple(
            jamming_angle(f.initial_fraction, f.width, f.spacing, v)
            for f, v in zip(self.families, self.own_limits, strict=True)
        )
        #: Share of the contacts where the compaction presses on the crossing tow [-].
        self.compaction_share = 0.5 * (g.interlaced_share("warp") + g.interlaced_share("weft"))

    def widths(self, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        g = self.geometry
        return (
            tow_width(u, g.tow_width_warp, g.tow_spacing_warp),
            tow_width(u, g.tow_width_weft, g.tow_spacing_weft),
        )

    def effective_radius(self, u: FloatArray) -> FloatArray:
        w_wp, w_wt = self.widths(u)
        return contact_mean_radius(w_wp, w_wt, u)

    def contact_force(self, u: FloatArray) -> FloatArray:
        import numpy as np

        g = np.clip(np.abs(u), 0.0, MAX_SHEAR)
        w_wp, w_wt = self.widths(u)
        stress = 0.5 * sum(
            lateral_stress(bundle, limit, family.state(g).fraction)
            for bundle, limit, family in zip(
                self.bundles, self.own_limits, self.families, strict=True
            )
        )
        area = w_wp * w_wt / np.cos(g)
        return np.asarray(
            self.pretension_force + self.compaction_share * stress * area, dtype=float
        )

    def torque_per_area(self, u: FloatArray) -> FloatArray:
        import numpy as np

        crossover_torque = self.mu * self.contact_force(u) * self.effective_radius(u)
        return np.asarray(self.geometry.crossovers_per_area * crossover_torque, dtype=float)


def _bundle(v0: float, modulus: float, compaction: TowCompaction, name: str) -> BundleCompaction:
    try:
        return bundle_law(v0, modulus, compaction)
    except ValueError as error:
        raise ValueError(f"{name} tows: {error}") from None


def build_friction_compaction(params: FrictionCompactionParams, fabric: Any) -> SignedShearLaw:
    """Build the law for a woven fabric entry: from its unit cell (``woven_unit_cell``, with the
    crimp of every contact), else from its ``crossover_geometry()`` (a plain weave's)."""
    cell = getattr(fabric, "woven_unit_cell", None)
    if cell is not None and hasattr(fabric, "errors") and not fabric.errors():
        from preform.plugins.woven.crimp import crossover_geometry_with_crimp

        return FrictionCompactionLaw(crossover_geometry_with_crimp(cell), params)
    return FrictionCompactionLaw(fabric.crossover_geometry(), params)


def plain_weave_geometry(
    tow_width_mm: float,
    tow_spacing_mm: float,
    linear_density_tex: float,
    fibre_density_g_cm3: float = 2.55,
    fibre_modulus_GPa: float = 72.0,
    tow_height_mm: float = 0.5,
) -> CrossoverGeometry:
    """A balanced plain weave's ``CrossoverGeometry`` in SI, from datasheet units (for tests and
    for the Table 1 fabrics without a full unit-cell model; glass defaults)."""
    from preform.plugins.woven.crossover import CrossoverGeometry

    w, s = tow_width_mm * 1e-3, tow_spacing_mm * 1e-3
    fibre_area = linear_density_tex / (1000.0 * fibre_density_g_cm3) * 1e-6
    return CrossoverGeometry(
        tow_width_warp=w,
        tow_width_weft=w,
        tow_spacing_warp=s,
        tow_spacing_weft=s,
        tow_height_warp=tow_height_mm * 1e-3,
        tow_height_weft=tow_height_mm * 1e-3,
        fibre_area_warp=fibre_area,
        fibre_area_weft=fibre_area,
        fibre_modulus=fibre_modulus_GPa * 1e9,
        crossovers_per_area=1.0 / (s * s),
        interlacings_per_area=2.0 / (s * s),
        thickness=2.0 * tow_height_mm * 1e-3,
    )


#: (law name, params model, builder) for the registry.
SHEAR_LAWS: list[tuple[str, type[BaseModel], Callable[[Any, Any], ShearLaw]]] = [
    ("friction_compaction", FrictionCompactionParams, build_friction_compaction)
]
