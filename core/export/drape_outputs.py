"""The drape's own files of a case, as pipeline steps: ``cells.csv`` (one row per cell),
``drape.vtu`` (ParaView) and ``fibre_pattern.png``. They sit with the writers they call, above
the drape that makes what they write."""

from __future__ import annotations

from typing import Any

from preform.drape.preform_steps import preform_if_asked
from preform.drape.steps import DrapedPly, scene_part
from preform.step import CaseContext, Step


def write_cells_csv(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.csv_columns import write_csv_columns
    from preform.export.tables import cell_columns

    ply: DrapedPly = ctx.products["drape"]
    energy = ctx.products["thickness"].applied(ply.result, ply.energy)  # the case's one thickness
    preform = ctx.products.get("permeability")  # only when the scene asks for it
    # without pandas: its import costs a worker more than the table (preform.export.csv_columns)
    write_csv_columns(cell_columns(ply.result, energy, preform), ctx.case_dir / "cells.csv")
    return {"cells_csv": "cells.csv"}


def write_vtu(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.vtu import write_drape_vtu

    ply: DrapedPly = ctx.products["drape"]
    energy = ctx.products["thickness"].applied(ply.result, ply.energy)  # the case's one thickness
    preform = ctx.products.get("permeability")  # only when the scene asks for it
    write_drape_vtu(ply.result, energy, ctx.case_dir / "drape.vtu", preform)
    return {"vtu": "drape.vtu"}


def write_fibre_pattern_png(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.fig_drape import fibre_pattern_figure

    ply: DrapedPly = ctx.products["drape"]
    every = max(1, round(5e-3 / ply.result.node_spacing))  # a tow line every ~5 mm
    surface = ctx.products.get("surface")
    fibre_pattern_figure(
        ply.result,
        ply.energy,
        ctx.case_dir / "fibre_pattern.png",
        title=ctx.fabric.name,  # the figure adds the angle, coverage and energy
        tow_every=every,
        part=scene_part(ctx.scene, surface) if surface is not None else None,
        covered_fraction=ctx.summary.get("covered_fraction"),
    )
    return {"fibre_pattern_png": "fibre_pattern.png"}


EXPORTERS = [
    Step.exporter(
        "cells_csv",
        ("drape", "thickness"),
        write_cells_csv,
        "cells.csv: one row per cell (shear, energy, status, thickness; Vf, permeability "
        "when the scene asks for permeability)",
        extra_requires=preform_if_asked,
    ),
    Step.exporter(
        "vtu",
        ("drape", "thickness"),
        write_vtu,
        "drape.vtu for ParaView",
        extra_requires=preform_if_asked,
    ),
    Step.exporter(
        "fibre_pattern_png",
        ("drape",),
        write_fibre_pattern_png,
        "fibre_pattern.png: top view with tows, 3D view by shear",
    ),
]
