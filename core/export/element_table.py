"""The neutral per-element table of a mapped drape, for any solver: CSV or Parquet.

One row per element of the user's mesh, uncovered elements included (``covered`` false, their
values empty), so the table says what was not covered instead of leaving rows out. Columns
carry their unit in the name: lengths in mm, angles in degrees.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from preform.export.fe_mapping import MeshMapping
from preform.export.tables import write_table

if TYPE_CHECKING:
    import pandas as pd

#: Column order of :func:`element_table`.
ELEMENT_COLUMNS: tuple[str, ...] = (
    "element_id",
    "covered",
    "centroid_x_mm",
    "centroid_y_mm",
    "centroid_z_mm",
    "fibre_u_x",
    "fibre_u_y",
    "fibre_u_z",
    "fibre_v_x",
    "fibre_v_y",
    "fibre_v_z",
    "angle_u_deg",
    "angle_v_deg",
    "shear_deg",
    "thickness_ratio",
    "thickness_mm",
    "energy_J_per_m2",
    "past_locking",
    "past_failure",
    "above_thickness_cap",
    "gap_mm",
)


def element_table(mapping: MeshMapping) -> pd.DataFrame:
    """One row per element: ``element_id`` (the solver's label), ``covered``, centroid [mm],
    unit fibre directions u and v in the global frame (projected into the element's plane),
    their signed angles from the reference direction about the element normal [deg],
    ``shear_deg``, ``thickness_ratio`` (t/t0 [-]), ``thickness_mm``, ``energy_J_per_m2``,
    the flags ``past_locking``, ``past_failure``, ``above_thickness_cap``, and ``gap_mm``
    (centroid to net [mm]). Values of uncovered elements are NaN / <NA>."""
    import pandas as pd

    cov = mapping.covered

    def flag(values: np.ndarray) -> pd.arrays.BooleanArray:
        return pd.arrays.BooleanArray(np.asarray(values, dtype=bool), ~cov)

    data: dict[str, object] = {
        "element_id": mapping.mesh.element_ids,
        "covered": cov,
    }
    for k, axis in enumerate("xyz"):
        data[f"centroid_{axis}_mm"] = mapping.centroid_mm[:, k]
    for name, vec in (("fibre_u", mapping.fibre_u), ("fibre_v", mapping.fibre_v)):
        for k, axis in enumerate("xyz"):
            data[f"{name}_{axis}"] = vec[:, k]
    data.update(
        {
            "angle_u_deg": mapping.angle_u_deg,
            "angle_v_deg": mapping.angle_v_deg,
            "shear_deg": mapping.shear_deg,
            "thickness_ratio": mapping.thickness_ratio,
            "thickness_mm": mapping.thickness_mm,
            "energy_J_per_m2": mapping.energy_J_per_m2,
            "past_locking": flag(mapping.past_locking),
            "past_failure": flag(mapping.past_failure),
            "above_thickness_cap": flag(mapping.above_thickness_cap),
            "gap_mm": np.where(cov, mapping.gap_mm, np.nan),
        }
    )
    return pd.DataFrame(data).loc[:, list(ELEMENT_COLUMNS)]


def write_element_table(mapping: MeshMapping, path: str | os.PathLike[str]) -> None:
    """Write :func:`element_table` to ``path``: Parquet for ``.parquet``, otherwise CSV."""
    write_table(element_table(mapping), path)
