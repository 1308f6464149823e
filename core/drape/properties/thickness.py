"""One thickness per draped cell, the same in every output.

A draped cell's thickness ratio t/t0 comes from one of two models, named in words wherever a
thickness is written (the case summary's ``thickness_model``, the FE exports' comments):

- ``"sheared unit cell"`` when the fabric has one (``FabricBase.sheared_cell``: woven and
  warp-knit architectures): t/t0 = t(|γ|)/t(0) of the cell, read from the table the preform's
  properties use (``preform.drape.properties.preform_fields.PreformResponse``, not a second tabulation).
  Before the cell locks the thickness is t0 exactly (the fibre volume fraction grows as
  1/cos γ instead); after it the tows compact to their jamming fraction, then the cell
  thickens.
- ``"constant fibre volume fraction (1/cos γ)"`` otherwise (an architecture without a cell
  model), or, said in a warning, when the fabric's cell cannot be sheared: the cell keeps its
  fibre volume while its area shrinks to d² cos γ.

The reference t0 [mm] is, in this order: the scene's ``export.nominal_thickness_mm``; the
sheared cell's own thickness at γ = 0 (for the cell model: so t0 · t/t0 is the cell's thickness
t(γ) itself, the ``preform_thickness_mm`` of the ``permeability`` output); the fabric's derived
``thickness_mm`` (the unit cell's as-built thickness); else unknown (ratios only). A shear
law's ``fabric_thickness_mm`` is a free, uncompressed thickness the law's friction terms start
from, never the preform's t0. ``reference`` says which one a result used.

Every VALID cell gets its thickness, in the part or not (the part decides which cells count
for energy, not which cells exist); cells that are not VALID keep the ratio 1 the energy field
gives them (their values are NaN in every table).
"""

from __future__ import annotations

import dataclasses
import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np

from preform.base.arrays import FloatArray
from preform.drape.engine.result import DrapeResult, EnergyField
from preform.drape.properties.preform_fields import PreformResponse

#: The two thickness models, in the words every output uses.
SHEARED_CELL = "sheared unit cell"
CONSTANT_FIBRE_VOLUME = "constant fibre volume fraction (1/cos γ)"

#: Fabrics whose sheared-cell table is kept in memory (tabulating costs 0.5–2.5 ms per fabric,
#: benchmarks/README.md (j)).
CACHE_SIZE = 16
_TABLES: OrderedDict[str, PreformResponse | None] = OrderedDict()


@dataclass(frozen=True)
class ThicknessModel:
    """How a fabric's draped thickness follows its shear, and the reference t0."""

    #: ``SHEARED_CELL`` or ``CONSTANT_FIBRE_VOLUME``.
    name: str
    #: The reference thickness t0 [mm], None when unknown (outputs then give ratios only).
    reference_mm: float | None
    #: Where t0 comes from, in words.
    reference: str
    #: The sheared cell's table over |γ| (None for the constant-fraction model).
    response: PreformResponse | None = None
    #: Why the fabric's cell could not be sheared (then the constant-fraction model is used).
    cell_error: str | None = None

    def ratio(self, shear: FloatArray) -> FloatArray:
        """Thickness ratio t/t0 [-] at shear angles γ [rad] (either sign)."""
        gamma = np.asarray(shear, dtype=float)
        if self.response is None:
            return 1.0 / np.maximum(np.cos(gamma), 1e-12)
        thickness, _ = self.response.at(gamma)
        return np.asarray(thickness / self.response.thickness[0], dtype=float)

    def beyond_table(self, result: DrapeResult) -> int:
        """Valid cells sheared past the cell table's end (values held there)."""
        if self.response is None:
            return 0
        valid = np.asarray(result.valid, dtype=bool)
        shear = np.abs(np.asarray(result.shear, dtype=float))
        return int(np.count_nonzero(valid & (shear > self.response.shear[-1])))

    def applied(self, result: DrapeResult, energy: EnergyField) -> EnergyField:
        """``energy`` with this model's thickness ratio on every VALID cell (1 elsewhere, as
        the energy field has it) and its name: what every output reads."""
        valid = np.asarray(result.valid, dtype=bool)
        shear = np.where(valid, np.asarray(result.shear, dtype=float), 0.0)
        ratio = np.where(valid, self.ratio(shear), 1.0)
        return dataclasses.replace(
            energy,
            thickness_ratio=ratio,
            thickness_model=self.name,
            thickness_reference_mm=self.reference_mm,
        )

    def summary(self, result: DrapeResult) -> dict[str, object]:
        """The model, t0 and where it comes from, and the ratio's maximum over the part's
        cells (every valid cell when none lies in the part)."""
        out: dict[str, object] = {
            "thickness_model": self.name,
            "thickness_reference_mm": self.reference_mm,
            "thickness_reference": self.reference,
        }
        counted = np.asarray(result.valid & result.in_part, dtype=bool)
        if not counted.any():
            counted = np.asarray(result.valid, dtype=bool)
        if counted.any():
            ratio = self.ratio(np.asarray(result.shear, dtype=float)[counted])
            out["thickness_ratio_max"] = float(ratio.max())
        return out


def cell_table(fabric: Any) -> PreformResponse | None:
    """The fabric's sheared-cell table (``PreformResponse.from_fabric``), kept for the last
    ``CACHE_SIZE`` library fabrics by their full data, so a run tabulates each fabric once per
    process.
    None when the architecture has no sheared cell; a cell that cannot be sheared raises its
    ValueError (not kept)."""
    dump = getattr(fabric, "model_dump_json", None)
    if not callable(dump):  # not a library entry: nothing to key it by (an id is reused)
        return PreformResponse.from_fabric(fabric)
    key = f"{type(fabric).__module__}.{type(fabric).__qualname__}:{dump()}"
    if key in _TABLES:
        _TABLES.move_to_end(key)
        return _TABLES[key]
    response = PreformResponse.from_fabric(fabric)
    _TABLES[key] = response
    while len(_TABLES) > CACHE_SIZE:
        _TABLES.popitem(last=False)
    return response


def thickness_model(fabric: Any, nominal_thickness_mm: float | None = None) -> ThicknessModel:
    """The thickness model of ``fabric`` (module docstring); ``nominal_thickness_mm`` [mm] is
    the scene's t0 when it gives one."""
    error: str | None = None
    try:
        response = cell_table(fabric)
    except ValueError as exc:
        response, error = None, f"the sheared unit cell of {fabric.name}: {exc}"
    name = SHEARED_CELL if response is not None else CONSTANT_FIBRE_VOLUME
    if nominal_thickness_mm is not None:
        reference_mm: float | None = float(nominal_thickness_mm)
        reference = "the scene's export.nominal_thickness_mm"
    elif response is not None:
        reference_mm = 1e3 * float(response.thickness[0])
        reference = "the sheared unit cell's thickness at zero shear"
    else:
        reference_mm = derived_thickness_mm(fabric)
        reference = (
            "the fabric's derived thickness_mm (its unit cell as built)"
            if reference_mm is not None
            else "not known: give export.nominal_thickness_mm for thicknesses in mm"
        )
    return ThicknessModel(name, reference_mm, reference, response, error)


def derived_thickness_mm(fabric: Any) -> float | None:
    """The fabric's derived ``thickness_mm`` [mm], None when it has none (or cannot say)."""
    try:
        value = dict(fabric.derived()).get("thickness_mm")
    except Exception:  # a fabric whose derivation fails still drapes, without a t0
        return None
    if isinstance(value, (int, float)) and math.isfinite(value) and value > 0:
        return float(value)
    return None
