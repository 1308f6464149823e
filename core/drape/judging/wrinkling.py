"""Where a drape asks more shear than the fabric can give: its wrinkling, as a result.

A pin-jointed net shears every cell as far as the tool's shape asks. Past some angles a real
fabric cannot follow: its tows are jammed (woven fabrics, past the law's ``packing_angle``) or
its stitching breaks (warp-knits, past ``failure_angle`` / ``failure_angle_negative``). There
it buckles out of plane, it wrinkles, and the shear law only continues its curve (the woven law
holds its jammed torque), so the energy those cells carry is the law's continuation, not a
physical energy. This module says, per cause, how many cells, how much of the part's area,
how much of the energy, where and how far past the limit (``docs/physics.md``, "Wrinkling and
what can be made").

Causes [D]
----------
``past_jamming`` (|γ| > the law's ``packing_angle``) and ``past_stitch_failure``
(γ > ``failure_angle``, or γ < −``failure_angle_negative``), read from the law through
:func:`preform.drape.judging.verdict.law_range`. A law may expose further limits of its own as a
``wrinkle_limits`` attribute: a sequence of :class:`WrinkleLimit` (a cause name, the positive
and negative limit [rad], what happens past it in words); each is reported like the built-in
two and counts in the same rule. Locking (the onset of tow contact) is no cause: a fabric
sheared past locking still shears, stiffer, and its energy is the law's (it is a warning).

The status rule [D]
-------------------
A drape whose total energy comes more than half (:data:`WRINKLE_ENERGY_SHARE_MAX`) from cells
past any of these limits is not ``ok``: its energy is mostly no physical energy, so comparing
it with another drape's compares continuations of two laws. The steps make the case
``partial`` with :meth:`Wrinkling.reason`. Shares are of the part (a cell cut by its edge by
its area inside it, as the energy counts it); a cell past two limits counts once in the
union.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.arrays import BoolArray, FloatArray

if TYPE_CHECKING:
    from preform.drape.engine.result import DrapeResult
    from preform.drape.judging.verdict import LawRange


#: A drape is ``ok`` only when at most this share of its total energy comes from cells past a
#: wrinkle limit [-] (issue 24: "not mostly energy from cells past jamming or stitch failure").
WRINKLE_ENERGY_SHARE_MAX = 0.5

#: An angle of the least-energy search can be made when its wrinkled share of the covered part
#: area is within this of the least share any evaluated angle reaches [-] (docs/physics.md,
#: "Wrinkling and what can be made"; a stated tolerance, the scene knob
#: ``search.wrinkle_area_tolerance``) [C].
WRINKLE_AREA_TOLERANCE = 0.02

PAST_JAMMING = "past_jamming"
PAST_STITCH_FAILURE = "past_stitch_failure"


@dataclass(frozen=True)
class WrinkleLimit:
    """A shear past which the fabric wrinkles instead of shearing. Angles [rad, > 0]."""

    #: Name of the cause, a word usable in a column name (``past_jamming``).
    cause: str
    #: γ > ``positive_rad`` is past the limit (None: no limit in the positive sense).
    positive_rad: float | None
    #: γ < −``negative_rad`` is past the limit (None: no limit in the negative sense).
    negative_rad: float | None
    #: What the limit is, in words ("the jamming angle 40.6°"), and what happens past it.
    name: str = ""
    consequence: str = "the fabric would wrinkle there"

    def past(self, gamma: FloatArray) -> BoolArray:
        """Whether each signed shear γ [rad] is past this limit (False for NaN)."""
        g = np.asarray(gamma, dtype=float)
        out = np.zeros(g.shape, dtype=bool)
        if self.positive_rad is not None:
            out |= g > self.positive_rad
        if self.negative_rad is not None:
            out |= g < -self.negative_rad
        return out

    def excess(self, gamma: FloatArray) -> FloatArray:
        """How far each γ [rad] lies past this limit [rad] (0 within it)."""
        g = np.asarray(gamma, dtype=float)
        out = np.zeros(g.shape)
        if self.positive_rad is not None:
            out = np.maximum(out, g - self.positive_rad)
        if self.negative_rad is not None:
            out = np.maximum(out, -g - self.negative_rad)
        return np.where(np.isfinite(out), out, 0.0)


def wrinkle_limits(limits: LawRange) -> tuple[WrinkleLimit, ...]:
    """The wrinkle limits of a law's range (module docstring): jamming, stitch failure, then
    the law's own ``wrinkle_limits``."""
    out: list[WrinkleLimit] = []
    if limits.packing is not None:
        deg = math.degrees(limits.packing)
        out.append(
            WrinkleLimit(
                PAST_JAMMING,
                limits.packing,
                limits.packing,
                f"{deg:.1f}°, where the law's fabric is jammed (its tows at the weave's "
                "jamming fraction)",
                "it would wrinkle there, and the law only holds its jammed torque",
            )
        )
    if limits.failure is not None or limits.failure_negative is not None:
        senses = []
        if limits.failure is not None:
            senses.append(f"{math.degrees(limits.failure):.1f}° (parallel to the stitch)")
        if limits.failure_negative is not None:
            senses.append(
                f"−{math.degrees(limits.failure_negative):.1f}° (perpendicular to the stitch)"
            )
        out.append(
            WrinkleLimit(
                PAST_STITCH_FAILURE,
                limits.failure,
                limits.failure_negative,
                "the stitch-failure angle " + " or ".join(senses),
                "the stitching would break there",
            )
        )
    out.extend(limits.further)
    return tuple(out)


