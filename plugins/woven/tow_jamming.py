"""One compaction model per tow: how far a laterally squeezed tow compacts before it jams.

Issue 24: the sheared unit cell (``preform.geometry.sheared_cell``), the woven shear law
(``preform.plugins.woven.shear``), and so the draped preform's thickness, Vf and permeability,
all read a tow's lateral compaction from here, with the tow's own constants (YAML
``tow_types.<name>.compaction``, defaults per fibre family below). No run holds two behaviours
of the same tow. The model, in the order a shear angle γ meets it (docs/physics.md, "One tow"):

1. **Locking** [P, paper Eqn 3-4]: the tow keeps its as-built width w₀ until its neighbours
   touch, at γ_L = acos(w₀/Ts); then its width is Ts·cos γ.
2. **Compaction at constant height** [P]: a narrowed tow's fibre fraction is V = V₀·w₀/w. Its
   lateral (bundle) stress σ_b(V) is the Cai–Gutowski law (``preform.plugins.woven.compaction``;
   Gutowski 1987 with onset V_o = V₀ [C]: the as-built tow carries no lateral stress).
3. **The tow's own limit V_c** [C]: at σ_b(V_c) = p, the through-thickness pressure holding the
   tow flat (``confining_pressure_kPa``; default 100 kPa, a vacuum-bagged preform), squeezing
   it further is cheaper in height than in width, so where its section is held (below) it
   stops compacting. V_c never passes the pole guard V_cap = V_a(1 − ε).
4. **Jamming from the weave** [C, from the unit cell]: a share s of a tow's crossings are
   interlaced (the crossing tow changes side there: s = interlacings / crossings = 1/F, F the
   mean float length; plain weave s = 1, 2/2 twill and crowfoot ½, 5HS 0.4, 8HS ¼). At an
   interlacing the crossing tow passes between the tow and its neighbour and holds its section,
   so there the tow compacts only to V_c; along a float neighbouring tows lie side by side with
   nothing between them and nest, up to V_cap. The tow family jams when its fraction reaches
   the crossing-weighted mean

       V_J = s·V_c + (1 − s)·V_cap,

   so with the same tows a longer float never jams earlier (V_J rises as s falls), and a plain
   weave jams at its tows' own limit. That floats let threads pack closer is textile practice
   (Peirce 1937's jammed cloth; the maximum sett of a weave rises with its float length) [L,
   qualitative]; the weighted mean is this project's rule [C]. Between V_c and V_J the lateral
   stress stays at p (the interlaced parts are at their limit, the floats nest).
5. **Past jamming**: the tow cannot compact further; the sheared cell thickens at constant V_J
   and the shear law holds its torque (the fabric wrinkles: a limit, not an energy).

SI units: Pa, m; fractions dimensionless.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

from preform.plugins.woven.compaction import SQUARE_PACKING, BundleCompaction

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np

#: Default through-thickness pressure holding a tow flat [Pa]: one atmosphere, a
#: vacuum-bagged preform (liquid moulding, where Vf and permeability are asked) [C].
DEFAULT_CONFINING_PRESSURE_PA = 1.0e5
#: Pole guard ε of the bundle law: fractions are followed up to V_a(1 − ε) [C].
DEFAULT_PACKING_MARGIN = 1e-2


@dataclass(frozen=True)
class TowCompaction:
    """A tow's compaction constants (SI). Defaults: ``FIBRE_COMPACTION`` by fibre family."""

    #: Through-thickness pressure p holding the tow flat [Pa] (step 3 of the module doc).
    confining_pressure_Pa: float = DEFAULT_CONFINING_PRESSURE_PA
    #: Gutowski β, span-to-height ratio of the fibre waves [-]; A_s = 3πE_f/β⁴.
    fibre_wave_ratio: float = 350.0
    #: Gutowski V_a, maximum attainable fibre fraction [-].
    max_fraction: float = SQUARE_PACKING
    #: Pole guard ε [-]: V ≤ V_a(1 − ε).
    packing_margin: float = DEFAULT_PACKING_MARGIN
    #: Cai–Gutowski coupling compliance F_bl [1/Pa] (0: Gutowski's stress exactly).
    coupling_compliance: float = 0.0


#: Compaction constants by fibre family, each with its source. Gutowski et al. (1987, J. Compos.
#: Mater. 21:650, as PHYSICS.md §3 quotes it [L, constants to verify against the original])
#: fitted β ≈ 350, V_a ≈ 0.8 (taken here as square packing π/4 ≈ 0.785, the ceiling for round
#: fibres without nesting) to AS4 carbon fibre beds; no
#: published set for glass or aramid tows was available to us, so they take the same β and V_a,
#: marked illustrative [C]. The fibre modulus enters A_s through the fibre (E-glass 72 GPa, so a
#: glass tow is ~3× softer laterally than carbon at the same fractions).
FIBRE_COMPACTION: dict[str, TowCompaction] = {
    "carbon": TowCompaction(fibre_wave_ratio=350.0, max_fraction=SQUARE_PACKING),
    "glass": TowCompaction(fibre_wave_ratio=350.0, max_fraction=SQUARE_PACKING),
    "aramid": TowCompaction(fibre_wave_ratio=350.0, max_fraction=SQUARE_PACKING),
    "polyester": TowCompaction(fibre_wave_ratio=350.0, max_fraction=SQUARE_PACKING),
}
#: Where each default comes from, for ``materials show`` and the docs.
FIBRE_COMPACTION_SOURCE: dict[str, str] = {
    "carbon": "Gutowski et al. 1987 (AS4 carbon beds): beta 350, V_a ~ 0.8 (pi/4 used) [L]",
    "glass": "Gutowski et al. 1987 carbon values, illustrative for glass (no glass set) [C]",
    "aramid": "Gutowski et al. 1987 carbon values, illustrative for aramid [C]",
    "polyester": "Gutowski et al. 1987 carbon values, illustrative for polyester [C]",
}


