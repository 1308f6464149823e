"""A drape compared with a measurement: per measured point, the angle between the measured and
predicted fibres of each family, the shear difference, and flags; summaries by region.

How:

1. **On the tool.** Each point's distance to the tool is measured first (the tool's closest
   point); a point farther than ``max_gap_mm`` (default: the node spacing d) is *off the tool*,
   reported and left out. When most points are off the tool and a unit factor (m, cm, inch)
   would put them on it, the file has a unit slip: :class:`UnitSlipError` says which.
2. **On the net.** The others are put at their closest point on the draped net and the drape's
   cell fields interpolated there, exactly as the FE mapping does
   (``preform.export.fe_mapping.closest_on_net`` and its bilinear interpolation of the cell
   centres); a point past the net's edge (its closest point is not the foot of a perpendicular)
   is *off the net*: outside the draped ply.
3. **Angles in the tool's tangent plane.** Measured and predicted fibres are projected into the
   tangent plane of the tool at the point's closest point (the net's own plane when no tool is
   given), and the error of a family is the signed angle from the predicted to the measured
   fibre about the outward normal [deg], wrapped to (−90°, 90°] (a fibre is a line). Measured
   in-plane angles become vectors from the reference direction projected into the same plane.
   The shear error is measured minus predicted γ [deg]; the measured γ is the given
   ``shear_deg``, else the angle between the measured families minus 90°.
4. **Flags.** ``off_tool``, ``off_net``, ``outside_part`` (the net cell is not in the part),
   ``near_fold`` (within one cell of a folded node or a cell lost behind it) and
   ``wrinkle_zone`` (the net cell is past a limit where the fabric would wrinkle:
   ``preform.drape.judging.wrinkling``, known when the energy field is given).

Summaries (rms, mean, max and percentiles of the absolute errors) are over the compared points,
for all of them and per region: the measurement's own ``region`` labels, and the flags'.
Everything a user reads is in mm and degrees.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import BoolArray, FloatArray
from preform.compare.measurement import MM, Measurement, MeasurementError
from preform.drape.engine.result import DrapeResult, EnergyField, NodeStatus
from preform.export.fe_mapping import (
    EDGE_TOLERANCE,
    NetHit,
    _dual_bilinear,
    _in_plane,
    _signed_angle_deg,
    _unit,
    closest_on_net,
)

if TYPE_CHECKING:
    import pandas as pd


#: Unit factors a file's points are tried with when most of them miss the tool: the factor
#: that turns the numbers into mm, and what the file then held.
UNIT_SLIPS = ((1000.0, "metres"), (10.0, "centimetres"), (25.4, "inches"), (1e-3, "micrometres"))
#: Share of the points that must miss the tool before a unit slip is looked for, and that a
#: factor must put on it to be named.
SLIP_OFF_SHARE = 0.5
SLIP_ON_SHARE = 0.8
#: Percentiles every summary reports.
PERCENTILES = (50, 90, 95)
FLAGS = ("off_tool", "off_net", "outside_part", "near_fold", "wrinkle_zone")


class UnitSlipError(MeasurementError):
    """The measurement's points miss the tool unless scaled: a unit slip."""


@dataclass(frozen=True)
class OnTool:
    """Where each measured point meets the tool: foot normal and distance."""

    #: Unit outward normal of the tool at each point's closest point (n, 3); NaN without a tool.
    normal: FloatArray
    #: Distance to the tool (n,) [mm]; NaN without a tool.
    distance_mm: FloatArray
    off_tool: BoolArray
    tolerance_mm: float


def on_tool(
    measurement: Measurement, surface: Any | None, tolerance_mm: float, *, check_units: bool = True
) -> OnTool:
    """Each point's distance to ``surface`` [m] and the tool's normal there; points farther than
    ``tolerance_mm`` [mm] are off the tool. With ``check_units``, raise :class:`UnitSlipError`
    when most points miss the tool and a unit factor puts them on it."""
    n = measurement.count
    if surface is None:
        nan = np.full(n, np.nan)
        return OnTool(np.full((n, 3), np.nan), nan, np.zeros(n, dtype=bool), tolerance_mm)
    foot, dist = surface.closest_point(measurement.points)
    distance_mm = np.asarray(dist, dtype=float) / MM
    off = ~(distance_mm <= tolerance_mm)
    if check_units and n and np.count_nonzero(off) > SLIP_OFF_SHARE * n:
        _say_unit_slip(measurement, surface, tolerance_mm, int(np.count_nonzero(off)))
    normal = np.asarray(surface.normal(np.where(np.isfinite(foot), foot, 0.0)), dtype=float)
    return OnTool(_unit(normal), distance_mm, off, tolerance_mm)