def past_any(limits: Iterable[WrinkleLimit], gamma: FloatArray) -> BoolArray:
    """Whether each γ [rad] is past any of ``limits``."""
    g = np.asarray(gamma, dtype=float)
    out = np.zeros(g.shape, dtype=bool)
    for limit in limits:
        out |= limit.past(g)
    return out


def makeable(
    area_share: float,
    least_area_share: float,
    tolerance: float = WRINKLE_AREA_TOLERANCE,
    max_area_share: float | None = None,
) -> bool:
    """Whether a drape of the least-energy search can be made (docs/physics.md, "Wrinkling
    and what can be made"): its share of the covered part area past a wrinkle limit [-] is
    within ``tolerance`` [-] of the least share any compared angle reaches and, when given,
    at most ``max_area_share`` [-]. Feasibility first, by area: where the fabric wrinkles is
    what cannot be made, whatever energy the law continues with there."""
    if not area_share <= least_area_share + tolerance:
        return False
    return max_area_share is None or area_share <= max_area_share


@dataclass(frozen=True)
class WrinkleZone:
    """The cells of a drape past one limit. Areas mm², angles deg, lengths mm, energy J."""

    limit: WrinkleLimit
    cells: int
    #: Draped area of those cells inside the part, Σ s·area [mm²], and its share of the
    #: part's draped area [-].
    area_mm2: float
    area_share: float
    #: Their energy Σ W·s·d² [J] and its share of the drape's total [-].
    energy_J: float
    energy_share: float
    #: Plan-view box (x_min, y_min, x_max, y_max) and area-weighted centroid (x, y) of their
    #: draped centroids [mm]; None when there are none.
    bbox_mm: tuple[float, float, float, float] | None
    centroid_mm: tuple[float, float] | None
    #: Largest |γ| among them, and the largest excess over the limit [deg].
    max_abs_shear_deg: float
    max_excess_deg: float
    #: Their connected patches (cells touching at an edge or a corner): plan centroid (x, y)
    #: [mm] and draped area [mm²] of each, largest first (at most :data:`PATCHES_KEPT`).
    patches: tuple[tuple[tuple[float, float], float], ...] = ()

    def summary(self) -> dict[str, Any]:
        return {
            **_amounts(self),
            "limit_positive_deg": _deg(self.limit.positive_rad),
            "limit_negative_deg": _deg(self.limit.negative_rad),
            "bbox_mm": None if self.bbox_mm is None else list(self.bbox_mm),
            "centroid_mm": None if self.centroid_mm is None else list(self.centroid_mm),
            "max_abs_shear_deg": self.max_abs_shear_deg,
            "max_excess_deg": self.max_excess_deg,
            "patches": [
                {"centroid_mm": list(centre), "area_mm2": area} for centre, area in self.patches
            ],
        }

    def label(self) -> str:
        """The cause and its limit in a few words: "past jamming at 42.6°"."""
        pos, neg = self.limit.positive_rad, self.limit.negative_rad
        if pos is not None and neg is not None and abs(pos - neg) < 1e-12:
            at = f"{math.degrees(pos):.1f}°"
        else:
            at = " / ".join(
                f"{sign}{math.degrees(v):.1f}°" for sign, v in (("+", pos), ("−", neg)) if v
            )
        return f"{self.limit.cause.replace('_', ' ')} at {at}"

    def where(self) -> str:
        """Where and how far, in words (empty when there are no cells)."""
        if self.bbox_mm is None:
            return ""
        shown = ", ".join(
            f"{area:.3g} mm² around ({_mm(x)}, {_mm(y)}) mm" for (x, y), area in self.patches[:4]
        )
        more = len(self.patches) - 4
        count = len(self.patches)
        return (
            f"{self.area_mm2:.4g} mm² in {count} patch{'es' if count != 1 else ''}: {shown}"
            + (f" and {more} more" if more > 0 else "")
            + f"; up to {self.max_excess_deg:.3g}° past the limit (|γ| ≤ "
            f"{self.max_abs_shear_deg:.3g}°)"
        )