def compaction_for(fibre_name: str) -> TowCompaction:
    """The default compaction constants of a fibre family (``TowCompaction()`` if unknown)."""
    return FIBRE_COMPACTION.get(fibre_name, TowCompaction())


#: Fractions probed per call of the bundle law while bracketing V_c: each round shrinks the
#: bracket PROBES + 1 times, so ~7 rounds take one of 0.3 to neighbouring floats (a bisection
#: took 80 calls, ~15 ms per tow; issue 15h).
PROBES = 255
#: Bound on the rounds (the bracket stops shrinking long before: a guard, not a tolerance).
MAX_ROUNDS = 40


def bundle_law(
    initial_fraction: float, fibre_modulus_Pa: float, settings: TowCompaction
) -> BundleCompaction:
    """The tow's guarded Cai–Gutowski bundle law, onset at its as-built fraction V₀.

    Raises ValueError (in words) when V₀ is already at or above the packing cap: such a tow
    cannot exist."""
    cap = settings.max_fraction * (1.0 - settings.packing_margin)
    if not 0.0 < initial_fraction < cap:
        raise ValueError(
            f"the tow's as-built fibre fraction {initial_fraction:.3f} (fibre area over its "
            f"elliptical section) is not below the packing cap {cap:.3f}: the tow's width or "
            "height is too small for its linear density"
        )
    return BundleCompaction(
        fibre_modulus=fibre_modulus_Pa,
        span_to_height=settings.fibre_wave_ratio,
        initial_fraction=initial_fraction,
        onset_fraction=initial_fraction,
        max_fraction=settings.max_fraction,
        coupling_compliance=settings.coupling_compliance,
        packing_margin=settings.packing_margin,
    )


@lru_cache(maxsize=256)  # a table of sheared cells asks the same tows at every angle
def jamming_fraction(
    initial_fraction: float, fibre_modulus_Pa: float, settings: TowCompaction | None = None
) -> float:
    """V_c [-], the tow's own limit: σ_b(V_c) = p, at most the packing cap (step 3).

    Raises ValueError (in words) when V₀ is already at or above the packing cap."""
    import numpy as np

    s = settings or TowCompaction()
    bundle = bundle_law(initial_fraction, fibre_modulus_Pa, s)
    cap = bundle.cap_fraction
    if float(bundle.stress(np.asarray(cap))) <= s.confining_pressure_Pa:
        return float(cap)
    # σ_b is monotone in V: bracket the root down to neighbouring floats (lo below p, hi at or
    # above it), PROBES fractions per bundle-law call (a bisection paid one call per halving).
    lo, hi = initial_fraction, cap
    for _ in range(MAX_ROUNDS):
        probes = np.linspace(lo, hi, PROBES + 2)[1:-1]
        reached = bundle.stress(probes) >= s.confining_pressure_Pa
        first = int(np.argmax(reached)) if reached.any() else PROBES
        new_lo = float(probes[first - 1]) if first > 0 else lo
        new_hi = float(probes[first]) if first < PROBES else hi
        if (new_lo, new_hi) == (lo, hi):  # no float between them: resolved
            break
        lo, hi = new_lo, new_hi
    return lo


def weave_jamming_fraction(
    initial_fraction: float,
    fibre_modulus_Pa: float,
    settings: TowCompaction,
    interlaced_share: float,
) -> float:
    """V_J [-] of a tow family whose crossings are interlaced in the share s ∈ [0, 1] (step 4):
    s·V_c + (1 − s)·V_cap, never below V_c nor above the cap."""
    if not 0.0 <= interlaced_share <= 1.0:
        raise ValueError(f"interlaced share {interlaced_share!r} must lie in [0, 1]")
    own = jamming_fraction(initial_fraction, fibre_modulus_Pa, settings)
    cap = bundle_law(initial_fraction, fibre_modulus_Pa, settings).cap_fraction
    return min(cap, max(own, interlaced_share * own + (1.0 - interlaced_share) * cap))


def lateral_stress(bundle: BundleCompaction, own_limit: float, fraction: np.ndarray) -> np.ndarray:
    """Lateral stress [Pa] of a tow at fibre fraction(s) V (steps 2-4): the bundle law up to
    the tow's own limit V_c; from there to V_J it stays at σ_b(V_c) = p (the interlaced parts
    are at their limit while the floats nest)."""
    import numpy as np

    v = np.asarray(fraction, dtype=float)
    return np.asarray(bundle.stress(np.minimum(v, own_limit)), dtype=float)


def jamming_angle(initial_fraction: float, width: float, spacing: float, jam: float) -> float:
    """|γ| [rad] at which a tow of fraction V₀ and width w₀ at spacing Ts reaches V_J:
    cos γ = V₀·w₀/(V_J·Ts) (0 when it is there already)."""
    return math.acos(min(1.0, initial_fraction * width / (jam * spacing)))
