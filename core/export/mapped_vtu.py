"""The user's shell mesh with the mapped drape as cell data, for ParaView (.vtu, mm).

Same fields and names as the per-element table (``preform.export.element_table``). Uncovered
elements are in the file with ``covered`` = 0 and NaN values, which ParaView draws in its NaN
colour: an honest "no value", never a default.
"""

from __future__ import annotations

import os

import numpy as np

from preform.base.atomic import atomic_path
from preform.export.fe_mapping import MeshMapping
from preform.export.vtu import _require_meshio


def write_mapped_vtu(mapping: MeshMapping, path: str | os.PathLike[str]) -> None:
    """Write the mesh [mm] with cell data ``element_id``, ``covered`` (0/1), ``fibre_u``,
    ``fibre_v`` (unit 3-vectors), ``angle_u_deg``, ``angle_v_deg``, ``shear_deg``,
    ``thickness_ratio``, ``thickness_mm``, ``energy_J_per_m2``, ``past_locking``,
    ``past_failure``, ``above_thickness_cap`` (0/1) and ``gap_mm``. Triangles and quads
    are separate cell blocks, each in mesh order."""
    meshio = _require_meshio()
    mesh = mapping.mesh
    tri = mesh.is_triangle
    blocks = []
    cell_data: dict[str, list[np.ndarray]] = {}
    columns: dict[str, np.ndarray] = {
        "element_id": mesh.element_ids.astype(np.int64),
        "covered": mapping.covered.astype(np.int32),
        "fibre_u": mapping.fibre_u,
        "fibre_v": mapping.fibre_v,
        "angle_u_deg": mapping.angle_u_deg,
        "angle_v_deg": mapping.angle_v_deg,
        "shear_deg": mapping.shear_deg,
        "thickness_ratio": mapping.thickness_ratio,
        "thickness_mm": mapping.thickness_mm,
        "energy_J_per_m2": mapping.energy_J_per_m2,
        "past_locking": mapping.past_locking.astype(np.int32),
        "past_failure": mapping.past_failure.astype(np.int32),
        "above_thickness_cap": mapping.above_thickness_cap.astype(np.int32),
        "gap_mm": np.where(mapping.covered, mapping.gap_mm, np.nan),
    }
    for kind, mask, width in (("triangle", tri, 3), ("quad", ~tri, 4)):
        if not mask.any():
            continue
        blocks.append((kind, mesh.corners[mask, :width]))
        for name, values in columns.items():
            cell_data.setdefault(name, []).append(np.asarray(values)[mask])
    out = meshio.Mesh(points=mesh.points, cells=blocks, cell_data=cell_data)
    with atomic_path(path) as tmp:
        meshio.write(tmp, out, file_format="vtu")
