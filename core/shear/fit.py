"""Fit normalised shear data (angle [deg], F_s/L [N/mm]) to a ``polynomial`` or ``tabulated`` law.

Polynomial: least squares in F_s/L over powers 1..N of the angle in degrees; by default with no
constant term, so the fitted curve passes through zero (an unsheared fabric carries no shear
force), or with one (``through_zero=False``; ``preform fit --free-intercept``).
Tabulated: the points are averaged in bins of ``step_deg`` and negative averages set to zero.
Fit quality is reported against the data as R² and RMSE [N/mm]. ``shear_law_block`` turns one or
two fits (γ > 0 and γ < 0) into a ``shear_law`` mapping that validates as it is.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import yaml
from numpy.typing import ArrayLike

from preform.base.arrays import FloatArray
from preform.shear.laws import PolynomialParams, TabulatedParams


@dataclass(frozen=True)
class FitQuality:
    """Goodness of fit: coefficient of determination R² [-], RMSE [N/mm], number of points."""

    r_squared: float
    rmse_N_per_mm: float
    points: int


@dataclass(frozen=True)
class PolynomialFit:
    """F_s/L [N/mm] = Σ a_k (γ/deg)^k with a_0 = 0; fitted over [0, max_angle_deg]."""

    coefficients_N_per_mm: tuple[float, ...]
    max_angle_deg: float
    quality: FitQuality

    def __call__(self, angle_deg: ArrayLike) -> FloatArray:
        """F_s/L [N/mm] at angles [deg]."""
        return np.asarray(
            np.polynomial.polynomial.polyval(
                np.asarray(angle_deg, float), self.coefficients_N_per_mm
            ),
            dtype=float,
        )


@dataclass(frozen=True)
class TableFit:
    """Bin-averaged points (angle [deg], F_s/L [N/mm]) for a tabulated law."""

    angle_deg: tuple[float, ...]
    force_N_per_mm: tuple[float, ...]
    quality: FitQuality


def _clean(angle_deg: ArrayLike, force_N_per_mm: ArrayLike) -> tuple[FloatArray, FloatArray]:
    a = np.abs(np.asarray(angle_deg, dtype=float).ravel())
    f = np.abs(np.asarray(force_N_per_mm, dtype=float).ravel())
    keep = np.isfinite(a) & np.isfinite(f) & (a < 90.0)
    if a.shape != f.shape or np.count_nonzero(keep) < 2:
        raise ValueError("need at least two finite (angle, force) points of equal count")
    return a[keep], f[keep]


def _quality(data: FloatArray, model: FloatArray) -> FitQuality:
    residual = data - model
    total = float(np.sum((data - data.mean()) ** 2))
    sse = float(np.sum(residual**2))
    r2 = 1.0 - sse / total if total > 0.0 else (1.0 if sse == 0.0 else 0.0)
    return FitQuality(r2, float(np.sqrt(sse / data.size)), int(data.size))


def fit_polynomial(
    angle_deg: ArrayLike,
    force_N_per_mm: ArrayLike,
    degree: int,
    *,
    through_zero: bool = True,
) -> PolynomialFit:
    """Least-squares polynomial of F_s/L [N/mm] in the shear angle [deg].

    ``through_zero`` (the default) leaves out the constant term, so the curve passes through
    zero: an unsheared fabric carries no shear force. With ``through_zero=False`` the constant
    a_0 [N/mm] is fitted too (a test rig's friction or a preload offset shows there).
    Angles and forces are taken as magnitudes (one sense per call). ``degree`` ≥ 1.
    """
    if degree < 1:
        raise ValueError("degree must be at least 1")
    a, f = _clean(angle_deg, force_N_per_mm)
    scale = float(a.max()) or 1.0  # scaled powers keep the normal equations well conditioned
    first = 1 if through_zero else 0
    powers = np.arange(first, degree + 1)
    design = (a[:, None] / scale) ** powers
    solution, *_ = np.linalg.lstsq(design, f, rcond=None)
    fitted = (solution / scale**powers).tolist()
    coefficients = (0.0, *fitted) if through_zero else tuple(fitted)
    fit = PolynomialFit(tuple(coefficients), float(a.max()), FitQuality(0.0, 0.0, 0))
    return PolynomialFit(fit.coefficients_N_per_mm, fit.max_angle_deg, _quality(f, fit(a)))


def fit_table(angle_deg: ArrayLike, force_N_per_mm: ArrayLike, step_deg: float = 2.0) -> TableFit:
    """Average F_s/L [N/mm] in angle bins of ``step_deg`` [deg] for a tabulated law."""
    if step_deg <= 0.0:
        raise ValueError("step_deg must be positive")
    a, f = _clean(angle_deg, force_N_per_mm)
    bins = np.floor(a / step_deg).astype(int)
    angles, forces = [], []
    for b in np.unique(bins):
        sel = bins == b
        angles.append(float(a[sel].mean()))
        forces.append(max(0.0, float(f[sel].mean())))
    if len(angles) < 2:
        raise ValueError("the data span less than two bins; use a smaller step")
    model = np.interp(a, angles, forces)
    return TableFit(tuple(angles), tuple(forces), _quality(f, model))


def shear_law_block(
    positive: PolynomialFit | TableFit, negative: PolynomialFit | TableFit | None = None
) -> dict[str, Any]:
    """A ``shear_law`` mapping (polynomial or tabulated) from a fit per sense; validated."""
    block: dict[str, Any]
    if isinstance(positive, PolynomialFit):
        block = {
            "law": "polynomial",
            "force_coefficients_N_per_mm": list(positive.coefficients_N_per_mm),
            "max_angle_deg": positive.max_angle_deg,
            "beyond_range": "hold",
        }
        if isinstance(negative, PolynomialFit):
            block["force_coefficients_negative_N_per_mm"] = list(negative.coefficients_N_per_mm)
            block["max_angle_negative_deg"] = negative.max_angle_deg
        elif negative is not None:
            raise TypeError("both senses must be fitted the same way")
        PolynomialParams.model_validate(block)
        return block
    block = {
        "law": "tabulated",
        "angle_deg": list(positive.angle_deg),
        "force_N_per_mm": list(positive.force_N_per_mm),
        "beyond_range": "hold",
    }
    if isinstance(negative, TableFit):
        block["angle_negative_deg"] = list(negative.angle_deg)
        block["force_negative_N_per_mm"] = list(negative.force_N_per_mm)
    elif negative is not None:
        raise TypeError("both senses must be fitted the same way")
    TabulatedParams.model_validate(block)
    return block


def block_to_yaml(block: dict[str, Any], comments: list[str] | None = None) -> str:
    """YAML text ``shear_law: {...}`` ready to paste into a library entry."""
    text = yaml.safe_dump({"shear_law": block}, sort_keys=False, default_flow_style=None)
    header = "".join(f"# {line}\n" for line in comments or [])
    return header + text
