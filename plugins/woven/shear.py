"""The woven ``friction_compaction`` shear law: crossover friction, then tow compaction [P].

Paper (Souter, Long et al., Nottingham, "Mechanical model for fabric shear"), Eqns 1–5: each
crossover resists rotation with the torque T = μ·F_c·R_eff, R_eff the mean distance from the
centre of the parallelogram where the two tows touch; tow widths stay Tw0 until neighbouring tows
meet at the locking angle γ_L = acos(Tw0/Ts), then follow Tw = Ts·cos γ; the contact force comes
from the fabric pre-tension, plus, after lateral contact, a force from inter-tow compaction.
Torque per unit area C(γ) = (crossovers per area)·T. The law is symmetric in γ.

Modelling choices [C] (the paper does not pin these down; every one is a parameter):

* One geometry: tow widths, spacings, fibre areas, heights and the tow paths come from the
  fabric's unit cell (``WovenUnitCell``). The cell's tow height is the nominal (as-woven,
  compacted) height of one tow. ``fabric_thickness_mm``, when given, is a *free* (uncompressed)
  fabric thickness, such as the one the paper fitted for its Table 1 fabrics: the relaxed fabric
  is the cell expanded through its thickness by t_free / t_cell, so the law's path rises and tow
  heights are the cell's times that ratio, and the tow section is the paper's lenticular one,
  (2/3)·Tw0·h. Without it the law uses the cell as it is, with the cell's own (elliptical)
  section: V_f0 = A_f / ((π/4)·Tw0·h).
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
* Compaction: the bundle stress (``preform.plugins.woven.compaction``; V_f = V_f0·Tw0/Tw, onset
  fraction V_o = V_f0 by default so the force starts at zero at locking) is integrated over the
  tow contact area the paper names, the crossover parallelogram A = Tw_wp·Tw_wt/cos γ; the mean
  of the two families' stresses is used. Compaction acts at every contact, wrapped or not.
* Jamming: the fabric is jammed at the first angle where its tows reach the packing cap
  V_a(1 − ε) or its picture-frame force F_s/L reaches ``jamming_force_N_per_mm``; a dry fabric
  that cannot shear further in its plane leaves it (wrinkles). Past that angle the law holds the
  torque it reached (the energy grows linearly, by C_J per radian) instead of following the
  compaction pole, whose energies (1e7–1e9 J/m²) are no fabric's; ``packing_angle`` reports the
  jamming angle and drape results count the cells past it as unphysical.
* Angles are clamped to |γ| ≤ 90° − 1e-9 rad (the picture frame and the parallelogram are
  singular at 90°).

The same rules serve twill, satin, basket and 3D weaves: their floats leave crossovers unwrapped,
so the crimp force falls with the share of interlacings; for 3D weaves crossovers_per_area counts
every tow-on-tow contact of the stack. No weave-specific constant enters.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import BaseModel, Field

from preform.material import ParamsModel, Plausible
from preform.plugins.woven.compaction import SQUARE_PACKING, BundleCompaction
from preform.shear.energy import QuadratureBranch
from preform.shear.law import ShearLaw
from preform.shear.laws import SignedShearLaw

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

    # built from a fabric's cell when a law is built, which a listing never does
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


#: Hexagonal packing of round fibres, π/(2√3): no fibre fraction can exceed it.
HEXAGONAL_PACKING = math.pi / (2.0 * math.sqrt(3.0))

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
JAMMING_FORCE = Plausible(
    0.1,
    100.0,
    "N/mm",
    "a picture-frame force at which a jammed fabric wrinkles",
    "measured picture-frame curves of dry fabrics end, wrinkling, at ≈ 1–10 N/mm",
)
FRAME_WIDTH = Plausible(1.0, 5000.0, "mm", "a frame width", "picture frames are 100–300 mm a side")
TOW_FRACTION = Plausible(
    0.05,
    HEXAGONAL_PACKING,
    "",
    "a tow fibre volume fraction",
    "as-woven tows hold 0.4–0.8 fibre; hexagonal packing π/(2√3) ≈ 0.907 is the ceiling",
)
MAX_FRACTION = Plausible(
    0.3,
    HEXAGONAL_PACKING,
    "",
    "a maximum attainable fibre fraction",
    "square packing π/4 ≈ 0.785 to hexagonal π/(2√3) ≈ 0.907 (Gutowski's V_a ≈ 0.75–0.85)",
)
WAVE_RATIO = Plausible(
    1.0,
    1e4,
    "",
    "Gutowski's fibre-wave ratio β",
    "350 quoted for AS4 carbon, 30 the default here; A_s goes as β⁻⁴",
)
COUPLING = Plausible(
    0.0,
    100.0,
    "1/GPa",
    "the Cai–Gutowski coupling compliance",
    "a fibre bed's compliances are ≈ 1/E_f ≈ 0.004–0.1 /GPa",
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
            "the law then expands the unit cell's tow heights and path rises by thickness / "
            "(cell thickness) [C]. Default: none, the unit cell's own tow heights (the "
            "nominal height of one tow, tow_types.*.height_mm)."
        ),
    )
    pretension_width_mm: Annotated[float, FRAME_WIDTH] = Field(
        default=150.0,
        gt=0.0,
        description="Fabric width [mm] sharing pretension_N (the frame side) [C].",
    )
    tow_volume_fraction: Annotated[float | None, TOW_FRACTION] = Field(
        default=None,
        gt=0.0,
        lt=1.0,
        description=(
            "As-woven fibre fraction V_f0 in a tow [-]; default A_f / ((2/3)·Tw0·h), a "
            "lenticular section of height h [C]."
        ),
    )
    onset_volume_fraction: Annotated[float | None, TOW_FRACTION] = Field(
        default=None,
        gt=0.0,
        lt=1.0,
        description="Gutowski V_o [-], the fraction where the fibres start to carry load; default V_f0 [C].",
    )
    max_volume_fraction: Annotated[float, MAX_FRACTION] = Field(
        default=SQUARE_PACKING,
        gt=0.0,
        lt=1.0,
        description="Gutowski V_a [-], maximum attainable fraction; default π/4 (square packing).",
    )
    fibre_wave_ratio: Annotated[float, WAVE_RATIO] = Field(
        default=30.0,
        gt=0.0,
        description=(
            "Gutowski β [-], span-to-height ratio of fibre waves, A_s = 3πE_f/β⁴. Default 30 [C]: "
            "makes compaction stiffen the Table 1 fabrics within ~10° past locking, as the "
            "paper's curves do; the carbon value 350 leaves it negligible at V_f0 ≈ 0.23."
        ),
    )
    coupling_compliance_per_GPa: Annotated[float, COUPLING] = Field(
        default=0.0,
        ge=0.0,
        description="Cai–Gutowski F_bl [1/GPa]; 0 reduces the bundle stress to Gutowski's [C].",
    )
    packing_margin: float = Field(
        default=1e-2,
        gt=0.0,
        lt=0.5,
        description="ε: V_f is followed exactly up to V_a(1−ε), linearly beyond (pole guard) [-].",
    )
    jamming_force_N_per_mm: Annotated[float, JAMMING_FORCE] = Field(
        default=10.0,
        gt=0.0,
        description=(
            "Picture-frame force F_s/L [N/mm] at which the jammed fabric leaves its plane; past "
            "the angle where it (or the packing cap) is reached the torque is held [C]."
        ),
    )


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
        packs = [a for part in self._parts for a in part.packing_angles]
        packing = min(packs)
        #: Angle [rad] where the tows reach the guarded packing cap (before any jamming force).
        self.tows_packed_angle: float = packing
        jam = self._force_jamming_angle(params.jamming_force_N_per_mm * 1000.0, packing)
        #: Jamming angle [rad]: packing cap or jamming force, whichever comes first.
        first = min(packing, jam)
        self.packing_angle: float | None = None if first >= MAX_SHEAR - 1e-12 else first
        self._jam = MAX_SHEAR if self.packing_angle is None else self.packing_angle
        # Kinks: the locking angles before the jam, and the jam itself (the torque is held).
        breaks = [a for a in locks if a < self._jam]
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

    def _force_jamming_angle(self, force_N_per_m: float, stop: float) -> float:
        """First angle [rad] in [0, stop] where C/cos γ reaches ``force_N_per_m``; MAX_SHEAR if
        none. A grid finds the first crossing (the force rises monotonically past locking);
        four finer grids inside the bracket refine it to ~1e-12 rad, one vector call each."""
        import numpy as np

        lo, hi = 0.0, stop
        for level in range(5):
            grid = np.linspace(lo, hi, 257)
            force = self._free_torque(grid) / np.cos(grid)
            above = np.nonzero(force >= force_N_per_m)[0]
            if above.size == 0:
                return MAX_SHEAR if level == 0 else hi
            k = int(above[0])
            if k == 0:
                return float(grid[0])
            lo, hi = float(grid[k - 1]), float(grid[k])
        return hi

    def torque_magnitude(self, u: FloatArray) -> FloatArray:
        """Torque per area |C| [N·m/m²] at shear-angle magnitudes u [rad]; held past jamming."""
        import numpy as np

        return self._free_torque(np.minimum(np.asarray(u, dtype=float), self._jam))

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
            # Free thickness: the relaxed cell, expanded through its thickness (module doc).
            cell_thickness = g.thickness if g.thickness is not None else g.levels * max(heights)
            expand = params.fabric_thickness_mm * 1e-3 / cell_thickness
            section = 2.0 / 3.0  # the paper's lenticular tow section
        else:
            expand = 1.0
            section = math.pi / 4.0  # the unit cell's elliptical tow section
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
        self.bundles = tuple(
            self._bundle(params, fibre_area, w0, h * expand, section, g.fibre_modulus)
            for fibre_area, w0, h in (
                (g.fibre_area_warp, g.tow_width_warp, g.tow_height_warp),
                (g.fibre_area_weft, g.tow_width_weft, g.tow_height_weft),
            )
        )
        self.packing_angles = tuple(
            self._packing_angle(b, w0, ts)
            for b, w0, ts in (
                (self.bundles[0], g.tow_width_warp, g.tow_spacing_warp),
                (self.bundles[1], g.tow_width_weft, g.tow_spacing_weft),
            )
        )

    @staticmethod
    def _bundle(
        params: FrictionCompactionParams,
        fibre_area: float,
        initial_width: float,
        height: float,
        section: float,
        modulus: float,
    ) -> BundleCompaction:
        v0 = params.tow_volume_fraction or fibre_area / (section * initial_width * height)
        cap = params.max_volume_fraction * (1.0 - params.packing_margin)
        if not v0 < cap:
            shape = "lenticular" if section < 0.7 else "elliptical"
            raise ValueError(
                f"as-woven tow fibre fraction {v0:.3f} (fibre area over a {shape} section of "
                f"width {initial_width * 1e3:.3g} mm, height {height * 1e3:.3g} mm) is not "
                f"below the packing cap {cap:.3f}: raise the tow height (or the free "
                "fabric_thickness_mm) or give tow_volume_fraction"
            )
        return BundleCompaction(
            fibre_modulus=modulus,
            span_to_height=params.fibre_wave_ratio,
            initial_fraction=v0,
            onset_fraction=params.onset_volume_fraction or v0,
            max_fraction=params.max_volume_fraction,
            coupling_compliance=params.coupling_compliance_per_GPa * 1e-9,
            packing_margin=params.packing_margin,
        )

    @staticmethod
    def _packing_angle(bundle: BundleCompaction, initial_width: float, spacing: float) -> float:
        # V_f = V_f0·Tw0/(Ts cos γ) reaches the cap when cos γ = V_f0·Tw0/(V_c·Ts).
        ratio = bundle.initial_fraction * initial_width / (bundle.cap_fraction * spacing)
        return math.acos(min(1.0, ratio))

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

        g = self.geometry
        w_wp, w_wt = self.widths(u)
        stress = 0.5 * (
            self.bundles[0].stress(self.bundles[0].initial_fraction * g.tow_width_warp / w_wp)
            + self.bundles[1].stress(self.bundles[1].initial_fraction * g.tow_width_weft / w_wt)
        )
        cos_g = np.cos(np.clip(np.abs(u), 0.0, MAX_SHEAR))
        return np.asarray(self.pretension_force + stress * w_wp * w_wt / cos_g, dtype=float)

    def torque_per_area(self, u: FloatArray) -> FloatArray:
        import numpy as np

        crossover_torque = self.mu * self.contact_force(u) * self.effective_radius(u)
        return np.asarray(self.geometry.crossovers_per_area * crossover_torque, dtype=float)


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
