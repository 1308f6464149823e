"""The shear-law contract: what every registered law gives the rest of preform.

Sign convention (used everywhere in preform): the shear angle γ [rad] is the reduction of the
angle between the two fibre families from 90°, signed against the fabric's reference direction
(``FabricBase.reference_direction_deg``): γ > 0 when the fabric lengthens along its reference
direction. For a warp-knit the reference is the stitch, so γ > 0 is shear *parallel* to the
stitch (stitch in tension) and γ < 0 *perpendicular* (stitch slack). Symmetric laws have
C(−γ) = −C(γ).

Units: torque per unit undeformed area C [N·m/m² = N/m]; strain energy per unit area
W [J/m²]; normalised picture-frame shear force F_s/L [N/mm].
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

    FloatArray = NDArray[np.float64]


@runtime_checkable
class ShearLaw(Protocol):
    """A fabric's in-plane shear response, vectorised over signed shear angle γ [rad]."""

    #: Angle [rad, > 0] past which the fabric locks (wrinkles), or None.
    locking_angle: float | None
    #: Angle [rad, > 0] at which stitching fails in the parallel sense, or None.
    failure_angle: float | None

    def torque(self, gamma: ArrayLike) -> FloatArray:
        """Torque per unit undeformed area C(γ) [N·m/m²] at signed shear angles γ [rad]."""
        ...

    def energy(self, gamma: ArrayLike) -> FloatArray:
        """Strain energy per unit undeformed area W(γ) = ∫_0^γ C(g) dg [J/m²]."""
        ...


def force_per_length_N_per_mm(law: ShearLaw, gamma: ArrayLike) -> FloatArray:
    """Normalised picture-frame shear force F_s/L [N/mm] at signed shear angles γ [rad].

    Power balance on a picture frame of side L: C(γ) = F_s·cos γ / L, so F_s/L = C / cos γ
    (N/m, divided by 1000 for N/mm). At |γ| → 90° the frame is singular; cos γ is floored at
    1e-9 so the result stays finite and grows without bound, as the kinematics say it must.
    """
    import numpy as np

    g = np.asarray(gamma, dtype=float)
    cos_g = np.maximum(np.cos(g), 1e-9)
    return np.asarray(law.torque(g), dtype=float) / cos_g / 1000.0
