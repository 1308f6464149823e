"""The ``permeability`` output: the draped preform's thickness, Vf and permeability per cell.

A scene lists ``permeability`` among its outputs to have it computed (nothing else asks for it);
then the ``cells_csv`` and ``vtu`` outputs of the same scene carry its columns and arrays too,
and the case summary gets their ranges over the part (``preform.drape.preform_fields``).
A fabric whose architecture has no sheared unit cell, or whose cell cannot be sheared, fails the
case in words; cells sheared past 89° (the table's end) are held there and said in a warning.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.pipeline.status import CaseFailure
from preform.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene

#: The scene output that asks for the preform's properties.
OUTPUT = "permeability"


def preform_if_asked(scene: Scene) -> tuple[str, ...]:
    """Extra requirement of the drape's table and VTU: the properties, when the scene asks."""
    return (OUTPUT,) if OUTPUT in tuple(getattr(scene, "outputs", ()) or ()) else ()


def run_permeability(ctx: CaseContext) -> dict[str, Any]:
    from preform.drape.preform_fields import PreformResponse, preform_field, preform_summary

    ply = ctx.products["drape"]
    fabric = ctx.fabric
    try:
        response = PreformResponse.from_fabric(fabric)
    except ValueError as error:
        raise CaseFailure(
            f"permeability: the sheared unit cell of {fabric.name}: {error}"
        ) from None
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
        "permeability",
        (OUTPUT,),
        ("drape",),
        "1",
        run_permeability,
        "Per draped cell: thickness and fibre volume fraction from the sheared unit cell, "
        "in-plane permeability tensor (Gebart fibre bed per family)",
    )
]
