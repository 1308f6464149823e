"""What a stack is at each place: total thickness, fibre volume fraction, plies present,
plies wrinkling, from the draped plies (``preform.stack.steps``).

A draped ply is known per cell of its own net; the stack is read at *stations*, points on the
tool side of the stack (the cell centres of the ply covering the largest area, the
``reference`` ply), or at any points (an FE mesh's element centroids, a tool mesh's vertices).
A ply is present at a point when the point's closest point on the ply's net lies inside the
net (within 5 % of its node spacing d along it, as ``preform.export.fe_mapping`` judges an
element covered) and the gap normal to the net is at most d plus the stack's thickness there
(the plies lie that far above the tool); its thickness there is its cell's, t0 · t/t0, and its
fibre volume fraction the cell's (the sheared unit cell's, or the fabric's as built when the
fabric keeps its fibre volume fraction). Where a ply is absent it adds nothing.

The stack's fibre volume fraction is the thickness-weighted mean of its plies' (Σ Vf·t / Σ t),
NaN where a present ply's fraction is not known. Lengths in mm here (the tables' unit).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import BoolArray, FloatArray
from preform.drape.engine.result import DrapeResult
from preform.export.fe_mapping import EDGE_TOLERANCE, closest_on_net

MM_PER_M = 1e3


@dataclass(frozen=True)
class PlyLayer:
    """One draped ply as the stack reads it; per-cell arrays have the net's cell shape."""

    name: str
    fabric: str
    #: Ply angle from the layup's reference direction [deg].
    orientation_deg: float
    result: DrapeResult
    #: Thickness t0 · t/t0 [mm] and fibre volume fraction [-] per cell (NaN where not valid
    #: or not known).
    thickness_mm: FloatArray
    fibre_volume_fraction: FloatArray
    #: Cells past a wrinkle limit (jamming, stitch failure: ``preform.drape.judging.wrinkling``).
    wrinkles: BoolArray
    #: The reference thickness t0 [mm] and the ply's offset from the tool [mm] (the analytic
    #: offset's one distance, or the largest of a mesh's).
    nominal_thickness_mm: float
    offset_mm: float
    status: str

    @property
    def region(self) -> BoolArray:
        """The cells that are the ply: valid and in its part."""
        return np.asarray(self.result.valid & self.result.in_part, dtype=bool)

    def mean_thickness_mm(self) -> float:
        """Area-weighted mean thickness over the ply's part [mm]."""
        region = self.region
        weight = np.asarray(self.result.area, dtype=float) * np.asarray(
            self.result.part_weight, dtype=float
        )
        w = weight[region]
        if not w.sum() > 0:
            return float(self.nominal_thickness_mm)
        return float(np.sum(w * self.thickness_mm[region]) / w.sum())

    def thickness_range_mm(self) -> tuple[float, float]:
        """Least and largest thickness over the ply's part [mm]."""
        values = self.thickness_mm[self.region]
        if values.size == 0:
            return (self.nominal_thickness_mm, self.nominal_thickness_mm)
        return (float(np.nanmin(values)), float(np.nanmax(values)))

    def covered_area_mm2(self) -> float:
        """The ply's draped area in its part [mm²]."""
        area = np.asarray(self.result.area, dtype=float) * np.asarray(
            self.result.part_weight, dtype=float
        )
        return float(area[self.region].sum() * MM_PER_M**2)


@dataclass(frozen=True)
class PlyAt:
    """One ply read at points: present, thickness [mm], fraction [-], wrinkling (k,)."""

    present: BoolArray
    thickness_mm: FloatArray
    fibre_volume_fraction: FloatArray
    wrinkles: BoolArray


