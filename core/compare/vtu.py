"""Measured points with their errors against the drape, for ParaView (.vtu, mm, degrees).

One vertex cell per point; the point data holds the measured and predicted angles, the errors
and the flags (0/1) of ``preform.compare.comparison.Comparison``. Points that were not
compared keep NaN errors, which ParaView draws in its NaN colour: "no value", never a default.
"""

from __future__ import annotations

import os

import numpy as np

from preform.base.atomic import atomic_path
from preform.compare.comparison import FLAGS, Comparison
from preform.export.vtu import _require_meshio


def write_comparison_vtu(comparison: Comparison, path: str | os.PathLike[str]) -> None:
    """Write the measured points [mm] as vertices with point data ``error_u_deg``,
    ``error_v_deg``, ``error_shear_deg``, ``abs_angle_error_deg`` (the larger family's),
    measured and predicted angles and shear [deg], ``tool_gap_mm``, ``net_gap_mm`` and the
    flags ``compared``, ``off_tool``, ``off_net``, ``outside_part``, ``near_fold``,
    ``wrinkle_zone`` (0/1)."""
    meshio = _require_meshio()
    c = comparison
    n = len(c.point_mm)
    data: dict[str, np.ndarray] = {
        "error_u_deg": c.error_u_deg,
        "error_v_deg": c.error_v_deg,
        "error_shear_deg": c.error_shear_deg,
        "abs_angle_error_deg": largest_angle_error(c),
        "measured_angle_u_deg": c.measured_angle_u_deg,
        "measured_angle_v_deg": c.measured_angle_v_deg,
        "predicted_angle_u_deg": c.predicted_angle_u_deg,
        "predicted_angle_v_deg": c.predicted_angle_v_deg,
        "measured_shear_deg": c.measured_shear_deg,
        "predicted_shear_deg": c.predicted_shear_deg,
        "tool_gap_mm": c.tool_gap_mm,
        "net_gap_mm": c.net_gap_mm,
        "compared": c.compared.astype(np.int32),
    }
    for flag in FLAGS:
        data[flag] = np.asarray(getattr(c, flag)).astype(np.int32)
    cells = [("vertex", np.arange(n, dtype=np.int64).reshape(-1, 1))]
    out = meshio.Mesh(
        points=np.asarray(c.point_mm, dtype=float),
        cells=cells,
        point_data={k: np.asarray(v, dtype=float if v.dtype.kind == "f" else np.int32)
                    for k, v in data.items()},
    )  # fmt: skip
    with atomic_path(path) as tmp:
        meshio.write(tmp, out, file_format="vtu")


def largest_angle_error(comparison: Comparison) -> np.ndarray:
    """Per point, the larger |error| of the two families, else |shear error| [deg]; NaN where
    nothing was compared."""
    both = np.abs(np.column_stack([comparison.error_u_deg, comparison.error_v_deg]))
    with np.errstate(all="ignore"):
        fibre = np.where(np.all(np.isnan(both), axis=1), np.nan, np.nanmax(
            np.where(np.isnan(both), -np.inf, both), axis=1))  # fmt: skip
    return np.asarray(np.where(np.isnan(fibre), np.abs(comparison.error_shear_deg), fibre))