def _say_unit_slip(measurement: Measurement, surface: Any, tolerance_mm: float, off: int) -> None:
    n = measurement.count
    for factor, unit in UNIT_SLIPS:
        _, dist = surface.closest_point(measurement.points * factor)
        on = int(np.count_nonzero(np.asarray(dist) / MM <= tolerance_mm))
        if on >= SLIP_ON_SHARE * n:
            lo = measurement.points.min(axis=0) / MM
            hi = measurement.points.max(axis=0) / MM
            raise UnitSlipError(
                [f"{measurement.source}: {off} of {n} points are off the tool (farther than "
                 f"{tolerance_mm:g} mm) and span only x {lo[0]:.4g} … {hi[0]:.4g}, y "
                 f"{lo[1]:.4g} … {hi[1]:.4g}, z {lo[2]:.4g} … {hi[2]:.4g} mm; multiplied by "
                 f"{factor:g}, {on} lie on it: the points look like they are in {unit}, not "
                 "mm. Convert them to mm (or, in a CSV, name the columns x_m, y_m, z_m for "
                 "metres; a point cloud: unit='m', --unit m)"]
            )  # fmt: skip


def _wrap_line_deg(angle: FloatArray) -> FloatArray:
    """An angle between lines [deg] wrapped to (−90, 90]."""
    return np.asarray(90.0 - np.mod(90.0 - angle, 180.0))


def _fold_cells(result: DrapeResult) -> BoolArray:
    """Cells within one cell of a folded node or a cell lost behind it."""
    status = result.status
    bad = (status == NodeStatus.FOLDED) | (status == NodeStatus.NO_INTERSECTION)
    if not bad.any():
        return np.zeros(result.cell_status.shape, dtype=bool)
    from preform.drape.judging.verdict import dependency_shadow

    shadow = bad | (dependency_shadow(bad, result.start_index) & (status != NodeStatus.PLACED))
    cells = shadow[:-1, :-1] | shadow[1:, :-1] | shadow[:-1, 1:] | shadow[1:, 1:]
    grown = cells.copy()
    grown[1:, :] |= cells[:-1, :]
    grown[:-1, :] |= cells[1:, :]
    grown[:, 1:] |= grown[:, :-1].copy()
    grown[:, :-1] |= grown[:, 1:].copy()
    return np.asarray(grown)


@dataclass(frozen=True)
class PointAngles:
    """Measured and predicted angles at each point and their differences [deg], one row per
    point."""

    #: Predicted in-plane angles of the u and v fibres to the reference direction [deg], and
    #: predicted signed shear [deg].
    predicted_angle_u_deg: FloatArray
    predicted_angle_v_deg: FloatArray
    predicted_shear_deg: FloatArray
    #: Measured in-plane angles (from vectors or angles) [deg] and measured shear [deg].
    measured_angle_u_deg: FloatArray
    measured_angle_v_deg: FloatArray
    measured_shear_deg: FloatArray
    #: Measured minus predicted: fibre angle of each family (−90, 90] and shear [deg].
    error_u_deg: FloatArray
    error_v_deg: FloatArray
    error_shear_deg: FloatArray