def ply_at(
    layer: PlyLayer,
    points_mm: FloatArray,
    max_gap_mm: float | FloatArray,
    own_cells: bool = False,
) -> PlyAt:
    """``layer`` read at ``points_mm`` (k, 3) [mm] (module docstring); ``max_gap_mm`` [mm] the
    largest normal gap (one, or one per point) at which the ply counts as there. ``own_cells``:
    the points are this ply's part cell centres, in ``np.nonzero(layer.region)`` order (the
    stations on the reference ply), so each is its own nearest cell, at its centre.

    A point is read in the cell that holds it: its coordinates in the cell's parallelogram
    (the mean edges a, b and the normal n) lie within half a cell of the centre and its gap
    within the limit; the point's nearest cell (by centroid) is tried first, then its eight
    neighbours (``preform.stack.maps_kernels``). The points none holds but near the net (its
    edge) are found exactly (``closest_on_net``: sixteen triangle tests a point)."""
    from scipy.spatial import cKDTree

    from preform.stack.maps_kernels import holding_cells

    points = np.asarray(points_mm, dtype=float).reshape(-1, 3)
    k = len(points)
    region = layer.region
    gap_limit = np.broadcast_to(np.asarray(max_gap_mm, dtype=float), (k,))
    none = PlyAt(np.zeros(k, bool), np.zeros(k), np.full(k, np.nan), np.zeros(k, bool))
    if not region.any() or k == 0:
        return none
    result = layer.result
    d_mm = MM_PER_M * float(result.node_spacing)
    ci_all, cj_all = np.nonzero(region)
    centroid = MM_PER_M * np.asarray(result.centroid, dtype=float)
    centres = centroid[ci_all, cj_all]
    far = np.zeros(k, bool)
    tree = None
    if own_cells:  # the same answer as the search below, without it
        nearest = np.arange(k)
    else:
        # a cell centre farther than this is not "near" (below): the search may stop there
        bound = 2.0 * d_mm + float(gap_limit.max())
        tree = cKDTree(centres)
        distance, nearest = tree.query(points, distance_upper_bound=bound)
        far = ~np.isfinite(distance)
        nearest[far] = 0  # any cell: a far point is neither present nor in doubt
    present, ci, cj, doubt = holding_cells(
        points,
        ci_all[nearest],
        cj_all[nearest],
        far,
        MM_PER_M * np.asarray(result.nodes, dtype=float),
        centroid,
        region,
        np.ascontiguousarray(gap_limit),
        d_mm,
    )
    if doubt.any():
        hit = closest_on_net(result, points[doubt], region, tree)
        inside = (hit.tangential_mm <= EDGE_TOLERANCE * d_mm) & (hit.gap_mm <= gap_limit[doubt])
        present[doubt] = inside
        ci[doubt], cj[doubt] = hit.cell_i, hit.cell_j
    thickness = np.where(present, layer.thickness_mm[ci, cj], 0.0)
    fraction = np.where(present, layer.fibre_volume_fraction[ci, cj], np.nan)
    wrinkles = present & layer.wrinkles[ci, cj]
    return PlyAt(present, thickness, fraction, wrinkles)


@dataclass(frozen=True)
class StackMaps:
    """The stack read at points: per point (k,) and per point and ply (k, n_plies)."""

    points_mm: FloatArray
    #: Area each point stands for [mm²] (a station's cell area; 1 for bare points).
    area_mm2: FloatArray
    ply_names: tuple[str, ...]
    present: BoolArray
    thickness_mm: FloatArray
    fibre_volume_fraction: FloatArray
    wrinkles: BoolArray

    @property
    def total_thickness_mm(self) -> FloatArray:
        """Sum of the present plies' thicknesses [mm]."""
        return np.asarray(self.thickness_mm.sum(axis=1), dtype=float)

    @property
    def plies_present(self) -> NDArray[np.int64]:
        return np.asarray(self.present.sum(axis=1), dtype=np.int64)

    @property
    def plies_wrinkling(self) -> NDArray[np.int64]:
        return np.asarray(self.wrinkles.sum(axis=1), dtype=np.int64)

    @property
    def stack_fibre_volume_fraction(self) -> FloatArray:
        """Σ Vf·t / Σ t over the present plies [-]; NaN where none is present or a present
        ply's fraction is not known."""
        t = self.thickness_mm
        vf = np.where(self.present, self.fibre_volume_fraction, 0.0)
        unknown = np.any(self.present & ~np.isfinite(self.fibre_volume_fraction), axis=1)
        total = t.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            out = (vf * t).sum(axis=1) / total
        return np.where(unknown | (total <= 0.0), np.nan, out)

    def summary(self) -> dict[str, Any]:
        """The stack's ranges, for the case summary (mm, mm², -)."""
        total = self.total_thickness_mm
        area = self.area_mm2
        n = len(self.ply_names)
        count = self.plies_present
        some = count > 0
        out: dict[str, Any] = {
            "stack_plies": n,
            "stack_stations": len(total),
            "stack_area_mm2": float(area[some].sum()),
            "stack_area_all_plies_mm2": float(area[count == n].sum()),
            "stack_plies_present_min": int(count[some].min()) if some.any() else 0,
            "stack_plies_present_max": int(count.max()) if len(count) else 0,
            "stack_area_wrinkling_mm2": float(area[self.plies_wrinkling > 0].sum()),
        }
        if some.any():
            out["stack_thickness_max_mm"] = float(total[some].max())
            out["stack_thickness_min_mm"] = float(total[some].min())
            out["stack_thickness_mean_mm"] = float(
                np.sum(total[some] * area[some]) / area[some].sum()
            )
            vf = self.stack_fibre_volume_fraction[some]
            known = np.isfinite(vf)
            if known.all():
                w = (total * area)[some]
                out["stack_fibre_volume_fraction_mean"] = float(np.sum(vf * w) / w.sum())
                out["stack_fibre_volume_fraction_max"] = float(vf.max())
        return out


