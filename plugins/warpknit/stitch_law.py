"""The warp-knit ``stitch_yarn`` shear law: the stitch yarn of the unit cell stretched by the shear.

Beyond the paper, which fitted the measured warp-knit curves (``stitch_polynomial`` stays the
route for measured data), this law derives the asymmetric response from the construction [C]:

* Kinematics: the fabric shears as a pin-jointed net whose fibre families lie at ±45° from its
  reference direction r (the stitch for ±45° fabrics). At shear γ (the reduction of the angle
  between the families, γ > 0 lengthening the fabric along r) the plane deforms by
  F = λ₁ r⊗r + λ₂ r⊥⊗r⊥, λ₁ = cos(γ/2) + sin(γ/2) (stretch along r), λ₂ = cos(γ/2) − sin(γ/2)
  (across r); λ₁λ₂ = cos γ is the area change of the net. The through-thickness parts of the
  stitch (the loop legs through the stack) keep their length (the stack keeps its thickness).
* The stitch yarn path of each thread level over one repeat of its lapping
  (``WarpKnitGeometry.stitch_path``: loops round the needles, underlaps on the back) is carried
  by F segment by segment. Its length becomes L(γ) = Σ |F·d_i|, and
  dL/dγ = Σ (λ₁λ₂/2)(a_i² − b_i²)/|F·d_i| with a_i, b_i the components of segment i along r and
  across it. A segment along r lengthens in γ > 0 and shortens in γ < 0; a segment across r does
  the opposite; one along a fibre (45°) keeps its length (the fibres are inextensible).
* The yarn slides round its loops without friction, so its tension is one value along the
  repeat: strain ε = L(γ)/L(0) − 1 when positive (the yarn is taut, not pre-strained, at γ = 0;
  a shortened yarn is slack and carries nothing). Tension T = E·A·ε, linear to break, with the
  yarn's fibre area A = tex/ρ and modulus E (thread entry ``yarn_modulus_GPa``, default the
  fibre's). Strain energy per fabric area Σ_levels ½·E·A·ε²·L(0)/A_repeat, its torque
  Σ E·A·ε·(dL/dγ)/A_repeat.
* Inter-ply friction under the stitch's compaction: each loop clamps the stack with its two
  legs, 2T, over the patch of fabric it holds (one stitch length × one thread pitch). The plies
  (the two fibre families) turn against each other by γ at each stitch point, so each patch
  resists with μ·2T·R̄, R̄ the mean distance from the patch centre over the patch (a
  rectangle, closed form); torque per area μ·2T·R̄·loops/A_repeat.
* Failure: a level's stitch breaks at the first angle, in each sense, where ε reaches the yarn's
  strain at break ε_b (thread entry ``failure_strain`` or the law's ``yarn_failure_strain``).
  From there that level carries no tension, no energy is added and its friction is gone; the
  energy it stored stays spent (W never falls). ``failure_angle`` is the parallel-sense (γ > 0)
  angle of the first level to break, ``failure_angle_negative`` the perpendicular one.

So a pillar (chain) stitch along the machine direction, whose path runs along r, is stretched
as the fabric along r in γ > 0 (ε = λ₁ − 1 scaled by the share of its length in the plane)
and is slack in γ < 0; a tricot's zig-zag underlaps, steeper than 45° to r, lengthen in γ < 0
while its loops lengthen in γ > 0, so its curve is less asymmetric. The laminate's tows
themselves (lateral compaction after locking) are not modelled here: the law reports no locking
angle, and past the stitch failure it gives no further resistance.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import ArrayLike
from pydantic import BaseModel, Field

from preform.base.arrays import FloatArray
from preform.geometry.fibres import fibre, fibre_area_m2
from preform.material import ParamsModel, Plausible
from preform.plugins.warpknit.model import YARN_FAILURE_STRAIN
from preform.shear.energy import QuadratureBranch
from preform.shear.law import ShearLaw
from preform.shear.laws import SignedShearLaw

#: Largest shear-angle magnitude [rad] evaluated (the net is singular at 90°).
MAX_SHEAR = math.pi / 2 - 1e-9

PLY_FRICTION = Plausible(
    0.0,
    2.0,
    "",
    "an inter-ply friction coefficient",
    "dry glass and carbon plies slide on each other with μ ≈ 0.2–0.4",
)


class StitchYarnParams(ParamsModel):
    """Parameters of the warp-knit ``stitch_yarn`` law (YAML ``shear_law`` block); the stitch
    geometry, yarn tex, fibre and tensile data come from the fabric's ``threads``."""

    law: Literal["stitch_yarn"] = Field(description="Selects this law.")
    ply_friction_coefficient: Annotated[float, PLY_FRICTION] = Field(
        default=0.3,
        ge=0.0,
        description="Friction coefficient μ between the plies the stitch clamps [-].",
    )
    yarn_failure_strain: Annotated[float | None, YARN_FAILURE_STRAIN] = Field(
        default=None,
        gt=0.0,
        description="Strain at break of every stitching yarn [-], for threads that do not "
        "give their own failure_strain.",
    )