def _amounts(found: WrinkleZone | Wrinkling) -> dict[str, Any]:
    """How much: cells, area [mm²] and share, energy [J] and share."""
    names = ("cells", "area_mm2", "area_share", "energy_J", "energy_share")
    return {name: getattr(found, name) for name in names}


def _deg(value: float | None) -> float | None:
    return None if value is None else math.degrees(value)


def _mm(value: float) -> str:
    return f"{round(value) + 0.0:.0f}"  # + 0.0 so that -0.4 mm reads "0", not "-0"


def _percent(share: float) -> str:
    # a share that is small but not zero says how small rather than "0.0"
    percent = 100.0 * share
    return f"{percent:.1f}" if percent >= 0.1 or percent == 0 else f"{percent:.2g}"


@dataclass(frozen=True)
class Wrinkling:
    """Every wrinkle limit of a drape (module docstring) and their union."""

    zones: tuple[WrinkleZone, ...]
    #: Union over the limits: cells, draped area [mm²] and its share, energy [J] and share.
    cells: int
    area_mm2: float
    area_share: float
    energy_J: float
    energy_share: float
    #: The drape's total energy [J] and its part's draped area [mm²] the shares are of.
    total_energy_J: float
    part_draped_area_mm2: float

    @property
    def mostly_wrinkle(self) -> bool:
        """More than half the total energy comes from cells past a limit: not ``ok``."""
        return self.energy_share > WRINKLE_ENERGY_SHARE_MAX

    def reason(self) -> str:
        """Why the drape is not ``ok``, in words (empty when it is)."""
        if not self.mostly_wrinkle:
            return ""
        causes = "; ".join(
            f"{_percent(z.energy_share)} % from {z.cells} cells {z.label()} "
            f"({_percent(z.area_share)} % of the part's draped area, {z.where()})"
            for z in self.zones
            if z.cells
        )
        return (
            f"the drape would wrinkle: {_percent(self.energy_share)} % of its total energy "
            f"{self.total_energy_J:.4g} J, more than {100 * WRINKLE_ENERGY_SHARE_MAX:.0f} %, "
            f"comes from {_percent(self.area_share)} % of the part's draped area, sheared past "
            f"where the fabric can follow, and is the shear law's continuation there, not a "
            f"physical energy: {causes}"
        )

    def summary(self) -> dict[str, Any]:
        """The ``wrinkling`` block of summary.json (mm², mm, degrees, J, shares 0..1)."""
        return {
            **_amounts(self),
            "energy_share_max": WRINKLE_ENERGY_SHARE_MAX,
            "mostly_wrinkle": self.mostly_wrinkle,
            "total_energy_J": self.total_energy_J,
            "part_draped_area_mm2": self.part_draped_area_mm2,
            "causes": {z.limit.cause: z.summary() for z in self.zones},
        }

    def columns(self) -> dict[str, Any]:
        """Scalar results for the tables (one row per case): the union, and per cause."""
        out: dict[str, Any] = {
            "wrinkle_cells": self.cells,
            "wrinkle_area_mm2": self.area_mm2,
            "wrinkle_area_share": self.area_share,
            "wrinkle_energy_share": self.energy_share,
        }
        for z in self.zones:
            key = f"wrinkle_{z.limit.cause}"
            out[f"{key}_cells"] = z.cells
            out[f"{key}_area_mm2"] = z.area_mm2
            out[f"{key}_area_share"] = z.area_share
            out[f"{key}_energy_share"] = z.energy_share
            out[f"{key}_max_excess_deg"] = z.max_excess_deg
        return out


#: Patches of one cause kept in the record (the largest) [-].
PATCHES_KEPT = 20


def _centre(xy: FloatArray, weight: FloatArray) -> tuple[float, float]:
    total = float(weight.sum())
    mid = (xy * weight[:, None]).sum(axis=0) / total if total > 0 else xy.mean(axis=0)
    return (float(mid[0]), float(mid[1]))