@dataclass(frozen=True)
class Comparison(PointAngles):
    """A drape against a measurement, one row per measured point (mm, degrees).

    Errors are NaN where the point is not compared (off the tool, off the net) or the
    quantity was not measured; flags say which."""

    measurement: Measurement
    #: Measured points (n, 3) [mm].
    point_mm: FloatArray
    #: Distance to the tool [mm] (NaN without a tool) and to the net, normal to it [mm].
    tool_gap_mm: FloatArray
    net_gap_mm: FloatArray
    off_tool: BoolArray
    off_net: BoolArray
    outside_part: BoolArray
    near_fold: BoolArray
    wrinkle_zone: BoolArray
    #: Net cell holding each compared point (−1 where none).
    cell_i: NDArray[np.int64]
    cell_j: NDArray[np.int64]
    node_spacing_mm: float
    max_gap_mm: float
    #: Whether the angles are in the tool's tangent plane ("tool") or the net's ("net").
    plane: str = "tool"

    @property
    def compared(self) -> BoolArray:
        return np.asarray(~self.off_tool & ~self.off_net)

    def groups(self) -> dict[str, BoolArray]:
        """The points of each region: ``all``, the measurement's labels, and the flags."""
        out: dict[str, BoolArray] = {"all": np.ones(len(self.point_mm), dtype=bool)}
        labels = np.asarray(self.measurement.region, dtype=object)
        for label in sorted({r for r in self.measurement.region if r}):
            out[f"region {label}"] = np.asarray(labels == label)
        for name in ("outside_part", "near_fold", "wrinkle_zone"):
            mask = np.asarray(getattr(self, name))
            if mask.any():
                out[name] = mask
        return out

    def statistics(self, mask: BoolArray | None = None) -> dict[str, Any]:
        """rms, mean, max and percentiles of |error| over the compared points in ``mask``:
        the two families pooled (``angle``), each family, and the shear [deg]."""
        keep = self.compared if mask is None else self.compared & mask
        out: dict[str, Any] = {"points": int(np.count_nonzero(keep))}
        pooled = np.concatenate([self.error_u_deg[keep], self.error_v_deg[keep]])
        for name, values in (
            ("angle", pooled),
            ("u", self.error_u_deg[keep]),
            ("v", self.error_v_deg[keep]),
            ("shear", self.error_shear_deg[keep]),
        ):
            err = np.abs(values[np.isfinite(values)])
            out[f"{name}_count"] = int(err.size)
            if err.size:
                out[f"{name}_rms_deg"] = float(np.sqrt(np.mean(err**2)))
                out[f"{name}_mean_abs_deg"] = float(np.mean(err))
                out[f"{name}_max_deg"] = float(np.max(err))
                for q in PERCENTILES:
                    out[f"{name}_p{q}_deg"] = float(np.percentile(err, q))
        return out

    def summary(self) -> dict[str, Any]:
        """JSON-ready counts, flags and statistics (all and by region) [mm, deg]."""
        n = len(self.point_mm)
        out: dict[str, Any] = {
            "source": self.measurement.source,
            "points": n,
            "points_compared": int(np.count_nonzero(self.compared)),
            **{f"points_{flag}": int(np.count_nonzero(getattr(self, flag))) for flag in FLAGS},
            "off_tool_points": [
                self.measurement.origin[k] for k in np.flatnonzero(self.off_tool)[:20]
            ],
            "node_spacing_mm": self.node_spacing_mm,
            "max_gap_mm": self.max_gap_mm,
            "reference_direction": list(self.measurement.reference_direction),
            "angle_plane": self.plane,
            "length_unit": "mm",
            "angle_unit": "deg",
        }
        out.update(self.statistics())
        out["by_region"] = {
            name: self.statistics(mask) for name, mask in self.groups().items() if name != "all"
        }
        return out

    def words(self) -> str:
        """One line: how far the drape is from the measurement."""
        s = self.statistics()
        if "angle_rms_deg" not in s and "shear_rms_deg" not in s:
            return f"no point of {len(self.point_mm)} could be compared"
        name = "angle" if "angle_rms_deg" in s else "shear"
        text = (
            f"{s['points']} of {len(self.point_mm)} points compared: {name} error rms "
            f"{s[f'{name}_rms_deg']:.3g}°, p95 {s[f'{name}_p95_deg']:.3g}°, max "
            f"{s[f'{name}_max_deg']:.3g}°"
        )
        skipped = [
            f"{int(np.count_nonzero(getattr(self, f)))} {f.replace('_', ' ')}"
            for f in ("off_tool", "off_net")
            if np.any(getattr(self, f))
        ]
        return text + (f" ({', '.join(skipped)})" if skipped else "")

    def to_pandas(self) -> pd.DataFrame:
        """One row per measured point: position [mm], measured and predicted angles, errors
        [deg], flags."""
        import pandas as pd

        columns: dict[str, Any] = {
            "origin": list(self.measurement.origin),
            "region": list(self.measurement.region),
            "x_mm": self.point_mm[:, 0],
            "y_mm": self.point_mm[:, 1],
            "z_mm": self.point_mm[:, 2],
            "tool_gap_mm": self.tool_gap_mm,
            "net_gap_mm": self.net_gap_mm,
            "measured_angle_u_deg": self.measured_angle_u_deg,
            "predicted_angle_u_deg": self.predicted_angle_u_deg,
            "error_u_deg": self.error_u_deg,
            "measured_angle_v_deg": self.measured_angle_v_deg,
            "predicted_angle_v_deg": self.predicted_angle_v_deg,
            "error_v_deg": self.error_v_deg,
            "measured_shear_deg": self.measured_shear_deg,
            "predicted_shear_deg": self.predicted_shear_deg,
            "error_shear_deg": self.error_shear_deg,
        }
        for flag in FLAGS:
            columns[flag] = np.asarray(getattr(self, flag))
        return pd.DataFrame(columns)


