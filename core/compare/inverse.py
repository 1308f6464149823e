"""The set-up that best explains a measurement: the inverse search over the drape's start.

The drape is re-run (kinematic net, the scene's own generators) over the start point (plan x,
y [mm]), the orientation of the first generator and the generator angle [deg] to minimise
Σ (error / σ)² over every measured fibre angle and every shear-only point, with σ each point's
uncertainty (:meth:`preform.compare.measurement.Measurement.sigma_deg`), in two phases:

1. Nelder-Mead on the robust sum Σ log(1 + (error / 3σ)²) from the scene's set-up. On a tool
   with sharp edges (the hat mould's vertical walls) the fibres a point sees jump as the start
   moves by a fraction of a millimetre (which node reaches a wall), so the sum of squares is
   rough away from the optimum and a gradient step stalls; the robust sum, searched without
   derivatives, walks over the jumps (on the hat mould: from a start 3.6 mm off to the truth).
2. ``scipy.optimize.least_squares`` (trust region, bounded, finite-difference Jacobian) on the
   sum of squares itself from there. The uncertainty of the best
set-up is the linearised one of the calibration (``preform.shear.calibrate``): cov =
s²(JᵀJ)⁻¹ from the Jacobian at the optimum, s² the residual variance per degree of freedom,
so a measurement whose stated uncertainty is right gives s² ≈ 1, and one that states none
(σ = 1° assumed) gets its scatter from the residuals. The 95 % interval is ±1.96 σ.

What it tells a user: when the best set-up brings the errors down to the measurement's own
scatter (s² near 1), the mismatch was the set-up (the ply placed 3° off); when a large error
remains, it is the physics (or the measurement). The residual comparison shows where.

Points off the tool are left out before the search; a point that falls past the net's edge at
some set-up keeps the interpolation of the nearest edge cells, so the sum stays smooth.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from preform.base.arrays import FloatArray
from preform.compare.comparison import Comparison, OnTool, compare, evaluate, on_tool
from preform.compare.measurement import MM, Measurement
from preform.drape.engine.net import DrapeError, drape
from preform.drape.engine.result import DrapeResult

#: What the search may vary, and the parameters each stands for.
VARIABLES = {
    "start": ("start_x_mm", "start_y_mm"),
    "orientation": ("orientation_deg",),
    "generator_angle": ("generator_angle_deg",),
}
#: How far the search may move each parameter from its starting value [mm, deg].
DEFAULT_REACH = {
    "start_x_mm": 25.0,
    "start_y_mm": 25.0,
    "orientation_deg": 30.0,
    "generator_angle_deg": 30.0,
}
#: Finite-difference step of the Jacobian, relative (mm and degrees are of order one).
DIFF_STEP = 1e-3
#: Phase 1 of the search (module docstring): the Cauchy scale [σ], the first simplex's
#: steps [mm, deg] and the evaluation budget.
ROBUST_SCALE = 3.0
SIMPLEX_STEP = 2.0
ROBUST_EVALUATIONS = 800
#: 95 % two-sided interval of a normal variable, in standard deviations.
Z95 = 1.96
#: Residual variance per degree of freedom below which the set-up explains the mismatch.
EXPLAINED_CHI2 = 2.0


@dataclass(frozen=True)
class SetUp:
    """Where and how the ply is laid: start (plan x, y) [mm], orientation of the first
    generator [deg from the tool's x axis], generator angle [deg]."""

    start_x_mm: float
    start_y_mm: float
    orientation_deg: float
    generator_angle_deg: float

    def as_dict(self) -> dict[str, float]:
        return {
            "start_x_mm": self.start_x_mm,
            "start_y_mm": self.start_y_mm,
            "orientation_deg": self.orientation_deg,
            "generator_angle_deg": self.generator_angle_deg,
        }

    def with_values(self, values: dict[str, float]) -> SetUp:
        return SetUp(**{**self.as_dict(), **values})


@dataclass(frozen=True)
class Explanation:
    """The inverse search's answer (mm, degrees)."""

    initial: SetUp
    best: SetUp
    #: Standard uncertainty of each varied parameter (None: the data do not determine it).
    sigma: dict[str, float | None]
    correlation: list[list[float | None]]
    varied: tuple[str, ...]
    before: Comparison
    after: Comparison
    #: Residual variance per degree of freedom at the optimum, Σ(r/σ)²/(m − p).
    chi2_reduced: float
    residuals: int
    evaluations: int
    converged: bool
    message: str
    #: The drape at the best set-up [m].
    result: DrapeResult = field(repr=False)

    def interval95(self, name: str) -> tuple[float, float] | None:
        s = self.sigma.get(name)
        if s is None:
            return None
        value = self.best.as_dict()[name]
        return (value - Z95 * s, value + Z95 * s)

    @property
    def explained(self) -> bool:
        """The best set-up brings the errors down to the measurement's scatter."""
        return self.chi2_reduced <= EXPLAINED_CHI2

    def words(self) -> str:
        b = self.best.as_dict()
        parts = []
        for name in self.varied:
            s = self.sigma.get(name)
            unit = "mm" if name.endswith("_mm") else "°"
            spread = "undetermined" if s is None else f"± {s:.2g}"
            parts.append(f"{name.removesuffix('_mm').removesuffix('_deg')} {b[name]:.4g}{unit} "
                         f"{spread}")  # fmt: skip
        rms_before = self.before.statistics().get("angle_rms_deg")
        rms_after = self.after.statistics().get("angle_rms_deg")
        change = (
            f"angle error rms {rms_before:.3g}° → {rms_after:.3g}°"
            if rms_before is not None and rms_after is not None
            else ""
        )
        verdict = (
            "the set-up explains the mismatch (residuals at the measurement's scatter)"
            if self.explained
            else "a mismatch remains that the set-up does not explain: the physics, or the "
            "measurement (see the residual map)"
        )
        return f"best set-up: {', '.join(parts)}; {change}; s² = {self.chi2_reduced:.3g}: {verdict}"

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "varied": list(self.varied),
            "initial": self.initial.as_dict(),
            "best": self.best.as_dict(),
            "sigma": dict(self.sigma),
            "interval95": {n: self.interval95(n) for n in self.varied},
            "correlation": self.correlation,
            "chi2_reduced": self.chi2_reduced,
            "residuals": self.residuals,
            "evaluations": self.evaluations,
            "converged": self.converged,
            "message": self.message,
            "explained": self.explained,
            "uncertainty": "linearised: Jacobian covariance scaled by the residual variance",
            "before": self.before.statistics(),
            "after": self.after.statistics(),
            "words": self.words(),
        }
        return out


