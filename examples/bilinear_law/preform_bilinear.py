"""A third-party preform plugin: a bilinear shear law (worked example of CONTRIBUTING.md).

Torque per unit area rises with slope k0 up to the locking angle, then with the steeper slope
k1: the simplest law that still has a locking angle. Symmetric in the shear sense.
Units: torque per unit area [N·m/m²], angles [rad] inside, [deg] in YAML.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from preform import hookimpl


class BilinearParams(BaseModel):
    """The YAML block: ``shear_law: {law: bilinear, ...}``."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    law: Literal["bilinear"]
    initial_slope_N_per_m_per_deg: float = Field(
        ge=0, description="Torque per area per degree of shear below locking [N·m/m²/deg]."
    )
    locked_slope_N_per_m_per_deg: float = Field(
        ge=0, description="Torque per area per degree of shear past locking [N·m/m²/deg]."
    )
    locking_angle_deg: float = Field(gt=0, lt=90, description="Locking angle [deg].")


class BilinearLaw:
    """C(γ) = k0·γ for |γ| ≤ γ_L, k0·γ_L + k1·(|γ| − γ_L) beyond (odd in γ)."""

    failure_angle = None

    def __init__(self, k0: float, k1: float, locking_angle: float) -> None:
        self.k0, self.k1, self.locking_angle = k0, k1, locking_angle

    def torque(self, gamma: Any) -> np.ndarray:
        g = np.abs(np.asarray(gamma, dtype=float))
        below = self.k0 * np.minimum(g, self.locking_angle)
        beyond = self.k1 * np.maximum(g - self.locking_angle, 0.0)
        return np.sign(gamma) * (below + beyond)

    def energy(self, gamma: Any) -> np.ndarray:
        # exact antiderivative of the piecewise-linear torque
        g = np.abs(np.asarray(gamma, dtype=float))
        gl = np.minimum(g, self.locking_angle)
        over = np.maximum(g - self.locking_angle, 0.0)
        return 0.5 * self.k0 * gl**2 + self.k0 * self.locking_angle * over + 0.5 * self.k1 * over**2


def build(params: BilinearParams, fabric: Any) -> BilinearLaw:
    per_rad = 180.0 / np.pi  # slopes are given per degree; the law works in radians
    return BilinearLaw(
        params.initial_slope_N_per_m_per_deg * per_rad,
        params.locked_slope_N_per_m_per_deg * per_rad,
        np.radians(params.locking_angle_deg),
    )


@hookimpl
def preform_register_shear_laws(register: Any) -> None:
    register.add("bilinear", BilinearParams, build)