@dataclass(frozen=True)
class Evaluation(PointAngles):
    """The raw per-point numbers of a comparison [deg], for every point whether or not it is on
    the net (past the net's edge the interpolation extends the edge cells): what the inverse
    search minimises. :class:`Comparison` is the reported, masked form."""

    hit: NetHit
    on_net: BoolArray


def evaluate(
    result: DrapeResult,
    measurement: Measurement,
    tool: OnTool,
    max_gap_mm: float,
    *,
    use_tool_plane: bool = True,
) -> Evaluation:
    """The measured and predicted angles at every point and their differences [deg] (module
    docstring, steps 2 and 3); ``use_tool_plane`` False measures in the net's own plane."""
    d_mm = float(result.node_spacing) / MM
    n = measurement.count
    region = np.asarray(result.valid, dtype=bool)
    if not region.any():
        raise ValueError("the draped net has no valid cell to compare with")
    hit = closest_on_net(result, measurement.points / MM, region)
    on_net = (hit.tangential_mm <= EDGE_TOLERANCE * d_mm) & (hit.gap_mm <= max_gap_mm)
    per_cell = {
        "fibre_u": np.asarray(result.fibre_u, dtype=float),
        "fibre_v": np.asarray(result.fibre_v, dtype=float),
    }
    values = _dual_bilinear(per_cell, region, hit.a, hit.b)
    fu, fv = values["fibre_u"], values["fibre_v"]
    normal = tool.normal if use_tool_plane else _unit(np.cross(fu, fv))
    ref = np.broadcast_to(np.asarray(measurement.reference_direction), (n, 3)).copy()
    ref_p = _in_plane(ref, normal)
    side = np.cross(normal, ref_p)

    def measured_vector(direction: FloatArray, angle_deg: FloatArray) -> FloatArray:
        a = np.radians(angle_deg)[:, None]
        from_angle = np.cos(a) * ref_p + np.sin(a) * side
        given = np.all(np.isfinite(direction), axis=1)
        return np.asarray(_in_plane(np.where(given[:, None], direction, from_angle), normal))

    meas_u = measured_vector(measurement.direction_u, measurement.angle_u_deg)
    meas_v = measured_vector(measurement.direction_v, measurement.angle_v_deg)
    pred_u, pred_v = _in_plane(fu, normal), _in_plane(fv, normal)
    # Shear as a measurement sees it: the angle between the fibres in the tangent plane, from
    # the same interpolated fibres (the cell's own γ, a mean of corner angles, differs from it
    # by O(d²): 0.03° at d = R/20 on a hemisphere).
    predicted_shear = np.mod(_signed_angle_deg(pred_u, pred_v, normal), 180.0) - 90.0
    between = np.mod(_signed_angle_deg(meas_u, meas_v, normal), 180.0) - 90.0
    measured_shear = np.where(np.isfinite(measurement.shear_deg), measurement.shear_deg, between)
    return Evaluation(
        hit=hit,
        on_net=np.asarray(on_net),
        predicted_angle_u_deg=_wrap_line_deg(_signed_angle_deg(ref_p, pred_u, normal)),
        predicted_angle_v_deg=_wrap_line_deg(_signed_angle_deg(ref_p, pred_v, normal)),
        predicted_shear_deg=np.asarray(predicted_shear),
        measured_angle_u_deg=_wrap_line_deg(_signed_angle_deg(ref_p, meas_u, normal)),
        measured_angle_v_deg=_wrap_line_deg(_signed_angle_deg(ref_p, meas_v, normal)),
        measured_shear_deg=np.asarray(measured_shear, dtype=float),
        error_u_deg=_wrap_line_deg(_signed_angle_deg(pred_u, meas_u, normal)),
        error_v_deg=_wrap_line_deg(_signed_angle_deg(pred_v, meas_v, normal)),
        error_shear_deg=np.asarray(measured_shear - predicted_shear, dtype=float),
    )