def _names(vary: Sequence[str]) -> tuple[str, ...]:
    unknown = [v for v in vary if v not in VARIABLES]
    if unknown or not vary:
        raise ValueError(
            f"vary must name some of {', '.join(VARIABLES)}; got {', '.join(vary) or 'nothing'}"
        )
    return tuple(name for v in VARIABLES if v in vary for name in VARIABLES[v])


def explain(
    measurement: Measurement,
    surface: Any,
    settings: dict[str, Any],
    initial: SetUp,
    *,
    vary: Sequence[str] = ("start", "orientation", "generator_angle"),
    reach: dict[str, float] | None = None,
    max_gap_mm: float | None = None,
    energy_of: Callable[[DrapeResult], Any] | None = None,
    loss: str = "linear",
    diff_step: float = DIFF_STEP,
    robust_start: bool = True,
) -> Explanation:
    """Search the set-up that best explains ``measurement`` (module docstring).

    ``surface``: the tool [m]; ``settings``: the other keyword arguments of
    :func:`preform.drape.engine.net.drape` (``node_spacing_m``, ``ply``, ``generators``, ``trim``,
    ``tolerance``, ``substeps``; ``preform.drape.steps.drape_settings(...).keywords()`` gives a
    scene's);
    ``initial``: the set-up the search starts from (the scene's). ``vary``: which of
    ``start``, ``orientation``, ``generator_angle``. ``reach``: how far each parameter may move
    [mm, deg] (default :data:`DEFAULT_REACH`). ``energy_of``: the energy field of a net, for
    the residual comparison's wrinkle flags. Raises ValueError when nothing can be compared."""
    from scipy.optimize import least_squares, minimize

    from preform.shear.calibrate import _covariance  # the calibration's linearised uncertainty

    names = _names(vary)
    limits = {**DEFAULT_REACH, **(reach or {})}
    varied = ("start_xy_m", "start_point", "orientation_rad", "generator_angle_rad")
    base = {k: v for k, v in settings.items() if k not in varied}
    if not isinstance(base.get("generators", "geodesic"), str):
        raise ValueError(
            "the inverse search varies the start, orientation and generator angle of "
            "geodesic or plan generators; these generators are given as polylines"
        )
    spacing_mm = float(base["node_spacing_m"]) / MM
    gap = spacing_mm if max_gap_mm is None else float(max_gap_mm)
    tool = on_tool(measurement, surface, gap)
    keep = ~tool.off_tool
    if not keep.any():
        raise ValueError(f"{measurement.source}: no measured point lies on the tool")
    used = measurement.subset(keep)
    used_tool = OnTool(tool.normal[keep], tool.distance_mm[keep], tool.off_tool[keep], gap)
    sigma = used.sigma_deg()
    has_u = np.asarray(used.has_u, dtype=bool)
    has_v = np.asarray(used.has_v, dtype=bool)
    shear_only = np.asarray(used.has_shear_only, dtype=bool)
    residual_count = int(has_u.sum() + has_v.sum() + shear_only.sum())
    x0 = np.zeros(len(names))
    low = np.array([-limits[n] for n in names])
    high = np.array([limits[n] for n in names])
    start = initial.as_dict()
    alpha0 = start["generator_angle_deg"]
    if "generator_angle_deg" in names:
        k = names.index("generator_angle_deg")
        low[k] = max(low[k], 1.0 - alpha0)
        high[k] = min(high[k], 179.0 - alpha0)
    evaluations = 0

    def set_up(x: FloatArray) -> SetUp:
        return initial.with_values({n: start[n] + float(v) for n, v in zip(names, x, strict=True)})

    def net(s: SetUp) -> DrapeResult:
        return drape(
            surface,
            start_xy_m=(s.start_x_mm * MM, s.start_y_mm * MM),
            orientation_rad=math.radians(s.orientation_deg),
            generator_angle_rad=math.radians(s.generator_angle_deg),
            **base,
        )

    def residual(x: FloatArray) -> FloatArray:
        nonlocal evaluations
        evaluations += 1
        try:
            result = net(set_up(x))
            ev = evaluate(result, used, used_tool, gap)
        except (DrapeError, ValueError):
            # no net at this set-up: the worst a line can be off, so the search turns back
            return np.full(residual_count, 90.0) / np.r_[sigma[has_u], sigma[has_v],
                                                        sigma[shear_only]]  # fmt: skip
        r = np.r_[
            ev.error_u_deg[has_u] / sigma[has_u],
            ev.error_v_deg[has_v] / sigma[has_v],
            ev.error_shear_deg[shear_only] / sigma[shear_only],
        ]
        return np.asarray(np.nan_to_num(r, nan=90.0), dtype=float)

    initial_result = net(initial)
    before = compare(initial_result, measurement, surface=surface, max_gap_mm=gap, tool=tool,
                     energy=energy_of(initial_result) if energy_of else None)  # fmt: skip
    x1 = x0
    if robust_start:
        # Phase 1, derivative-free and robust: on a tool with sharp edges the predicted
        # fibres of some points jump as the start moves (which cell reaches a wall), so the
        # sum of squares is rough far from the optimum and a gradient step stalls there.
        # Nelder-Mead on Σ log(1 + (r/c)²) (Cauchy, c = ROBUST_SCALE σ) walks over the jumps.
        def robust_cost(x: FloatArray) -> float:
            r = residual(np.clip(x, low, high)) / ROBUST_SCALE
            return float(np.sum(np.log1p(r * r)))

        simplex = np.vstack([x0, x0 + np.diag(np.minimum(SIMPLEX_STEP, 0.5 * (high - x0)))])
        coarse = minimize(
            robust_cost,
            x0,
            method="Nelder-Mead",
            options={"initial_simplex": simplex, "xatol": 1e-2, "fatol": 1e-3,
                     "maxfev": ROBUST_EVALUATIONS},
        )  # fmt: skip
        x1 = np.clip(coarse.x, low, high)
    # Phase 2: least squares from there, for the optimum and its Jacobian.
    fit = least_squares(
        residual, x1, bounds=(low, high), method="trf", x_scale=1.0, diff_step=diff_step,
        loss=loss,
    )  # fmt: skip
    sig, corr = _covariance(fit.jac, fit.fun, len(names))
    best = set_up(fit.x)
    best_result = net(best)
    after = compare(best_result, measurement, surface=surface, max_gap_mm=gap, tool=tool,
                    energy=energy_of(best_result) if energy_of else None)  # fmt: skip
    dof = max(residual_count - len(names), 1)
    return Explanation(
        initial=initial,
        best=best,
        sigma=dict(zip(names, sig, strict=True)),
        correlation=corr,
        varied=names,
        before=before,
        after=after,
        chi2_reduced=float(fit.fun @ fit.fun) / dof,
        residuals=residual_count,
        evaluations=evaluations,
        converged=bool(fit.status > 0),
        message=str(fit.message),
        result=best_result,
    )
