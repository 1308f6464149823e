"""The ``permeability`` output: the draped preform's thickness, Vf and permeability per cell.

A scene lists ``permeability`` among its outputs to have it computed (nothing else asks for it);
then the ``cells_csv`` and ``vtu`` outputs of the same scene carry its columns and arrays too,
and the case summary gets their ranges over the part (``preform.drape.properties.preform_fields``).
A fabric whose architecture has no sheared unit cell, or whose cell cannot be sheared, fails the
case in words; cells sheared past 89° (the table's end) are held there and said in a warning.

The ``thickness`` product (``preform.drape.properties.thickness``) is the one thickness model of a case:
the cell tables, the VTU and the FE mapping read it, and ``permeability`` reuses its table of
the sheared cell. Only outputs that write a thickness ask for it (tabulating the cell costs
0.1–2 s per fabric, once per process).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.status import CaseFailure
from preform.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene

#: The scene output that asks for the preform's properties.
OUTPUT = "permeability"


def preform_if_asked(scene: Scene) -> tuple[str, ...]:
    """Extra requirement of the drape's table and VTU: the properties, when the scene asks."""
    return (OUTPUT,) if OUTPUT in tuple(getattr(scene, "outputs", ()) or ()) else ()


def run_thickness(ctx: CaseContext) -> dict[str, Any]:
    from preform.drape.properties.thickness import SHEARED_CELL, thickness_model

    export = getattr(ctx.scene, "export", None)
    nominal = getattr(export, "nominal_thickness_mm", None)
    model = thickness_model(ctx.fabric, nominal)
    ply = ctx.products["drape"]
    ctx.summary.update(model.summary(ply.result))
    if model.cell_error is not None:
        ctx.warn(
            f"thickness: {model.cell_error}; the thickness follows the constant fibre volume "
            "fraction (1/cos γ) instead"
        )
    beyond = model.beyond_table(ply.result)
    if beyond and model.response is not None and not preform_if_asked(ctx.scene):
        # (the permeability step says the same of all its fields when it runs)
        ctx.warn(
            f"thickness: {beyond} cell(s) are sheared past "
            f"{math.degrees(model.response.shear[-1]):g}°, where the sheared unit cell ends: "
            "their thickness is held at that angle's"
        )
    if model.name == SHEARED_CELL and nominal is not None and model.response is not None:
        cell_mm = 1e3 * float(model.response.thickness[0])
        if not math.isclose(float(nominal), cell_mm, rel_tol=1e-9):
            ctx.warn(
                f"thickness: export.nominal_thickness_mm {float(nominal):g} mm is not the "
                f"sheared unit cell's {cell_mm:.4g} mm: thickness_mm is t/t0 of the cell times "
                f"{float(nominal):g} mm, while the cell's own thickness (preform_thickness_mm, "
                "with its fibre volume fraction) stays the cell's"
            )
    return {"thickness": model}


def run_permeability(ctx: CaseContext) -> dict[str, Any]:
    from preform.drape.properties.preform_fields import preform_field, preform_summary

    ply = ctx.products["drape"]
    fabric = ctx.fabric
    model = ctx.products.get("thickness")  # the planner runs the thickness step first
    if model is None:
        from preform.drape.properties.thickness import thickness_model

        model = thickness_model(fabric)
    if model.cell_error is not None:
        raise CaseFailure(f"permeability: {model.cell_error}")
    response = model.response
    if response is None:
        raise CaseFailure(
            f"permeability: architecture {fabric.architecture!r} has no sheared unit cell, so "
            "the preform's thickness, fibre volume fraction and permeability are unknown"
        )
    field = preform_field(ply.result, response)
    ctx.summary.update(preform_summary(ply.result, field))
    beyond = int(np.count_nonzero(field.beyond_table))
    if beyond:
        ctx.warn(
            f"{beyond} cell(s) are sheared past {math.degrees(response.shear[-1]):g}°, where the "
            "sheared unit cell ends: their thickness, fibre volume fraction and permeability "
            "are held at that angle's values"
        )
    return {OUTPUT: field}


STEPS = [
    Step(
        "thickness",
        ("thickness",),
        ("drape",),
        "1",
        run_thickness,
        "The draped thickness model: the sheared unit cell's t(γ)/t(0) where the fabric has "
        "one, else constant fibre volume fraction (1/cos γ); the reference thickness t0",
    ),
    Step(
        "permeability",
        (OUTPUT,),
        ("drape", "thickness"),
        "1",
        run_permeability,
        "Per draped cell: thickness and fibre volume fraction from the sheared unit cell, "
        "in-plane permeability tensor (Gebart fibre bed per family)",
    ),
]
