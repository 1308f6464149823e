"""Measured fibre angles on a draped preform: reading them from a CSV file or a scanner's point
cloud, in mm and degrees.

A measurement is a set of points on (or near) the tool, each with what was measured there:

- the fibre direction of the first family (``u``, the first generator's fibres) and/or the
  second (``v``) as a vector (any length, either sense: a fibre is a line), or
- the in-plane angle of a family to a stated reference direction [deg], signed about the
  tool's outward normal (counter-clockwise seen from outside), the convention of
  ``preform.export.fe_mapping``; the reference direction is projected into the tool's tangent
  plane at the point, or
- the shear angle only [deg], signed as preform signs it (``preform.drape.engine.result``: γ = ω − 90°
  with ω the angle from the u to the v fibres),

and optionally a standard uncertainty [deg] of each angle. Inside, points are in metres.

The CSV format (docs/compare.md): ``#`` lines are comments, except ``# reference_direction:
x y z`` (default 1 0 0); a header row names the columns, points in ``x_mm, y_mm, z_mm`` (or
``x_m, y_m, z_m``), then any of ``u_x, u_y, u_z``, ``v_x, v_y, v_z``, ``angle_u_deg``,
``angle_v_deg``, ``shear_deg``, ``uncertainty_deg`` and ``region`` (a label to summarise by).
An empty cell is "not measured". Every bad row is reported as ``FILE:LINE: column: message``,
all at once.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from preform.base.arrays import BoolArray, FloatArray

MM = 1e-3
#: Length units the point columns may carry, and their size in metres.
LENGTH_UNITS = {"mm": 1e-3, "m": 1.0}
VECTOR_COLUMNS = {"u": ("u_x", "u_y", "u_z"), "v": ("v_x", "v_y", "v_z")}
SCALAR_COLUMNS = ("angle_u_deg", "angle_v_deg", "shear_deg", "uncertainty_deg")
#: Uncertainty assumed where none is given [deg]; the inverse search then scales its covariance
#: by the residual scatter, so only the relative weights matter.
DEFAULT_UNCERTAINTY_DEG = 1.0


class MeasurementError(ValueError):
    """A measurement that cannot be read: ``errors`` holds every located message."""

    def __init__(self, errors: Sequence[str]) -> None:
        self.errors = list(errors)
        super().__init__("\n".join(self.errors))


@dataclass(frozen=True)
class Measurement:
    """Measured fibre angles at points; arrays have one row per point, NaN where not measured.

    Points are in metres; angles in degrees (the user's unit: they are never computed on
    inside preform except through :mod:`preform.compare.comparison`)."""

    #: Point positions (n, 3) [m].
    points: FloatArray
    #: Measured fibre directions of the u and v families (n, 3), unit, NaN where not given.
    direction_u: FloatArray
    direction_v: FloatArray
    #: In-plane angles of the u and v fibres to the reference direction (n,) [deg].
    angle_u_deg: FloatArray
    angle_v_deg: FloatArray
    #: Measured signed shear angle (n,) [deg].
    shear_deg: FloatArray
    #: Standard uncertainty of each angle (n,) [deg]; NaN where not given.
    uncertainty_deg: FloatArray
    #: Unit reference direction the angles are measured from (global frame).
    reference_direction: tuple[float, float, float] = (1.0, 0.0, 0.0)
    #: A label per point to summarise by ("" where none).
    region: tuple[str, ...] = ()
    #: Where each point came from, for messages ("file.csv:12").
    origin: tuple[str, ...] = ()
    #: Where the measurement came from, in words.
    source: str = ""
    #: Free-form notes of the file (its ``#`` comment lines).
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        n = len(self.points)
        if not self.region:
            object.__setattr__(self, "region", ("",) * n)
        if not self.origin:
            object.__setattr__(self, "origin", tuple(f"point {k + 1}" for k in range(n)))

    @property
    def count(self) -> int:
        return len(self.points)

    @property
    def has_u(self) -> BoolArray:
        """Points where the u family was measured (a vector or an angle)."""
        return np.asarray(
            np.all(np.isfinite(self.direction_u), axis=1) | np.isfinite(self.angle_u_deg)
        )

    @property
    def has_v(self) -> BoolArray:
        return np.asarray(
            np.all(np.isfinite(self.direction_v), axis=1) | np.isfinite(self.angle_v_deg)
        )

    @property
    def has_shear_only(self) -> BoolArray:
        return np.asarray(np.isfinite(self.shear_deg) & ~self.has_u & ~self.has_v)

    def sigma_deg(self) -> FloatArray:
        """The uncertainty of each point [deg], :data:`DEFAULT_UNCERTAINTY_DEG` where not
        given."""
        return np.where(
            np.isfinite(self.uncertainty_deg), self.uncertainty_deg, DEFAULT_UNCERTAINTY_DEG
        )

    def subset(self, keep: ArrayLike) -> Measurement:
        """The points where ``keep`` (bool, n) holds."""
        from dataclasses import replace

        mask = np.asarray(keep, dtype=bool)
        idx = np.flatnonzero(mask)
        return replace(
            self,
            points=self.points[mask],
            direction_u=self.direction_u[mask],
            direction_v=self.direction_v[mask],
            angle_u_deg=self.angle_u_deg[mask],
            angle_v_deg=self.angle_v_deg[mask],
            shear_deg=self.shear_deg[mask],
            uncertainty_deg=self.uncertainty_deg[mask],
            region=tuple(self.region[k] for k in idx),
            origin=tuple(self.origin[k] for k in idx),
        )


def _unit_rows(v: FloatArray) -> FloatArray:
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(np.where(norm > 0, v / norm, np.nan))


def measurement(
    points_mm: ArrayLike,
    *,
    direction_u: ArrayLike | None = None,
    direction_v: ArrayLike | None = None,
    angle_u_deg: ArrayLike | None = None,
    angle_v_deg: ArrayLike | None = None,
    shear_deg: ArrayLike | None = None,
    uncertainty_deg: ArrayLike | float | None = None,
    reference_direction: Sequence[float] = (1.0, 0.0, 0.0),
    region: Sequence[str] | None = None,
    source: str = "python",
) -> Measurement:
    """A :class:`Measurement` from arrays: ``points_mm`` (n, 3) [mm]; directions (n, 3) (any
    length, NaN rows where not measured); angles (n,) [deg] to ``reference_direction``;
    ``shear_deg`` (n,) [deg]; ``uncertainty_deg`` per point or one for all [deg]. Raises
    :class:`MeasurementError` naming the first bad point of each problem."""
    points = np.asarray(points_mm, dtype=float)
    errors: list[str] = []
    if points.ndim != 2 or points.shape[1] != 3:
        raise MeasurementError([f"{source}: points_mm must be (n, 3), got {points.shape}"])
    n = len(points)

    def column(values: ArrayLike | float | None, name: str, width: int = 0) -> FloatArray:
        shape = (n, width) if width else (n,)
        if values is None:
            return np.full(shape, np.nan)
        out = np.asarray(values, dtype=float)
        if out.ndim == 0 and not width:
            out = np.full(n, float(out))
        if out.shape != shape:
            errors.append(f"{source}: {name} must have shape {shape}, got {out.shape}")
            return np.full(shape, np.nan)
        return out

    data = {
        "u": column(direction_u, "direction_u", 3),
        "v": column(direction_v, "direction_v", 3),
        "angle_u_deg": column(angle_u_deg, "angle_u_deg"),
        "angle_v_deg": column(angle_v_deg, "angle_v_deg"),
        "shear_deg": column(shear_deg, "shear_deg"),
        "uncertainty_deg": column(uncertainty_deg, "uncertainty_deg"),
    }
    bad = ~np.all(np.isfinite(points), axis=1)
    if bad.any():
        errors.append(f"{source}: point {int(np.argmax(bad)) + 1}: position is not finite")
    sigma = data["uncertainty_deg"]
    if np.any(sigma[np.isfinite(sigma)] <= 0):
        k = int(np.argmax(np.isfinite(sigma) & (sigma <= 0)))
        errors.append(f"{source}: point {k + 1}: uncertainty_deg must be positive")
    for fam in ("u", "v"):
        vec = data[fam]
        given = np.any(np.isfinite(vec), axis=1)
        broken = given & ~(np.all(np.isfinite(vec), axis=1) & (np.linalg.norm(vec, axis=1) > 0))
        if broken.any():
            k = int(np.argmax(broken))
            errors.append(f"{source}: point {k + 1}: direction_{fam} must be a non-zero vector")
    ref = np.asarray(reference_direction, dtype=float)
    if ref.shape != (3,) or not np.all(np.isfinite(ref)) or not np.linalg.norm(ref) > 0:
        errors.append(f"{source}: reference_direction must be a non-zero 3-vector")
        ref = np.array([1.0, 0.0, 0.0])
    labels = tuple(str(r) for r in region) if region is not None else ("",) * n
    if len(labels) != n:
        errors.append(f"{source}: region needs one label per point")
    if errors:
        raise MeasurementError(errors)
    result = Measurement(
        points=points * MM,
        direction_u=_unit_rows(data["u"]),
        direction_v=_unit_rows(data["v"]),
        angle_u_deg=data["angle_u_deg"],
        angle_v_deg=data["angle_v_deg"],
        shear_deg=data["shear_deg"],
        uncertainty_deg=data["uncertainty_deg"],
        reference_direction=tuple(float(c) for c in ref / np.linalg.norm(ref)),  # type: ignore[arg-type]
        region=labels,
        source=source,
    )
    nothing = ~(result.has_u | result.has_v | np.isfinite(result.shear_deg))
    if nothing.any():
        raise MeasurementError(
            [f"{source}: point {int(np.argmax(nothing)) + 1}: nothing measured (no direction, "
             "angle or shear)"]
        )  # fmt: skip
    return result


def read_measurement(path: str | os.PathLike[str], *, unit: str = "mm") -> Measurement:
    """Read a measurement file: the CSV format of the module docstring (``.csv``, ``.txt``),
    or a point cloud meshio reads (``.ply``, ``.vtk``, ``.vtu``, ...) whose point data holds
    ``fibre_u``/``fibre_v`` vectors (or ``u_x``... components) and any of the scalar columns.
    ``unit`` is the length unit of a point cloud's coordinates (``mm`` or ``m``; a CSV says
    its own in the column names). Raises :class:`MeasurementError` with every located
    problem."""
    p = Path(path)
    if not p.is_file():
        raise MeasurementError([f"{p}: no such measurement file"])
    if p.suffix.lower() in (".csv", ".txt"):
        return _read_csv(p)
    return _read_cloud(p, unit)


def _read_csv(path: Path) -> Measurement:
    errors: list[str] = []
    notes: list[str] = []
    reference: list[float] = [1.0, 0.0, 0.0]
    with path.open(newline="", encoding="utf-8-sig") as handle:
        lines = handle.read().splitlines()
    body: list[tuple[int, str]] = []
    for number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            text = stripped.lstrip("#").strip()
            key, _, value = text.partition(":")
            if key.strip().lower() == "reference_direction":
                try:
                    reference = [float(c) for c in value.replace(",", " ").split()]
                    if len(reference) != 3:
                        raise ValueError
                except ValueError:
                    errors.append(
                        f"{path}:{number}: reference_direction: give three numbers, got "
                        f"{value.strip()!r}"
                    )
            else:
                notes.append(text)
            continue
        body.append((number, line))
    if not body:
        raise MeasurementError([f"{path}: no header row and no data"])
    header_line, header_text = body[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
    unit = next((u for u in LENGTH_UNITS if all(f"{c}_{u}" in header for c in "xyz")), None)
    if unit is None:
        raise MeasurementError(
            [f"{path}:{header_line}: the header needs point columns x_mm, y_mm, z_mm (or x_m, "
             f"y_m, z_m); found {', '.join(header)}"]
        )  # fmt: skip
    known = {f"{c}_{unit}" for c in "xyz"} | set(SCALAR_COLUMNS) | {"region"}
    known |= {c for cols in VECTOR_COLUMNS.values() for c in cols}
    unknown = [h for h in header if h not in known]
    if unknown:
        errors.append(
            f"{path}:{header_line}: unknown column(s) {', '.join(unknown)}; known: "
            f"{', '.join(sorted(known))}"
        )
    n = len(body) - 1
    values = {h: np.full(n, np.nan) for h in header if h != "region"}
    regions = [""] * n
    origin = []
    for row, (number, text) in enumerate(body[1:]):
        origin.append(f"{path.name}:{number}")
        cells = next(csv.reader([text]))
        if len(cells) != len(header):
            errors.append(f"{path}:{number}: {len(cells)} value(s) for {len(header)} column(s)")
            continue
        for name, cell in zip(header, cells, strict=True):
            cell = cell.strip()
            if name == "region":
                regions[row] = cell
                continue
            if cell == "":
                if name.startswith(("x_", "y_", "z_")):
                    errors.append(f"{path}:{number}: {name}: a point needs all three coordinates")
                continue
            try:
                number_value = float(cell)
            except ValueError:
                errors.append(f"{path}:{number}: {name}: not a number: {cell!r}")
                continue
            if not math.isfinite(number_value):
                errors.append(f"{path}:{number}: {name}: not a finite number: {cell!r}")
                continue
            if name == "uncertainty_deg" and number_value <= 0:
                errors.append(f"{path}:{number}: uncertainty_deg: must be positive, got {cell}")
                continue
            values[name][row] = number_value
        vector_given = {
            fam: [values[c][row] for c in cols if c in values]
            for fam, cols in VECTOR_COLUMNS.items()
        }
        for fam, comps in vector_given.items():
            finite = [math.isfinite(c) for c in comps]
            if any(finite) and not (len(comps) == 3 and all(finite)):
                errors.append(f"{path}:{number}: {fam}_x, {fam}_y, {fam}_z: give all three or none")
            elif all(finite) and len(comps) == 3 and not any(c != 0 for c in comps):
                errors.append(f"{path}:{number}: {fam}_x, {fam}_y, {fam}_z: a zero vector")
        measured = any(
            math.isfinite(values[c][row])
            for c in ("angle_u_deg", "angle_v_deg", "shear_deg", "u_x", "v_x")
            if c in values
        )
        if not measured and len(cells) == len(header):
            errors.append(f"{path}:{number}: nothing measured (no direction, angle or shear)")
    if n == 0:
        errors.append(f"{path}: no data rows after the header")
    if errors:
        raise MeasurementError(errors)

    def vec(fam: str) -> FloatArray | None:
        cols = VECTOR_COLUMNS[fam]
        if not all(c in values for c in cols):
            return None
        return np.stack([values[c] for c in cols], axis=1)

    scale = LENGTH_UNITS[unit] / MM
    points = np.stack([values[f"{c}_{unit}"] for c in "xyz"], axis=1) * scale
    try:
        found = measurement(
            points,
            direction_u=vec("u"),
            direction_v=vec("v"),
            angle_u_deg=values.get("angle_u_deg"),
            angle_v_deg=values.get("angle_v_deg"),
            shear_deg=values.get("shear_deg"),
            uncertainty_deg=values.get("uncertainty_deg"),
            reference_direction=reference,
            region=regions,
            source=str(path),
        )
    except MeasurementError as exc:
        raise MeasurementError(exc.errors) from None
    from dataclasses import replace

    return replace(found, origin=tuple(origin), notes=tuple(notes))


def _read_cloud(path: Path, unit: str) -> Measurement:
    import meshio

    if unit not in LENGTH_UNITS:
        raise MeasurementError([f"{path}: unit must be one of {', '.join(LENGTH_UNITS)}"])
    try:
        cloud = meshio.read(str(path))
    except Exception as exc:  # meshio raises many types for a file it cannot read
        raise MeasurementError([f"{path}: not a point cloud meshio can read: {exc}"]) from None
    data = {k: np.asarray(v, dtype=float) for k, v in cloud.point_data.items()}

    def vector(fam: str) -> FloatArray | None:
        whole = data.get(f"fibre_{fam}")
        if whole is not None:
            return whole.reshape(len(cloud.points), -1)[:, :3]
        cols = VECTOR_COLUMNS[fam]
        if all(c in data for c in cols):
            return np.stack([data[c] for c in cols], axis=1)
        return None

    vectors = {fam: vector(fam) for fam in ("u", "v")}
    scalars = {c: data[c].reshape(-1) if c in data else None for c in SCALAR_COLUMNS}
    if all(v is None for v in vectors.values()) and all(s is None for s in scalars.values()):
        raise MeasurementError(
            [f"{path}: the point data holds no fibre directions or angles (looked for fibre_u, "
             f"fibre_v, u_x.., {', '.join(SCALAR_COLUMNS)}; found {', '.join(data) or 'none'})"]
        )  # fmt: skip
    points = np.asarray(cloud.points, dtype=float)
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    return measurement(
        points * LENGTH_UNITS[unit] / MM,
        direction_u=vectors["u"],
        direction_v=vectors["v"],
        angle_u_deg=scalars["angle_u_deg"],
        angle_v_deg=scalars["angle_v_deg"],
        shear_deg=scalars["shear_deg"],
        uncertainty_deg=scalars["uncertainty_deg"],
        source=str(path),
    )
