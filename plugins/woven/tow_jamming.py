"""Where a laterally squeezed tow stops compacting and starts to thicken: the jamming fraction.

The sheared unit cell (``preform.geometry.sheared_cell``) narrows a locked tow; this module says
up to which fibre fraction V_j the narrowing compacts the fibre bed at constant height, using the
same Cai–Gutowski bundle law the plain-weave shear law uses (``preform.plugins.woven.compaction``,
reused, not copied). Modelling choice [C] (docs/physics.md, "Sheared unit cell"): the tow keeps
its height while its lateral compaction stress σ_b(V) is below the through-thickness pressure p
that holds it flat; at σ_b(V_j) = p it is cheaper for the tow to grow in height, so it thickens at
constant V_j. V_j never passes the law's packing cap V_a(1 − ε) < V_a ≤ π/4. The bundle law's
parameters default to the woven ``friction_compaction`` law's defaults (β = 30, V_a = π/4,
ε = 0.01, V_o = V₀, F_bl = 0). SI units: Pa, fractions dimensionless.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from preform.plugins.woven.compaction import SQUARE_PACKING, BundleCompaction


@dataclass(frozen=True)
class TowCompaction:
    """Settings of the tows' lateral compaction in a sheared cell (SI)."""

    #: Through-thickness pressure p holding the tows flat [Pa]. Default one atmosphere, the
    #: pressure of a vacuum-bagged preform in liquid moulding, where permeability is asked [C].
    confining_pressure_Pa: float = 1.0e5
    #: Gutowski β, fibre-wave span over height [-] (woven law's default 30 [C]).
    fibre_wave_ratio: float = 30.0
    #: Gutowski V_a, maximum attainable fraction [-] (square packing π/4).
    max_fraction: float = SQUARE_PACKING
    #: Pole guard ε: V_j ≤ V_a(1 − ε) [-] (woven law's default 0.01).
    packing_margin: float = 1e-2


#: Fractions probed per call of the bundle law while bracketing V_j: each round shrinks the
#: bracket PROBES + 1 times, so ~7 rounds take one of 0.3 to neighbouring floats (a bisection
#: took 80 calls, ~15 ms per tow; issue 15h).
PROBES = 255
#: Bound on the rounds (the bracket stops shrinking long before: a guard, not a tolerance).
MAX_ROUNDS = 40


@lru_cache(maxsize=256)  # a table of sheared cells asks the same tows at every angle
def jamming_fraction(
    initial_fraction: float, fibre_modulus_Pa: float, settings: TowCompaction | None = None
) -> float:
    """V_j [-] of a tow of as-built fraction V₀ and fibre modulus E_f [Pa]: σ_b(V_j) = p.

    Raises ValueError (in words) when V₀ is already at or above the packing cap: such a tow
    cannot exist, and no sheared cell is built for it.
    """
    s = settings or TowCompaction()
    cap = s.max_fraction * (1.0 - s.packing_margin)
    if not 0.0 < initial_fraction < cap:
        raise ValueError(
            f"the tow's as-built fibre fraction {initial_fraction:.3f} (fibre area over its "
            f"elliptical section) is not below the packing cap {cap:.3f}: the tow's width or "
            "height is too small for its linear density"
        )
    bundle = BundleCompaction(
        fibre_modulus=fibre_modulus_Pa,
        span_to_height=s.fibre_wave_ratio,
        initial_fraction=initial_fraction,
        onset_fraction=initial_fraction,
        max_fraction=s.max_fraction,
        packing_margin=s.packing_margin,
    )
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
