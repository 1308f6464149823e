"""Tidy tables (CSV, Parquet) and JSON summaries of a draped net.

Columns carry their unit in the name (``x_mm``, ``shear_deg``, ``energy_J_per_m2``) because a
table outlives the code that wrote it. Parquet needs pyarrow (``preform[parquet]``).
"""

from __future__ import annotations

import enum
import json
import math
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.atomic import atomic_open, atomic_path
from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField

if TYPE_CHECKING:
    import pandas as pd

    from preform.drape.properties.preform_fields import PreformField

#: Column order of ``cells_table``.
CELL_COLUMNS: tuple[str, ...] = (
    "i",
    "j",
    "status",
    "in_part",
    "part_share",
    "x_mm",
    "y_mm",
    "z_mm",
    "shear_deg",
    "area_mm2",
    "thickness_ratio",
    "thickness_mm",
    "energy_J_per_m2",
    "past_locking",
    "past_failure",
    "past_jamming",
    "wrinkling",
)


def cell_columns(
    result: DrapeResult, energy: EnergyField | None = None, preform: PreformField | None = None
) -> dict[str, Any]:
    """The columns of ``cells_table`` as numpy arrays (name -> values, in column order), one
    entry a cell: what ``cells_csv`` writes without building a DataFrame. ``status`` is a list
    of CellStatus names; ``past_locking``, ``past_failure``, ``past_jamming`` and ``wrinkling``
    are masked bool arrays (masked: not known). Values as ``cells_table`` describes."""
    n1, n2 = np.asarray(result.cell_status).shape
    ii, jj = np.meshgrid(np.arange(n1), np.arange(n2), indexing="ij")
    valid = np.asarray(result.cell_status == CellStatus.VALID).ravel()

    def on_valid(values: Any) -> np.ndarray:
        out = np.asarray(values, dtype=float).ravel().copy()
        out[~valid] = np.nan
        return out

    def flags(values: Any | None) -> np.ma.MaskedArray:
        if values is None:
            return np.ma.MaskedArray(np.zeros(n1 * n2, dtype=bool), mask=True)
        return np.ma.MaskedArray(np.asarray(values, dtype=bool).ravel(), mask=~valid)

    centroid_mm = 1e3 * np.asarray(result.centroid, dtype=float).reshape(-1, 3)
    centroid_mm[~valid] = np.nan
    shear = on_valid(result.shear)
    names = {int(s): s.name for s in CellStatus}
    codes = np.asarray(result.cell_status, dtype=np.int64).ravel().tolist()
    status = [names.get(code, f"UNKNOWN_{code}") for code in codes]

    reference_mm = None
    if energy is not None:
        energy_density = on_valid(energy.energy_density)
        thickness_ratio = on_valid(energy.thickness_ratio)
        reference_mm = energy.thickness_reference_mm
    else:
        energy_density = np.full(n1 * n2, np.nan)
        thickness_ratio = 1.0 / np.cos(shear)
    thickness_mm = thickness_ratio * (np.nan if reference_mm is None else reference_mm)
    columns: dict[str, Any] = {
        "i": ii.ravel(),
        "j": jj.ravel(),
        "status": status,
        "in_part": np.asarray(result.in_part, dtype=bool).ravel(),
        "part_share": np.asarray(result.part_weight, dtype=float).ravel(),
        "x_mm": centroid_mm[:, 0],
        "y_mm": centroid_mm[:, 1],
        "z_mm": centroid_mm[:, 2],
        "shear_deg": np.degrees(shear),
        "area_mm2": 1e6 * on_valid(result.area),
        "thickness_ratio": thickness_ratio,
        "thickness_mm": thickness_mm,
        "energy_J_per_m2": energy_density,
        "past_locking": flags(None if energy is None else energy.past_locking),
        "past_failure": flags(None if energy is None else energy.past_failure),
        "past_jamming": flags(None if energy is None else energy.past_jamming),
        "wrinkling": flags(None if energy is None else energy.wrinkling),
    }
    assert tuple(columns) == CELL_COLUMNS
    if preform is not None:
        direction = np.asarray(preform.principal_direction, dtype=float).reshape(-1, 3)
        columns.update(
            {
                "preform_thickness_mm": 1e3 * on_valid(preform.thickness),
                "fibre_volume_fraction": on_valid(preform.fibre_volume_fraction),
                "permeability_k1_m2": on_valid(preform.principal_permeability[..., 0]),
                "permeability_k2_m2": on_valid(preform.principal_permeability[..., 1]),
                "permeability_k1_dir_x": on_valid(direction[:, 0]),
                "permeability_k1_dir_y": on_valid(direction[:, 1]),
                "permeability_k1_dir_z": on_valid(direction[:, 2]),
            }
        )
    return columns


