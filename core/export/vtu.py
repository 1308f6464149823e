"""VTK unstructured-grid (.vtu) files for ParaView: the unit cell's tow paths and the draped net.

Coordinates are written in millimetres, the unit of every other preform output (SI stays inside;
until 0.1 the drape file was in metres; meshio's VTU writer drops field data, so the unit is
said here and in every array name that has one); angles in degrees because that is what a ParaView user reads off a colour bar. meshio is an optional extra (``preform[vtk]``).
"""

from __future__ import annotations

import os
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from preform.base.atomic import atomic_path
from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField, NodeStatus

if TYPE_CHECKING:
    from preform.drape.properties.preform_fields import PreformField
    from preform.geometry.unit_cell import UnitCell

#: Integer code of each tow kind in the ``kind`` cell array (VTK cell data must be numeric).
TOW_KIND_CODES: dict[str, int] = {"warp": 0, "weft": 1, "binder": 2, "tow": 3, "stitch": 4}
#: Code for a kind not in ``TOW_KIND_CODES`` (a plugin's own kind still exports).
OTHER_KIND_CODE = 9
#: Millimetres per metre: files are in mm, preform holds metres.
MM_PER_M = 1e3


def _require_meshio() -> ModuleType:
    try:
        import meshio
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError('Writing .vtu files needs meshio: pip install "preform[vtk]"') from exc
    return meshio


def write_unit_cell_vtu(
    cell: UnitCell, path: str | os.PathLike[str], *, volumes: bool = True
) -> None:
    """Write a unit cell's tows to ``path`` (.vtu): centre-lines and, with ``volumes``, solids.

    Each tow's centreline becomes a chain of VTK "line" cells between its consecutive points
    (meshio has no poly-line cell); with ``volumes`` a second block holds the tow as a solid of
    wedges, its elliptical section swept along the centreline (``preform.export.tow_volumes``;
    the solid of a straight tow holds exactly its (π/4)·w·h section times its length). Points
    are in millimetres. Cell data on every cell of both blocks: ``tow`` (index of the tow in
    ``cell.tows``), ``kind`` (code from ``TOW_KIND_CODES``), ``level``, ``width_mm`` [mm],
    ``height_mm`` [mm] and ``solid`` (0 centre-line, 1 volume: ParaView's Threshold on it shows
    one or the other).
    """
    from preform.export.tow_volumes import tow_solids

    meshio = _require_meshio()
    point_blocks: list[np.ndarray] = []
    segment_blocks: list[np.ndarray] = []
    tow_index: list[np.ndarray] = []
    offset = 0
    for k, tow in enumerate(cell.tows):
        pts = np.asarray(tow.points, dtype=float).reshape(-1, 3)
        n = len(pts)
        point_blocks.append(pts)
        if n >= 2:
            start = np.arange(offset, offset + n - 1)
            segment_blocks.append(np.column_stack([start, start + 1]))
            tow_index.append(np.full(n - 1, k, dtype=np.int32))
        offset += n
    if not segment_blocks:
        raise ValueError("the unit cell has no tow with two or more points to write")

    kind = np.array(
        [TOW_KIND_CODES.get(t.kind, OTHER_KIND_CODE) for t in cell.tows], dtype=np.int32
    )
    level = np.array([t.level for t in cell.tows], dtype=np.int32)
    width = MM_PER_M * np.array([t.width for t in cell.tows], dtype=float)
    height = MM_PER_M * np.array([t.height for t in cell.tows], dtype=float)
    blocks = [("line", np.concatenate(segment_blocks), np.concatenate(tow_index), 0)]
    if volumes:
        solids = tow_solids(cell)
        point_blocks.append(solids.points)
        blocks.append(("wedge", solids.wedges + offset, solids.tow.astype(np.int32), 1))
    mesh = meshio.Mesh(
        points=MM_PER_M * np.concatenate(point_blocks),
        cells=[(name, cells) for name, cells, _, _ in blocks],
        cell_data={
            "tow": [tows for _, _, tows, _ in blocks],
            "kind": [kind[tows] for _, _, tows, _ in blocks],
            "level": [level[tows] for _, _, tows, _ in blocks],
            "width_mm": [width[tows] for _, _, tows, _ in blocks],
            "height_mm": [height[tows] for _, _, tows, _ in blocks],
            "solid": [np.full(len(tows), s, dtype=np.int32) for _, _, tows, s in blocks],
        },
    )
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")


