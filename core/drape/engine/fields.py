"""Per-cell fields of a draped net and its shear strain energy.

Cell (i, j) has corners (i, j), (i+1, j), (i+1, j+1), (i, j+1). Its two u edges run
(i, j)→(i+1, j) and (i, j+1)→(i+1, j+1), its two v edges (i, j)→(i, j+1) and
(i+1, j)→(i+1, j+1). At each corner one u edge and one v edge meet; ω there is the angle
between them taken in their +u and +v senses (``preform.drape.engine.result``). The cell's shear is

    γ = mean over the four corners of ω − 90°,

which is second-order accurate at the cell centre and, unlike the angle at one corner, does not
change when the net is mirrored. Fibre directions are the unit sums of the two u (v) edges.
The area is the mean of the two ways of splitting the (generally non-planar) cell into
triangles, again so that a mirrored net has mirrored areas.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.part import Part
from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField, NodeStatus
from preform.shear.law import ShearLaw

CentroidPredicate = Callable[[FloatArray], BoolArray]


def cell_status(status: NDArray[np.int8]) -> NDArray[np.int8]:
    """CellStatus per cell (ni−1, nj−1) from the NodeStatus of its corners (ni, nj).

    Precedence: OUTSIDE_PLY (a corner is not fabric), FOLDED (a corner could only be placed by
    turning the net over; each cell is completed by exactly one node, its corner farthest from
    the start, so this is the cell that folds), INCOMPLETE (another corner missing), VALID.
    """
    from preform.drape.kernels import field_kernels

    status = np.ascontiguousarray(status, dtype=np.int8)
    out = np.empty((max(status.shape[0] - 1, 0), max(status.shape[1] - 1, 0)), dtype=np.int8)
    field_kernels.cell_status_codes(status, out)
    return out


def cell_fields(
    nodes: FloatArray,
    status: NDArray[np.int8],
    *,
    trim: Part | CentroidPredicate | None = None,
) -> dict[str, Any]:
    """The cell arrays of a :class:`DrapeResult` from node positions (ni, nj, 3) [m] and
    statuses (ni, nj): ``cell_status``, ``shear`` [rad], ``centroid`` [m], ``area`` [m²],
    ``fibre_u``, ``fibre_v`` (unit), ``in_part`` and ``part_share``. ``trim`` is a
    :class:`~preform.drape.engine.part.Part` (cells cut by its edge count by their undeformed area
    inside it: ``part_share``; ``in_part`` is every valid cell with some area inside) or a
    predicate on centroids (a cell is in or out whole). Without it every valid cell counts
    whole. Zero (NaN for centroids) where not VALID."""
    from preform.drape.kernels import field_kernels

    c_status = cell_status(status)
    valid = c_status == CellStatus.VALID
    shape = valid.shape
    shear = np.empty(shape)
    area = np.empty(shape)
    centroid = np.empty((*shape, 3))
    fibre_u = np.empty((*shape, 3))
    fibre_v = np.empty((*shape, 3))
    field_kernels.cell_geometry(
        np.ascontiguousarray(nodes, dtype=float), valid, shear, centroid, area, fibre_u, fibre_v
    )
    in_part = valid.copy()
    if isinstance(trim, Part):
        # Cut cells count by their undeformed area inside the part (preform.drape.engine.part).
        with np.errstate(invalid="ignore"):
            phi = np.asarray(trim.level(nodes), dtype=float)
        share = np.empty(shape)
        field_kernels.grid_part_share(np.ascontiguousarray(phi), valid, share)
        in_part &= share > 0.0
    elif trim is not None and valid.any():
        in_part[valid] &= np.asarray(trim(centroid[valid]), dtype=bool)
        share = in_part.astype(float)
    else:
        share = valid.astype(float)
    return {
        "part_share": share,
        "cell_status": c_status,
        "shear": shear,
        "centroid": centroid,
        "area": area,
        "fibre_u": fibre_u,
        "fibre_v": fibre_v,
        "in_part": in_part,
    }


def energy_field(
    result: DrapeResult,
    law: ShearLaw,
    *,
    region: BoolArray | CentroidPredicate | None = None,
) -> EnergyField:
    """Shear strain energy of a draped net under ``law``.

    W(γ) [J/m²] per cell from the signed shear (so an asymmetric law takes the branch the
    convention in ``preform.drape.engine.result`` says), thickness ratio t/t0 = 1/cos γ, cells past the
    locking angle (|γ| > locking), past stitch failure (γ > failure, the parallel sense), past
    jamming and past any wrinkle limit (``preform.drape.judging.wrinkling``),
    and the total Σ W·s·d² [J] over the counted cells (d² the undeformed cell, s its share
    inside the part, ``result.part_weight``: 1 for a cell wholly inside).

    Counted cells: valid cells in the part (``result.in_part``), further restricted by
    ``region`` (a boolean mask (ni−1, nj−1) or a predicate on centroids (n, 3) [m]). The
    per-cell arrays are zero outside them (the thickness ratio is 1 there: no deformation counted).
    """
    counted = result.valid & result.in_part
    if region is not None:
        if callable(region):
            keep = np.zeros_like(counted)
            if counted.any():
                keep[counted] = np.asarray(region(result.centroid[counted]), dtype=bool)
        else:
            keep = np.asarray(region, dtype=bool)
            if keep.shape != counted.shape:
                raise ValueError(f"region mask shape {keep.shape} != cell shape {counted.shape}")
        counted = counted & keep
    from preform.drape.kernels import field_kernels

    counted = np.ascontiguousarray(counted)
    shear = np.ascontiguousarray(result.shear, dtype=float)
    # the law is evaluated on the counted cells only (a mechanistic law is costly per angle)
    at_counted = field_kernels.counted_values(shear, counted)
    law_energy = np.zeros(0)
    if at_counted.size:
        values = np.asarray(law.energy(at_counted), dtype=float)
        law_energy = np.ascontiguousarray(np.broadcast_to(values, at_counted.shape))
    share = np.ascontiguousarray(
        counted if result.part_share is None else result.part_share, dtype=float
    )
    density = np.empty(counted.shape)
    thickness_ratio = np.empty(counted.shape)
    past_locking = np.empty(counted.shape, dtype=bool)
    past_failure = np.empty(counted.shape, dtype=bool)
    locking, failure = law.locking_angle, law.failure_angle
    # A law whose stitch also breaks shearing the other way says so (stitch_yarn).
    failure_negative = getattr(law, "failure_angle_negative", None)
    weighted = field_kernels.energy_cells(
        shear,
        counted,
        law_energy,
        share,
        np.inf if locking is None else float(locking),
        np.inf if failure is None else float(failure),
        np.inf if failure_negative is None else float(failure_negative),
        density,
        thickness_ratio,
        past_locking,
        past_failure,
    )
    total = float(weighted * result.node_spacing**2)
    # Where the fabric would wrinkle instead (preform.drape.judging.wrinkling): the same limits the
    # verdicts read, so the cell flags and the wrinkling block count the same cells.
    from preform.drape.judging.verdict import law_range
    from preform.drape.judging.wrinkling import PAST_JAMMING, wrinkle_limits

    wrinkling = np.zeros(counted.shape, dtype=bool)
    past_jamming = np.zeros(counted.shape, dtype=bool)
    for limit in wrinkle_limits(law_range(law)):
        past = counted & limit.past(shear)
        wrinkling |= past
        if limit.cause == PAST_JAMMING:
            past_jamming |= past
    return EnergyField(
        energy_density=density,
        thickness_ratio=thickness_ratio,
        past_locking=np.asarray(past_locking, dtype=bool),
        past_failure=np.asarray(past_failure, dtype=bool),
        total_energy=total,
        past_jamming=past_jamming,
        wrinkling=wrinkling,
    )


def node_shear(result: DrapeResult) -> FloatArray:
    """Signed shear γ at every node (ni, nj) [rad], NaN where it cannot be formed.

    At node (i, j) the fibre edges to (i±1, j) and (i, j±1) form up to four corners (the +u
    or −u edge with the +v or −v edge, each taken in its + sense); γ is the mean of their
    angles ω minus 90°, as for a cell (so it is centred on the node: second-order accurate
    where all four exist). Unlike the cell value, which is the shear at a cell centre, the
    node value reaches the part's edge itself: nodes are where the extremes are read."""
    from preform.drape.kernels import field_kernels

    nodes = np.ascontiguousarray(result.nodes, dtype=float)
    status = np.ascontiguousarray(result.status, dtype=np.int8)
    gamma = np.empty(status.shape)
    field_kernels.node_shear(nodes, status, gamma)
    return gamma