def stack_at(
    layers: Sequence[PlyLayer],
    points_mm: FloatArray,
    area_mm2: FloatArray | None = None,
    own: int | None = None,
) -> StackMaps:
    """Every ply of ``layers`` read at ``points_mm`` (k, 3) [mm] lying on the tool side of
    the stack, or on any ply: a ply counts as present up to a normal gap of its node spacing
    plus the stack's height (module docstring). ``own``: the index of the ply whose part cell
    centres the points are (``stations``), read without a search."""
    points = np.asarray(points_mm, dtype=float).reshape(-1, 3)
    k = len(points)
    # the points and a ply may be as far apart as the whole stack is thick
    height = max((layer.offset_mm + layer.thickness_range_mm()[1] for layer in layers), default=0)
    reads = []
    for index, layer in enumerate(layers):
        d_mm = MM_PER_M * float(layer.result.node_spacing)
        reads.append(ply_at(layer, points, d_mm + height, own_cells=index == own))

    def column(get: str) -> Any:
        if not reads:
            return np.zeros((k, 0))
        return np.column_stack([getattr(r, get) for r in reads])

    return StackMaps(
        points_mm=points,
        area_mm2=np.ones(k) if area_mm2 is None else np.asarray(area_mm2, dtype=float),
        ply_names=tuple(layer.name for layer in layers),
        present=np.asarray(column("present"), dtype=bool).reshape(k, len(reads)),
        thickness_mm=np.asarray(column("thickness_mm"), dtype=float).reshape(k, len(reads)),
        fibre_volume_fraction=np.asarray(column("fibre_volume_fraction"), dtype=float).reshape(
            k, len(reads)
        ),
        wrinkles=np.asarray(column("wrinkles"), dtype=bool).reshape(k, len(reads)),
    )


#: A ply covering at least this share of the largest ply's area is "as large" as it: the
#: stations are those of the tool-side one of such plies (an outer ply's area grows with its
#: offset, R + h on a dome, so it must not win by that alone).
AS_LARGE = 0.95


def reference_ply(layers: Sequence[PlyLayer]) -> int:
    """Index of the stations' ply: the tool-side one of the plies covering about the largest
    area (``AS_LARGE``)."""
    areas = np.array([layer.covered_area_mm2() for layer in layers])
    return int(np.flatnonzero(areas >= AS_LARGE * areas.max())[0])


def stations(layers: Sequence[PlyLayer]) -> tuple[FloatArray, FloatArray]:
    """The stack's stations: the cell centres [mm] of the reference ply's part cells and
    their areas in the part [mm²]."""
    layer = layers[reference_ply(layers)]
    region = layer.region
    centres = MM_PER_M * np.asarray(layer.result.centroid, dtype=float)[region]
    area = (np.asarray(layer.result.area, dtype=float) * np.asarray(layer.result.part_weight))[
        region
    ] * MM_PER_M**2
    return centres, area