def connected_patches(
    cells: BoolArray, centres: FloatArray, weights: FloatArray
) -> list[tuple[tuple[float, float], float]]:
    """Connected patches of ``cells`` (ni−1, nj−1; edge or corner neighbours): each patch's
    ``weights``-averaged centre (the mean where its weights sum to 0) and total weight, largest
    first. ``centres`` (ni−1, nj−1, 2) and ``weights`` (ni−1, nj−1) are per cell, in any units.
    Shared by the fold zones (``preform.drape.judging.verdict``) and the wrinkle patches."""
    if not cells.any():
        return []
    from scipy import ndimage

    labels, count = ndimage.label(cells, structure=np.ones((3, 3), dtype=int))
    label = labels[cells]
    w = np.asarray(weights, dtype=float)[cells]
    xy = np.asarray(centres, dtype=float)[cells]

    def per_patch(values: FloatArray) -> FloatArray:
        return np.asarray(np.bincount(label, weights=values, minlength=count + 1)[1:], dtype=float)

    total, n = per_patch(w), per_patch(np.ones_like(w))
    weighted = total > 0
    mid = np.stack(
        [
            np.where(weighted, per_patch(xy[:, a] * w), per_patch(xy[:, a]))
            / np.where(weighted, total, n)
            for a in (0, 1)
        ],
        axis=1,
    )
    found = [((float(x), float(y)), float(t)) for (x, y), t in zip(mid, total, strict=True)]
    found.sort(key=lambda patch: -patch[1])
    return found


def _patches(
    past: BoolArray, plan_mm: FloatArray, area_mm2: FloatArray
) -> tuple[tuple[tuple[float, float], float], ...]:
    """Connected patches of ``past``: area-weighted plan centroid [mm] and area [mm²] of
    each, largest first, at most :data:`PATCHES_KEPT`."""
    return tuple(connected_patches(past, plan_mm, area_mm2)[:PATCHES_KEPT])


def wrinkling(
    result: DrapeResult, energy_density: FloatArray, limits: Sequence[WrinkleLimit]
) -> Wrinkling:
    """The wrinkling of a drape: ``energy_density`` W per cell (ni−1, nj−1) [J/m²] (the
    energy field's), ``limits`` from :func:`wrinkle_limits`. Counted cells are those the
    energy sums (valid, in the part), each by its share inside it."""
    counted = np.asarray(result.valid & result.in_part, dtype=bool)
    gamma = np.where(counted, np.asarray(result.shear, dtype=float), 0.0)
    weight = np.asarray(result.part_weight, dtype=float)
    area = np.asarray(result.area, dtype=float) * weight * 1e6  # mm², inside the part
    cell_energy = np.asarray(energy_density, dtype=float) * result.node_spacing**2 * weight
    total_energy = float(cell_energy[counted].sum())
    total_area = float(area[counted].sum())
    plan = np.asarray(result.centroid, dtype=float)[..., :2] * 1e3

    def share(part: float, whole: float) -> float:
        return part / whole if whole > 0 else 0.0

    zones = []
    union = np.zeros(counted.shape, dtype=bool)
    for limit in limits:
        past = counted & limit.past(gamma)
        union |= past
        a = float(area[past].sum())
        e = float(cell_energy[past].sum())
        bbox = centroid = None
        if past.any():
            xy = plan[past]
            w = area[past]
            lo, hi = xy.min(axis=0), xy.max(axis=0)
            bbox = (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
            centroid = _centre(xy, w)
        zones.append(
            WrinkleZone(
                limit=limit,
                cells=int(np.count_nonzero(past)),
                area_mm2=a,
                area_share=share(a, total_area),
                energy_J=e,
                energy_share=share(e, total_energy),
                bbox_mm=bbox,
                centroid_mm=centroid,
                max_abs_shear_deg=float(np.degrees(np.abs(gamma[past]).max())) if bbox else 0.0,
                max_excess_deg=(
                    float(np.degrees(limit.excess(gamma[past]).max())) if bbox else 0.0
                ),
                patches=_patches(past, plan, area),
            )
        )
    a = float(area[union].sum())
    e = float(cell_energy[union].sum())
    return Wrinkling(
        zones=tuple(zones),
        cells=int(np.count_nonzero(union)),
        area_mm2=a,
        area_share=share(a, total_area),
        energy_J=e,
        energy_share=share(e, total_energy),
        total_energy_J=total_energy,
        part_draped_area_mm2=total_area,
    )