def extremes(result: DrapeResult, part: Part | None = None) -> dict[str, float]:
    """Largest |γ| in the part [deg], read two ways (named so they are not confused):

    - ``max_abs_shear_cells_deg``: over the cells counted in the part (any share inside), the
      shear at each cell's centre;
    - ``max_abs_shear_nodes_deg``: over the placed nodes inside ``part`` (every placed node
      when None), the shear at the node (:func:`node_shear`), which reaches the part's edge.
    """
    from preform.drape.kernels import field_kernels

    counted = np.ascontiguousarray(result.valid & result.in_part)
    shape = np.shape(result.status)
    if part is not None:
        # a missing node's NaN position is in no part (φ NaN; its node shear is NaN too)
        inside = np.asarray(part.contains(result.nodes), dtype=bool)
    else:
        inside = np.ones(shape, dtype=bool)
    # the largest values in one compiled pass, without boolean-indexed copies
    cells, nodes = field_kernels.shear_extremes(
        np.ascontiguousarray(result.shear, dtype=float),
        counted,
        node_shear(result),
        np.ascontiguousarray(inside),
    )
    return {
        "max_abs_shear_cells_deg": float(np.degrees(cells)),
        "max_abs_shear_nodes_deg": float(np.degrees(nodes)),
    }


def summary(
    result: DrapeResult, energy: EnergyField | None = None, part: Part | None = None
) -> dict[str, object]:
    """A JSON-ready summary of a drape (angles in degrees, energy in J, areas in m²).

    ``max_abs_shear_deg`` is the cell value ``max_abs_shear_cells_deg`` (kept under its old
    name); ``max_abs_shear_nodes_deg`` is read at the nodes inside ``part``
    (:func:`extremes`). ``mean_abs_shear_deg`` weighs each cell by its area in the part."""
    from preform.drape.kernels import field_kernels

    node_counts = field_kernels.code_counts(
        np.ascontiguousarray(result.status, dtype=np.int8), len(NodeStatus)
    )
    cell_status = np.ascontiguousarray(result.cell_status, dtype=np.int8)
    cell_counts = field_kernels.code_counts(cell_status, len(CellStatus))
    share = result.part_share
    # the cell sums in one compiled pass (each numpy mask or sum would be a pass of its own)
    valid, counted, cut, weights, draped, shear_sum, locked = field_kernels.cell_sums(
        cell_status,
        np.ascontiguousarray(result.in_part, dtype=bool),
        np.ascontiguousarray(share if share is not None else np.zeros((0, 0)), dtype=float),
        share is not None,
        np.ascontiguousarray(result.shear, dtype=float),
        np.ascontiguousarray(result.area, dtype=float),
        np.ascontiguousarray(
            energy.past_locking if energy is not None else np.zeros((0, 0), dtype=bool),
            dtype=bool,
        ),
        energy is not None,
    )
    placed = int(node_counts[NodeStatus.PLACED])
    peaks = extremes(result, part)
    out: dict[str, object] = {
        "nodes_total": result.nodes_total,
        "nodes_placed": placed,
        # every node inside the ply placed (DrapeResult.complete)
        "complete": placed == result.nodes_total - int(node_counts[NodeStatus.OUTSIDE_PLY]),
        "cells_valid": int(valid),
        "cells_in_part": int(counted),
        "cells_cut_by_part_edge": int(cut),
        "part_fabric_area_m2": float(weights * result.node_spacing**2),
        "part_draped_area_m2": float(draped),
        "max_abs_shear_deg": peaks["max_abs_shear_cells_deg"],
        **peaks,
        "mean_abs_shear_deg": (
            float(np.degrees(shear_sum / weights)) if counted and weights > 0 else 0.0
        ),
        "generator_angle_deg": float(np.degrees(result.generator_angle)),
        "orientation_deg": float(np.degrees(result.orientation)),
        "node_spacing_m": result.node_spacing,
    }
    for code in NodeStatus:
        out[f"nodes_{code.name.lower()}"] = int(node_counts[code])
    for cell_code in CellStatus:
        out[f"cells_{cell_code.name.lower()}"] = int(cell_counts[cell_code])
    if energy is not None:
        out["total_energy_J"] = energy.total_energy
        out["cells_past_locking"] = int(np.count_nonzero(energy.past_locking))
        # Counted by the fabric area they put inside the part (undeformed, d² per whole cell).
        out["part_area_past_locking_m2"] = float(locked * result.node_spacing**2)
        out["cells_past_failure"] = int(np.count_nonzero(energy.past_failure))
    return out