def cells_table(
    result: DrapeResult, energy: EnergyField | None = None, preform: PreformField | None = None
) -> pd.DataFrame:
    """One row per cell of the net, invalid cells included.

    Columns: ``i``, ``j`` (cell index), ``status`` (CellStatus name, e.g. "VALID",
    "INCOMPLETE"), ``in_part`` (bool), ``x_mm``, ``y_mm``, ``z_mm`` (centroid [mm]),
    ``shear_deg`` (signed shear [deg]), ``area_mm2`` (draped area [mm²]),
    ``thickness_ratio`` (t/t0 [-]: a thickening, formerly ``thinning``; from the model
    ``energy.thickness_model`` names, ``preform.drape.properties.thickness``), ``thickness_mm`` (t0 · t/t0
    [mm], NaN when t0 is unknown), ``energy_J_per_m2`` (strain energy density [J/m²]),
    ``past_locking`` and ``past_failure`` (nullable bool), ``past_jamming`` (past the law's
    jamming angle) and ``wrinkling`` (past any limit where the fabric wrinkles: jamming, stitch
    failure, the law's own; ``preform.drape.judging.wrinkling``) (nullable bool), ``part_share`` (the share 0..1 of the
    cell's undeformed area inside the part, 0 outside it: the total energy is
    Σ energy_J_per_m2 · part_share · d²). Values of cells that are not VALID
    are NaN / <NA>; the energy columns are NaN / <NA> throughout when ``energy`` is None, and
    the thickness ratio then follows from the shear as 1/cos γ. With ``preform`` (the ``permeability``
    output) follow the sheared cell's thickness [mm] and fabric fibre volume fraction [-]
    (``preform_thickness_mm``, ``fibre_volume_fraction``), the principal in-plane
    permeabilities k1 ≥ k2 [m²] and k1's unit direction in the tool's axes
    (``permeability_k1_m2``, ``permeability_k2_m2``, ``permeability_k1_dir_x``/``_y``/``_z``).
    The same columns as arrays: ``cell_columns``.
    """
    import pandas as pd

    columns = cell_columns(result, energy, preform)
    columns["status"] = pd.array(columns["status"], dtype="string")
    for name in ("past_locking", "past_failure", "past_jamming", "wrinkling"):
        flags = columns[name]
        columns[name] = pd.arrays.BooleanArray(np.ma.getdata(flags), np.ma.getmaskarray(flags))
    return pd.DataFrame(columns)


def write_table(table: pd.DataFrame, path: str | os.PathLike[str]) -> None:
    """Write ``table`` to ``path``: Parquet when the suffix is ``.parquet``, otherwise CSV.

    CSV leaves missing values empty. Parquet keeps dtypes (nullable booleans stay nullable)
    and needs pyarrow: ``pip install "preform[parquet]"``.
    """
    if Path(path).suffix.lower() == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError as exc:  # pragma: no cover - exercised only without the extra
            raise ImportError(
                'Writing Parquet needs pyarrow: pip install "preform[parquet]"'
            ) from exc
        with atomic_path(path) as tmp:
            table.to_parquet(tmp, engine="pyarrow", index=False)
        return
    with atomic_open(path, "w", encoding="utf-8") as handle:
        table.to_csv(handle, index=False, lineterminator="\n")


def to_json_compatible(obj: Any) -> Any:
    """``obj`` made of plain JSON types: numpy scalars and arrays become numbers and lists,
    NaN and ±inf become None (JSON has no NaN), enums their name, paths strings, sets sorted
    lists, mapping keys strings. Raises TypeError for anything else.
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, enum.Enum):
        return obj.name
    if isinstance(obj, (int, np.integer)) and not isinstance(obj, np.bool_):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, np.ndarray):
        return [to_json_compatible(v) for v in obj.tolist()]
    if isinstance(obj, Mapping):
        return {str(k): to_json_compatible(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_json_compatible(v) for v in obj]
    if isinstance(obj, (set, frozenset)):
        return sorted((to_json_compatible(v) for v in obj), key=repr)
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    pandas = sys.modules.get("pandas")  # pd.NA exists only once pandas is imported
    if pandas is not None and obj is pandas.NA:
        return None
    raise TypeError(f"cannot write {type(obj).__name__} to JSON: {obj!r}")


def write_json(obj: Any, path: str | os.PathLike[str]) -> None:
    """Write ``obj`` to ``path`` as strict JSON (sorted keys, indent 2, trailing newline).

    Conversions as ``to_json_compatible``: NaN → null, numpy scalars → numbers.
    """
    text = json.dumps(to_json_compatible(obj), sort_keys=True, indent=2, allow_nan=False)
    with atomic_open(path, "w", encoding="utf-8") as handle:
        handle.write(text + "\n")
