"""Measured shear tests → shear angle, normalised shear force F_s/L and torque per area.

Picture frame [P/L] (side L pin to pin, cross-head displacement δ, force F):
half corner angle ψ = acos((√2 L + δ)/(2L)), γ = 90° − 2ψ, frame-side force F_s = F/(2 cos ψ).
Power balance F·dδ = C·dγ·A (dδ/dγ = L sin ψ) gives the torque per undeformed fabric area
C = F·L·sin ψ / A; with the full frame A = L² this is C = F sin ψ / L = F_s cos γ / L. For a
cruciform specimen whose sheared square has side L_fab < L, A = L_fab² [L: Harrison et al.,
Compos. A 35 (2004) 915]. Reported F_s/L is always C / cos γ, the force per length a full frame
of the same fabric would need, so results of different frames compare directly.

Bias extension [L: Harrison et al. 2008; Cao et al., Compos. A 39 (2008) 1037] (H × W, H ≥ 2W,
fibres at ±45°): central region A (area HW − 3W²/2) shears by γ = 90° − 2 acos((H − W + δ) /
(√2 (H − W))), regions B (area W²) by γ/2, regions C (W²/2) not at all. Energy balance with
dδ/dγ = (H − W)(cos(γ/2) − sin(γ/2))/2 gives the recursive normalisation

    F_s/L(γ) = [(H/W − 1)·F·(cos γ/2 − sin γ/2) − W·F_s/L(γ/2)·cos γ/2] / ((2H − 3W) cos γ).

Lengths here are in mm and forces in N (the units of a test file); angles in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from preform.base.arrays import FloatArray

#: cos γ below this is treated as the 90° singularity of the normalisations.
_COS_FLOOR = 1e-9


@dataclass(frozen=True)
class NormalisedShear:
    """A normalised shear test: shear angle γ [rad], F_s/L [N/mm], torque per area C [N·m/m²]."""

    shear_angle: FloatArray
    force_per_length_N_per_mm: FloatArray
    torque_N_per_m: FloatArray


def picture_frame_shear_angle(displacement_mm: ArrayLike, side_mm: float) -> FloatArray:
    """Shear angle γ [rad] of a picture frame of side L [mm] at cross-head displacement δ [mm]."""
    ratio = (math.sqrt(2.0) * side_mm + np.asarray(displacement_mm, dtype=float)) / (2.0 * side_mm)
    half_corner = np.arccos(np.clip(ratio, -1.0, 1.0))
    return np.asarray(np.pi / 2 - 2.0 * half_corner, dtype=float)


def picture_frame_displacement(shear_angle: ArrayLike, side_mm: float) -> FloatArray:
    """Cross-head displacement δ [mm] giving shear angle γ [rad] (inverse of the above)."""
    half_corner = (np.pi / 2 - np.asarray(shear_angle, dtype=float)) / 2.0
    return np.asarray(2.0 * side_mm * np.cos(half_corner) - math.sqrt(2.0) * side_mm, dtype=float)


def normalise_picture_frame(
    displacement_mm: ArrayLike,
    force_N: ArrayLike,
    side_mm: float,
    fabric_side_mm: float | None = None,
) -> NormalisedShear:
    """Normalise a picture-frame test (δ [mm], F [N], frame side [mm], cruciform fabric side [mm])."""
    if side_mm <= 0.0 or (fabric_side_mm is not None and fabric_side_mm <= 0.0):
        raise ValueError("frame and fabric sides must be positive")
    gamma = picture_frame_shear_angle(displacement_mm, side_mm)
    force = np.asarray(force_N, dtype=float)
    half_corner = (np.pi / 2 - gamma) / 2.0
    fabric_side = side_mm if fabric_side_mm is None else fabric_side_mm
    torque = force * side_mm * np.sin(half_corner) / fabric_side**2 * 1000.0  # N/mm → N/m
    force_per_length = torque / np.maximum(np.cos(gamma), _COS_FLOOR) / 1000.0
    return NormalisedShear(gamma, force_per_length, torque)


def bias_extension_shear_angle(
    displacement_mm: ArrayLike, height_mm: float, width_mm: float
) -> FloatArray:
    """Shear angle γ [rad] of the central region of a bias-extension specimen H × W [mm]."""
    _check_bias(height_mm, width_mm)
    gauge = height_mm - width_mm
    ratio = (gauge + np.asarray(displacement_mm, dtype=float)) / (math.sqrt(2.0) * gauge)
    return np.asarray(np.pi / 2 - 2.0 * np.arccos(np.clip(ratio, -1.0, 1.0)), dtype=float)


def bias_extension_displacement(
    shear_angle: ArrayLike, height_mm: float, width_mm: float
) -> FloatArray:
    """Displacement δ [mm] giving central shear angle γ [rad] (inverse of the above)."""
    gauge = height_mm - width_mm
    half = (np.pi / 2 - np.asarray(shear_angle, dtype=float)) / 2.0
    return np.asarray(math.sqrt(2.0) * gauge * np.cos(half) - gauge, dtype=float)


def _check_bias(height_mm: float, width_mm: float) -> None:
    if width_mm <= 0.0 or height_mm < 2.0 * width_mm:
        raise ValueError("bias extension needs W > 0 and H ≥ 2W")


def normalise_bias_extension(
    displacement_mm: ArrayLike, force_N: ArrayLike, height_mm: float, width_mm: float
) -> NormalisedShear:
    """Energy-based normalisation of a bias-extension test [L: Harrison 2008, Cao 2008].

    Points are processed in order of increasing γ; F_s/L(γ/2) is interpolated linearly from the
    points already normalised; below the first of them the curve is taken as linear through
    zero (a specimen at rest carries no force).
    Points must increase in displacement.
    """
    _check_bias(height_mm, width_mm)
    gamma = bias_extension_shear_angle(displacement_mm, height_mm, width_mm)
    force = np.asarray(force_N, dtype=float)
    if np.any(np.diff(gamma) < 0.0):
        raise ValueError("displacements must be non-decreasing")
    h, w = height_mm, width_mm
    known_angle = [0.0]
    known_force = [0.0]
    out = np.empty_like(gamma)
    for i, (g, f) in enumerate(zip(gamma, force, strict=True)):
        half = 0.5 * g
        drive = (h / w - 1.0) * f * (math.cos(half) - math.sin(half))
        base = (2.0 * h - 3.0 * w) * max(math.cos(g), _COS_FLOOR)
        if len(known_angle) == 1 or half < known_angle[1]:
            # Below the first normalised point the curve is taken as linear through zero,
            # F_s/L(γ/2) = F_s/L(γ)/2, and the balance is solved for F_s/L(γ) directly.
            out[i] = drive / (base + 0.5 * w * math.cos(half))
        else:
            previous = float(np.interp(half, known_angle, known_force))
            out[i] = (drive - w * previous * math.cos(half)) / base
        if g > known_angle[-1]:
            known_angle.append(float(g))
            known_force.append(float(out[i]))
    torque = out * np.cos(gamma) * 1000.0
    return NormalisedShear(gamma, out, torque)


def bias_extension_force(
    shear_angle: ArrayLike,
    force_per_length_N_per_mm: ArrayLike,
    half_angle_force: ArrayLike,
    height_mm: float,
    width_mm: float,
) -> FloatArray:
    """Axial force F [N] of a bias-extension test from F_s/L [N/mm] at γ and at γ/2 (the energy
    balance solved forwards; used to synthesise test data from a known law)."""
    g = np.asarray(shear_angle, dtype=float)
    h, w = height_mm, width_mm
    half = 0.5 * g
    numerator = (2.0 * h - 3.0 * w) * np.cos(g) * np.asarray(
        force_per_length_N_per_mm, dtype=float
    ) + w * np.asarray(half_angle_force, dtype=float) * np.cos(half)
    return np.asarray(numerator / ((h / w - 1.0) * (np.cos(half) - np.sin(half))), dtype=float)