def write_drape_vtu(
    result: DrapeResult,
    energy: EnergyField | None,
    path: str | os.PathLike[str],
    preform: PreformField | None = None,
) -> None:
    """Write the draped net to ``path`` (.vtu): placed nodes as points, valid cells as quads.

    Points are in millimetres. Cells that are not VALID are left out, so the file holds no NaN.
    Point data: ``i``, ``j`` (net indices), ``residual_mm`` [mm]. Cell data: ``i``, ``j``,
    ``shear_deg`` (signed shear [deg]), ``fibre_u`` and ``fibre_v`` (unit 3-vectors),
    ``thickness_ratio`` (t/t0 [-], the model ``energy.thickness_model`` names), ``thickness_mm``
    (t0 · t/t0 [mm], when t0 is known), ``status`` (CellStatus code), ``in_part`` (0/1) and,
    when ``energy`` is given, ``energy_J_per_m2`` [J/m²], ``past_locking``,
    ``past_failure``, ``past_jamming`` and ``wrinkling`` (0/1: past any limit where the fabric
    wrinkles, ``preform.drape.judging.wrinkling``); with ``preform`` (the ``permeability`` output)
    ``preform_thickness_mm`` [mm], ``fibre_volume_fraction`` [-], ``permeability_m2`` (the
    in-plane tensor in the file's axes, 9 components [m²]), ``permeability_k1_m2`` and
    ``permeability_k2_m2`` (principal values k1 ≥ k2 [m²]) and ``permeability_k1_dir`` (k1's unit
    direction: ParaView's Glyph filter draws the flow's fast direction). Without ``energy`` the
    thickness ratio is 1/cos γ, computed from the shear. A net
    with no valid cell is written as its placed nodes, one vertex cell each, without cell data.
    """
    meshio = _require_meshio()
    ni, nj = result.shape
    placed = np.asarray(result.status == NodeStatus.PLACED)
    # Renumber placed nodes 0..n-1 so unplaced (NaN) nodes never reach the file.
    point_id = np.full((ni, nj), -1, dtype=np.int64)
    point_id[placed] = np.arange(np.count_nonzero(placed))
    node_i, node_j = np.nonzero(placed)

    valid = np.asarray(result.cell_status == CellStatus.VALID)
    ci, cj = np.nonzero(valid)
    quads = np.column_stack(
        [point_id[ci, cj], point_id[ci + 1, cj], point_id[ci + 1, cj + 1], point_id[ci, cj + 1]]
    )
    if np.any(quads < 0):
        raise ValueError(
            "a VALID cell has an unplaced corner node; the DrapeResult is inconsistent"
        )

    shear = np.asarray(result.shear, dtype=float)[ci, cj]
    cell_data: dict[str, np.ndarray] = {
        "i": ci.astype(np.int32),
        "j": cj.astype(np.int32),
        "shear_deg": np.degrees(shear),
        "fibre_u": np.asarray(result.fibre_u, dtype=float)[ci, cj],
        "fibre_v": np.asarray(result.fibre_v, dtype=float)[ci, cj],
        "status": np.asarray(result.cell_status, dtype=np.int32)[ci, cj],
        "in_part": np.asarray(result.in_part, dtype=np.int32)[ci, cj],
    }
    if energy is not None:
        cell_data["energy_J_per_m2"] = np.asarray(energy.energy_density, dtype=float)[ci, cj]
        cell_data["thickness_ratio"] = np.asarray(energy.thickness_ratio, dtype=float)[ci, cj]
        cell_data["past_locking"] = np.asarray(energy.past_locking, dtype=np.int32)[ci, cj]
        cell_data["past_failure"] = np.asarray(energy.past_failure, dtype=np.int32)[ci, cj]
        for name in ("past_jamming", "wrinkling"):
            flags = getattr(energy, name)
            if flags is not None:
                cell_data[name] = np.asarray(flags, dtype=np.int32)[ci, cj]
        if energy.thickness_reference_mm is not None:
            t0 = energy.thickness_reference_mm
            cell_data["thickness_mm"] = t0 * cell_data["thickness_ratio"]
    else:
        cell_data["thickness_ratio"] = 1.0 / np.cos(shear)
    if preform is not None:
        cell_data["preform_thickness_mm"] = MM_PER_M * np.asarray(preform.thickness)[ci, cj]
        cell_data["fibre_volume_fraction"] = np.asarray(preform.fibre_volume_fraction)[ci, cj]
        cell_data["permeability_m2"] = np.asarray(preform.permeability)[ci, cj].reshape(-1, 9)
        cell_data["permeability_k1_m2"] = np.asarray(preform.principal_permeability)[ci, cj, 0]
        cell_data["permeability_k2_m2"] = np.asarray(preform.principal_permeability)[ci, cj, 1]
        cell_data["permeability_k1_dir"] = np.asarray(preform.principal_direction)[ci, cj]

    # A file is a result users open and trust: never write a NaN or an infinity into one (the
    # drape step fails such a case first; this guards direct callers).
    points = MM_PER_M * np.asarray(result.nodes, dtype=float)[placed]
    bad = [name for name, values in cell_data.items() if not np.all(np.isfinite(values))]
    if not np.all(np.isfinite(points)):
        bad.insert(0, "node positions")
    if bad:
        raise ValueError(
            f"the draped net has non-finite values in {', '.join(bad)}; not writing {path}"
        )

    # A net without a valid cell still shows its placed nodes, as vertex cells without cell
    # data: a file with an empty quad block, or with no cells, is one meshio cannot read back.
    has_cells = len(quads) > 0
    vertices = np.arange(len(node_i)).reshape(-1, 1)
    mesh = meshio.Mesh(
        points=points,
        cells=[("quad", quads)] if has_cells else [("vertex", vertices)],
        point_data={
            "i": node_i.astype(np.int32),
            "j": node_j.astype(np.int32),
            "residual_mm": MM_PER_M
            * np.nan_to_num(np.asarray(result.residual, dtype=float)[placed]),
        },
        cell_data={name: [values] for name, values in cell_data.items()} if has_cells else {},
    )
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