def net_stretches(gamma: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """(λ₁, λ₂) [-]: stretch of a pin-jointed net along the bisector r of its fibre families
    and across it, at signed shear γ [rad] (γ > 0 lengthens along r)."""
    g = np.clip(np.asarray(gamma, dtype=float), -MAX_SHEAR, MAX_SHEAR)
    c, s = np.cos(0.5 * g), np.sin(0.5 * g)
    return np.asarray(c + s, dtype=float), np.asarray(c - s, dtype=float)


def rectangle_mean_radius(length: float, width: float) -> float:
    """Mean distance [m] from the centre over a rectangle of sides ``length`` × ``width`` [m].

    Closed form, half-sides p, q and half-diagonal d: [2pq·d + p³ ln((q + d)/p) +
    q³ ln((p + d)/q)] / (6pq) (integrating r over the four triangles centre–edge; a square of
    side w gives w(√2 + ln(1 + √2))/6).
    """
    p, q = 0.5 * length, 0.5 * width
    d = math.hypot(p, q)
    return (2 * p * q * d + p**3 * math.log((q + d) / p) + q**3 * math.log((p + d) / q)) / (
        6 * p * q
    )


@dataclass(frozen=True)
class StitchLevel:
    """One thread level's stitch, ready for the law (SI units)."""

    #: Path segments over one repeat: (n, 3) [m], components along r, across r, through z.
    segments: FloatArray
    #: Fabric area one repeat of one thread covers [m²] (repeat length × thread pitch).
    repeat_area: float
    #: Loops (courses) per repeat.
    loops: int
    #: E·A of the yarn [N].
    axial_stiffness: float
    #: Strain at break [-].
    failure_strain: float
    #: Mean radius of the patch one loop clamps [m].
    patch_radius: float

    @property
    def rest_length(self) -> float:
        """L(0) [m]."""
        return float(np.linalg.norm(self.segments, axis=1).sum())

    def length(self, gamma: ArrayLike) -> FloatArray:
        """L(γ) [m] at signed shear angles γ [rad]."""
        l1, l2 = net_stretches(gamma)
        a, b, z = self.segments.T
        g = np.asarray(l1)[..., None]
        h = np.asarray(l2)[..., None]
        return np.asarray(np.sqrt((g * a) ** 2 + (h * b) ** 2 + z**2).sum(axis=-1), dtype=float)

    def length_rate(self, gamma: ArrayLike) -> FloatArray:
        """dL/dγ [m/rad] at signed shear angles γ [rad]."""
        l1, l2 = net_stretches(gamma)
        a, b, z = self.segments.T
        g = np.asarray(l1)[..., None]
        h = np.asarray(l2)[..., None]
        stretched = np.sqrt((g * a) ** 2 + (h * b) ** 2 + z**2)
        safe = np.where(stretched > 0.0, stretched, 1.0)
        rate = 0.5 * g * h * (a**2 - b**2) / safe
        return np.asarray(rate.sum(axis=-1), dtype=float)

    def strain(self, gamma: ArrayLike) -> FloatArray:
        """Yarn strain ε(γ) ≥ 0 [-]; 0 where the yarn is slack."""
        return np.maximum(self.length(gamma) / self.rest_length - 1.0, 0.0)

    def failure_angle(self, sense: float) -> float | None:
        """First angle magnitude [rad] in ``sense`` (+1 or −1) where ε reaches the strain at
        break, or None below 90°."""
        grid = np.linspace(0.0, MAX_SHEAR, 4097)
        strain = self.strain(sense * grid)
        above = np.nonzero(strain >= self.failure_strain)[0]
        if above.size == 0:
            return None
        k = int(above[0])
        lo, hi = float(grid[max(k - 1, 0)]), float(grid[k])
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if float(self.strain(sense * mid)) >= self.failure_strain:
                hi = mid
            else:
                lo = mid
        return hi

    def tension(self, gamma: ArrayLike) -> FloatArray:
        """Yarn tension T [N] before any break."""
        return self.axial_stiffness * self.strain(gamma)

    def torque(self, u: FloatArray, sense: float, mu: float) -> FloatArray:
        """Torque magnitude per fabric area [N·m/m²] of this level at magnitudes u [rad] in
        ``sense``, before any break: stretching plus inter-ply friction."""
        g = sense * np.asarray(u, dtype=float)
        tension = self.tension(g)
        stretching = sense * tension * self.length_rate(g) / self.repeat_area
        friction = mu * 2.0 * tension * self.patch_radius * self.loops / self.repeat_area
        return np.asarray(np.maximum(stretching, 0.0) + friction, dtype=float)


def stitch_levels(fabric: Any, params: StitchYarnParams) -> list[StitchLevel]:
    """The stitch of every thread level of a warp-knit fabric entry (``WarpKnitFabric``)."""
    geometry = fabric.geometry
    ref = math.radians(fabric.reference_direction_deg())
    along = np.array([math.cos(ref), math.sin(ref)])
    across = np.array([-math.sin(ref), math.cos(ref)])
    levels = []
    for k, (entry, level) in enumerate(zip(fabric.threads, geometry.thread_levels, strict=True)):
        strain_at_break = entry.failure_strain or params.yarn_failure_strain
        if strain_at_break is None:
            raise ValueError(
                f"threads.{k}.failure_strain: the stitch_yarn law needs the stitching yarn's "
                "strain at break; give it on the thread or as yarn_failure_strain in the law"
            )
        yarn = fibre(level.fibre)
        modulus = entry.yarn_modulus_GPa * 1e9 if entry.yarn_modulus_GPa else yarn.modulus_Pa
        area = fibre_area_m2(level.linear_density_tex, yarn.density_g_cm3)
        points = geometry.stitch_path(k).points
        d = np.diff(points, axis=0)
        segments = np.column_stack([d[:, :2] @ along, d[:, :2] @ across, d[:, 2]])
        courses = len(level.sequence.courses)
        levels.append(
            StitchLevel(
                segments=segments,
                repeat_area=level.repeat_length * level.thread_pitch,
                loops=courses,
                axial_stiffness=modulus * area,
                failure_strain=float(strain_at_break),
                patch_radius=rectangle_mean_radius(level.stitch_length, level.thread_pitch),
            )
        )
    return levels


class StitchYarnLaw(SignedShearLaw):
    """Asymmetric warp-knit law from the stitch yarn's stretch (module docstring). Torque
    [N·m/m²], energy [J/m²], angles [rad]."""

    def __init__(self, levels: list[StitchLevel], params: StitchYarnParams) -> None:
        if not levels:
            raise ValueError("a stitch_yarn law needs at least one thread level")
        self.levels = levels
        self.params = params
        self._breaks = {sense: [lv.failure_angle(sense) for lv in levels] for sense in (1.0, -1.0)}
        positive = [a for a in self._breaks[1.0] if a is not None]
        negative = [a for a in self._breaks[-1.0] if a is not None]
        #: Perpendicular-sense (γ < 0) failure angle magnitude [rad], or None.
        self.failure_angle_negative: float | None = min(negative) if negative else None
        branches = {
            sense: QuadratureBranch(
                self._magnitude(sense),
                breakpoints=[a for a in self._breaks[sense] if a is not None],
            )
            for sense in (1.0, -1.0)
        }
        super().__init__(
            branches[1.0],
            branches[-1.0],
            locking_angle=None,
            failure_angle=min(positive) if positive else None,
        )

    def _magnitude(self, sense: float) -> Callable[[FloatArray], FloatArray]:
        mu = self.params.ply_friction_coefficient

        def magnitude(u: FloatArray) -> FloatArray:
            u = np.asarray(u, dtype=float)
            total = np.zeros(np.shape(u))
            for level, broken_at in zip(self.levels, self._breaks[sense], strict=True):
                part = level.torque(u, sense, mu)
                if broken_at is not None:
                    part = np.where(u < broken_at, part, 0.0)
                total = total + part
            return total

        return magnitude

    def strain(self, gamma: ArrayLike) -> FloatArray:
        """Strain [-] of the first thread level's yarn at signed γ [rad] (ignoring breaks)."""
        return self.levels[0].strain(gamma)


def build_stitch_yarn(params: StitchYarnParams, fabric: Any) -> ShearLaw:
    """Build the law for a warp-knit fabric entry (its ``threads`` and ``geometry``)."""
    if not hasattr(fabric, "threads") or not hasattr(fabric, "geometry"):
        raise ValueError("the stitch_yarn law needs a warp-knit fabric (threads and stitch)")
    return StitchYarnLaw(stitch_levels(fabric, params), params)


#: (law name, params model, builder) for the registry.
SHEAR_LAWS: list[tuple[str, type[BaseModel], Callable[[Any, Any], ShearLaw]]] = [
    ("stitch_yarn", StitchYarnParams, build_stitch_yarn)
]
