"""The draped net and its per-cell fields: the hand-over between the drape engine, the energy
search, and the exporters.

Indexing: node (i, j), i counts along the first generator family (u), j along the second (v);
cell (i, j) has corners (i, j), (i+1, j), (i+1, j+1), (i, j+1). Lengths in metres, angles in
radians.

Signed shear (the convention of the whole product, see ``preform.shear.law``): ω is the angle
between the cell's +u edge (i, j)→(i+1, j) and its +v edge (i, j)→(i, j+1). The fabric is laid
with its reference direction along the bisector of +u and −v, so γ = ω − 90° is positive when the
fabric lengthens along its reference direction (for a warp-knit: parallel to the stitch). A
generator angle α (between +u and +v at the start node) below 90° therefore puts shear α − 90° < 0
on the generators.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import BoolArray, FloatArray

IntArray = NDArray[np.int8]


class NodeStatus(IntEnum):
    """Why a node is or is not on the tool. Every node has exactly one."""

    PLACED = 0
    #: The construction left the tool (past its edge); the node has no position.
    OFF_TOOL = 1
    #: The two distance constraints had no solution on the surface (too much curvature for d).
    NO_INTERSECTION = 2
    #: A solution exists but the net would turn over (cell orientation flipped).
    FOLDED = 3
    #: The node lies outside the ply outline; not part of the fabric.
    OUTSIDE_PLY = 4
    #: Not reached because a node it depends on failed.
    NOT_REACHED = 5


class CellStatus(IntEnum):
    VALID = 0
    #: At least one corner is not placed.
    INCOMPLETE = 1
    #: The cell is turned over (its normal opposes the tool's).
    FOLDED = 2
    #: Outside the ply outline.
    OUTSIDE_PLY = 3


@dataclass(frozen=True)
class DrapeResult:
    """A pin-jointed net on a tool surface.

    Node positions are NaN exactly where ``status != PLACED``; the status says why, so no NaN is
    unexplained. Cell arrays are 0 (or NaN for positions) where ``cell_status != VALID``.
    """

    #: Node positions (ni, nj, 3) [m].
    nodes: FloatArray
    #: NodeStatus codes (ni, nj).
    status: IntArray
    #: Constraint residual of each placed node (ni, nj) [m]: max of | |P−A| − d | and the
    #: distance to the surface (on a mesh, |P−A| is the length along the surface where a
    #: feature crease lies between, docs/physics.md).
    residual: FloatArray
    #: Index of the start node.
    start_index: tuple[int, int]
    #: Node spacing d [m].
    node_spacing: float
    #: Generator intersection angle α [rad].
    generator_angle: float
    #: Plan direction of the first generator at the start [rad from the tool x axis].
    orientation: float
    #: Per-cell status (ni−1, nj−1).
    cell_status: IntArray
    #: Signed shear angle γ per cell (ni−1, nj−1) [rad].
    shear: FloatArray
    #: Cell centroids (ni−1, nj−1, 3) [m].
    centroid: FloatArray
    #: Draped cell area (ni−1, nj−1) [m²] (d² cos γ for a flat rhombus).
    area: FloatArray
    #: Unit fibre directions of the u and v families per cell (ni−1, nj−1, 3).
    fibre_u: FloatArray
    fibre_v: FloatArray
    #: Cells with some of their area inside the part (trim region); by default every valid
    #: cell.
    in_part: BoolArray
    #: Free-form diagnostics (iteration counts, tolerances used, ...).
    info: dict[str, object] = field(default_factory=dict)
    #: Share (0..1) of each cell's undeformed area d² inside the part (ni−1, nj−1) [-]: 1 for
    #: a cell wholly inside, between for a cell cut by the part's edge
    #: (``preform.drape.engine.part``). None: every cell of ``in_part`` counts whole.
    part_share: FloatArray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.nodes.shape[0]), int(self.nodes.shape[1]))

    @property
    def nodes_total(self) -> int:
        return int(self.status.size)

    @property
    def nodes_placed(self) -> int:
        return int(np.count_nonzero(self.status == NodeStatus.PLACED))

    @property
    def valid(self) -> BoolArray:
        return np.asarray(self.cell_status == CellStatus.VALID)

    @property
    def part_weight(self) -> FloatArray:
        """Share (0..1) of each cell's undeformed area counted in the part (ni−1, nj−1) [-]:
        ``part_share`` on valid cells in the part, 0 elsewhere."""
        counted = self.valid & self.in_part
        if self.part_share is None:
            return counted.astype(float)
        return np.where(counted, np.asarray(self.part_share, dtype=float), 0.0)

    @property
    def complete(self) -> bool:
        """True when every node inside the ply is placed. A ply larger than the tool is never
        complete in this sense; whether a drape covers what its scene asked (the overhang past
        the tool's edge allowed) is ``preform.drape.judging.verdict.coverage``, which the case
        summary's ``complete`` reports."""
        inside = self.status != NodeStatus.OUTSIDE_PLY
        return bool(np.all(self.status[inside] == NodeStatus.PLACED))


@dataclass(frozen=True)
class EnergyField:
    """Strain energy of a draped net under a fabric's shear law."""

    #: Strain energy per unit undeformed area W(γ) per cell (ni−1, nj−1) [J/m²].
    energy_density: FloatArray
    #: Thickness ratio t/t0 per cell (ni−1, nj−1) [-]: 1/cos γ as ``energy_field`` gives it
    #: (the fabric keeps its fibre volume, so the sheared cell's area d² cos γ thickens it);
    #: the fabric's sheared unit cell where it has one (``preform.drape.properties.thickness``). It is a *thickening*
    #: (≥ 1); the old name ``thinning`` remains as a deprecated alias. No compaction limit is
    #: applied here: exporters report cells above a cap (``preform.export.fe_mapping``).
    thickness_ratio: FloatArray
    #: Cells past the locking angle, and past the stitch-failure angle (ni−1, nj−1).
    past_locking: BoolArray
    past_failure: BoolArray
    #: Cells past the law's jamming angle, and past any limit where the fabric wrinkles
    #: (jamming, stitch failure, the law's own: ``preform.drape.judging.wrinkling``) (ni−1, nj−1);
    #: None when not computed.
    past_jamming: BoolArray | None = field(default=None, kw_only=True)
    wrinkling: BoolArray | None = field(default=None, kw_only=True)
    #: Total strain energy Σ W·A0 over the valid cells in the part [J] (A0 = d², undeformed).
    total_energy: float
    #: The model the thickness ratio comes from, in words, recorded with every export: this
    #: default, or "sheared unit cell" once ``preform.drape.properties.thickness`` applies the fabric's.
    thickness_model: str = "constant fibre volume fraction (1/cos γ)"
    #: The reference thickness t0 [mm] of the ratio, None when not known.
    thickness_reference_mm: float | None = None

    @property
    def thinning(self) -> FloatArray:
        """Deprecated name of :attr:`thickness_ratio` (it was never a thinning)."""
        import warnings

        warnings.warn(
            "EnergyField.thinning is renamed thickness_ratio", DeprecationWarning, stacklevel=2
        )
        return self.thickness_ratio