def compare(
    result: DrapeResult,
    measurement: Measurement,
    *,
    surface: Any | None = None,
    energy: EnergyField | None = None,
    max_gap_mm: float | None = None,
    check_units: bool = True,
    tool: OnTool | None = None,
) -> Comparison:
    """Compare the draped net ``result`` [m] with ``measurement`` (module docstring).

    ``surface``: the tool the net lies on (for the off-tool check, the unit-slip check and the
    tangent planes); without it the net's own plane is used and no point is off the tool.
    ``energy``: the net's energy field, for the wrinkle-zone flag. ``max_gap_mm``: farthest a
    point may lie from the tool and from the net [mm] (default the node spacing d).
    ``tool``: :func:`on_tool`'s answer when already computed (the inverse search reuses it).
    Raises :class:`UnitSlipError` for a unit slip."""
    d_mm = float(result.node_spacing) / MM
    gap = d_mm if max_gap_mm is None else float(max_gap_mm)
    if not gap > 0:
        raise ValueError(f"max_gap_mm must be positive, got {max_gap_mm!r}")
    if tool is None:
        tool = on_tool(measurement, surface, gap, check_units=check_units)
    n = measurement.count
    points_mm = measurement.points / MM
    nan = np.full(n, np.nan)
    ev = evaluate(result, measurement, tool, gap, use_tool_plane=surface is not None)
    hit, compared = ev.hit, ev.on_net & ~tool.off_tool
    plane = "tool" if surface is not None else "net"

    def only(values: FloatArray) -> FloatArray:
        return np.where(compared, values, np.nan)

    fold = _fold_cells(result)
    ci = np.where(compared, hit.cell_i, -1)
    cj = np.where(compared, hit.cell_j, -1)

    def cell_flag(cells: BoolArray | None) -> BoolArray:
        out = np.zeros(n, dtype=bool)
        if cells is not None and compared.any():
            out[compared] = np.asarray(cells, dtype=bool)[ci[compared], cj[compared]]
        return out

    wrinkles = energy.wrinkling if energy is not None else None
    return Comparison(
        measurement=measurement,
        point_mm=points_mm,
        tool_gap_mm=tool.distance_mm,
        net_gap_mm=np.where(tool.off_tool, nan, hit.gap_mm),
        # what was measured stays whatever the net; what the net predicts only where compared
        **{
            f.name: getattr(ev, f.name)
            if f.name.startswith("measured")
            else only(getattr(ev, f.name))
            for f in fields(PointAngles)
        },
        off_tool=tool.off_tool,
        off_net=~ev.on_net & ~tool.off_tool,
        outside_part=cell_flag(~np.asarray(result.in_part, dtype=bool)),
        near_fold=cell_flag(fold),
        wrinkle_zone=cell_flag(wrinkles),
        cell_i=ci.astype(np.int64),
        cell_j=cj.astype(np.int64),
        node_spacing_mm=d_mm,
        max_gap_mm=gap,
        plane=plane,
    )
