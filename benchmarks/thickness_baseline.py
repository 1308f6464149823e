"""The sheared-cell table as it was before issue 15h: the baseline of the speed ratios in
``bench_thickness.py``, measured in the same process.

A frozen copy, reachable only from the benchmarks (never imported by preform or its tests):
``PreformResponse.from_fabric``'s table built from one ``fabric.sheared_cell(γ)`` per grid angle
from the locking angle on, each woven cell rebuilt with its tows' heights at γ and its thickness
the envelope of its tow polylines (``tow_points`` per tow, the column stacks recomputed per
cell), each warp-knit cell rebuilt likewise with its stack summed, and each tow's jamming
fraction found by bisection (one bundle-law call per halving; kept per process as today's is).
Only the thickness and the fibre fraction of each angle are kept (what the table reads); the
tow families, their states and the fabric's own checks per angle are today's code, called as
the old path called them, with the old jamming fraction swapped in while ``table`` runs.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Iterator
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from preform.geometry.sheared_cell import MAX_SHEAR, check_shear
from preform.plugins.warpknit import sheared_cell as warp_knit_module
from preform.plugins.warpknit.geometry import WarpKnitGeometry
from preform.plugins.woven import sheared_cell as woven_module
from preform.plugins.woven import tow_jamming as tow_jamming_module
from preform.plugins.woven.compaction import BundleCompaction
from preform.plugins.woven.geometry import Family, TowKey, TowType, WovenUnitCell
from preform.plugins.woven.tow_jamming import TowCompaction

FloatArray = NDArray[np.float64]


@lru_cache(maxsize=256)
def jamming_fraction(
    initial_fraction: float, fibre_modulus_Pa: float, settings: TowCompaction | None = None
) -> float:
    """The old V_j: bisection of σ_b(V) = p, one bundle-law call per halving."""
    s = settings or TowCompaction()
    cap = s.max_fraction * (1.0 - s.packing_margin)
    if not 0.0 < initial_fraction < cap:
        raise ValueError(f"as-built fibre fraction {initial_fraction:.3f} not below {cap:.3f}")
    bundle = BundleCompaction(
        fibre_modulus=fibre_modulus_Pa,
        span_to_height=s.fibre_wave_ratio,
        initial_fraction=initial_fraction,
        onset_fraction=initial_fraction,
        max_fraction=s.max_fraction,
        packing_margin=s.packing_margin,
    )
    cap = bundle.cap_fraction
    if float(bundle.stress(np.asarray(cap))) <= s.confining_pressure_Pa:
        return float(cap)
    lo, hi = initial_fraction, cap
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if float(bundle.stress(np.asarray(mid))) < s.confining_pressure_Pa:
            lo = mid
        else:
            hi = mid
    return lo


@contextlib.contextmanager
def old_jamming() -> Iterator[None]:
    """The old jamming fraction in both architectures' tow families for a ``with`` block (the
    woven families reach it through ``tow_jamming.weave_jamming_fraction`` since issue 24,
    which adds the weave's floats to the tow's own limit; the old bisection is the tow's own
    limit)."""
    saved = tow_jamming_module.jamming_fraction, warp_knit_module.jamming_fraction
    tow_jamming_module.jamming_fraction = warp_knit_module.jamming_fraction = jamming_fraction
    try:
        yield
    finally:
        tow_jamming_module.jamming_fraction, warp_knit_module.jamming_fraction = saved


def _heights_z(cell: WovenUnitCell) -> dict[tuple[int, int, int], float]:
    weave = cell.weave
    z: dict[tuple[int, int, int], float] = {}
    for i, row in enumerate(weave.matrix):
        for j, entry in enumerate(row):
            height = {lv: cell.tow_type(cell._key_at(i, j, lv)).height for lv in entry}
            stacked = [lv for lv in entry if lv not in weave.binder_levels]
            bottom = -sum(height[lv] for lv in stacked) / 2.0
            edge: dict[int, float] = {}
            for lv in stacked:
                edge[lv] = bottom
                bottom += height[lv]
            top = bottom
            for k, lv in enumerate(entry):
                if lv in edge:
                    z[(i, j, lv)] = edge[lv] + height[lv] / 2.0
                    continue
                below = [b for b in entry[:k] if b in edge]
                above = [a for a in entry[k + 1 :] if a in edge]
                if not below:
                    z[(i, j, lv)] = edge[stacked[0]] - height[lv] / 2.0 if stacked else 0.0
                elif not above:
                    z[(i, j, lv)] = top + height[lv] / 2.0
                else:
                    z[(i, j, lv)] = edge[above[0]]
    return z


def _tow_points(cell: WovenUnitCell, key: TowKey, heights: dict[Any, float]) -> FloatArray:
    cell._require_valid()
    weave = cell.weave
    columns = cell._columns_along(key)
    zs = [heights[(i, j, key.level)] for i, j in columns]
    z_edge = (zs[0] + zs[-1]) / 2.0
    if key.family == "warp":
        pitch = cell.tow_spacing_weft
        across = (key.position + 0.5) * cell.tow_spacing_warp
        along_end = weave.repeat_weft * pitch
    else:
        pitch = cell.tow_spacing_warp
        across = (key.position + 0.5) * cell.tow_spacing_weft
        along_end = weave.repeat_warp * pitch
    along = [0.0, *((k + 0.5) * pitch for k in range(len(columns))), along_end]
    zz = [z_edge, *zs, z_edge]
    if key.family == "warp":
        pts = [(a, across, z) for a, z in zip(along, zz, strict=True)]
    else:
        pts = [(across, a, z) for a, z in zip(along, zz, strict=True)]
    return np.array(pts, dtype=float)


def _woven_thickness(cell: WovenUnitCell) -> float:
    heights = _heights_z(cell)
    tops, bottoms = [], []
    for key in cell.tow_keys():
        z = _tow_points(cell, key, heights)[:, 2]
        h = cell.tow_type(key).height
        tops.append(z.max() + h / 2.0)
        bottoms.append(z.min() - h / 2.0)
    return float(max(tops) - min(bottoms))


def _woven_path_length(cell: WovenUnitCell, key: TowKey) -> float:
    points = _tow_points(cell, key, _heights_z(cell))
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def woven_cell(cell: WovenUnitCell, gamma: float) -> tuple[float, float]:
    """Thickness [m] and fibre fraction [-] of the old ``sheared_woven_cell``."""
    check_shear(gamma)
    families = woven_module.tow_families(cell)
    states = {name: fam.state(gamma) for name, fam in families.items()}

    def at_gamma(family: Family, tow: TowType) -> TowType:
        state = states[(family, tow.name)]
        return dataclasses.replace(tow, width=float(state.width), height=float(state.height))

    sheared = dataclasses.replace(
        cell,
        warp_tow_types=tuple(
            tuple(at_gamma("warp", t) for t in level) for level in cell.warp_tow_types
        ),
        weft_tow_types=tuple(
            tuple(at_gamma("weft", t) for t in level) for level in cell.weft_tow_types
        ),
    )
    volumes = dict.fromkeys(families, 0.0)
    for key in cell.tow_keys():
        tow = cell.tow_type(key)
        volumes[(key.family, tow.name)] += tow.fibre_area * _woven_path_length(cell, key)
    total = sum(volumes.values())
    sheared._require_valid()  # the old cell's tow_points checked the rebuilt cell
    area = cell.area * math.cos(gamma)
    thickness = _woven_thickness(sheared)
    return thickness, total / (area * thickness)


def warp_knit_cell_at(
    geo: WarpKnitGeometry, gamma: float, reference_deg: float
) -> tuple[float, float]:
    """Thickness [m] and fibre fraction [-] of the old ``sheared_warp_knit_cell``."""
    check_shear(gamma)
    families = warp_knit_module.tow_families(geo, reference_deg)
    states = tuple(f.state(gamma) for f in families)
    layers = tuple(
        dataclasses.replace(
            layer,
            tow=dataclasses.replace(layer.tow, width=float(s.width), height=float(s.height)),
        )
        for layer, s in zip(geo.tow_layers, states, strict=True)
    )
    sheared = dataclasses.replace(geo, tow_layers=layers)
    length, width = geo.cell_fit.size
    area0 = length * width
    total = sum(f.fibre_area * area0 / f.spacing for f in families)
    loop_band = max(t.diameter for t in sheared.thread_levels)
    thickness = (
        loop_band
        + sum(t.tow.height for t in sheared.tow_layers)
        + sum(t.diameter for t in sheared.thread_levels)
    )
    return thickness, total / (area0 * math.cos(gamma) * thickness)


def cell_at(fabric: Any, gamma: float) -> tuple[float, float]:
    """The old ``fabric.sheared_cell(γ)``'s thickness and fraction, with the fabric's checks."""
    if fabric.architecture == "woven":
        return woven_cell(fabric._require_valid(), gamma)
    problems = fabric.errors()
    if problems:
        raise ValueError(str(problems[0]))
    return warp_knit_cell_at(fabric.geometry, gamma, fabric.reference_direction_deg())


def table(fabric: Any, step_deg: float = 0.25) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The old ``PreformResponse.from_fabric``: |γ| grid [rad], thickness [m], fraction [-]."""
    with old_jamming():
        return _table(fabric, step_deg)


def _table(fabric: Any, step_deg: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    flat = fabric.sheared_cell(0.0)
    grid = np.radians(np.arange(0.0, math.degrees(MAX_SHEAR), step_deg))
    marks = [flat.locking_angle, flat.jamming_angle, MAX_SHEAR]
    grid = np.unique(np.concatenate([grid, [m for m in marks if 0.0 <= m <= MAX_SHEAR]]))
    free = grid < flat.locking_angle
    cells = [cell_at(fabric, float(g)) for g in grid[~free]]
    thickness = np.full(grid.shape, flat.thickness)
    fraction = flat.fibre_volume_fraction / np.cos(grid)
    thickness[~free] = [c[0] for c in cells]
    fraction[~free] = [c[1] for c in cells]
    return grid, thickness, fraction
