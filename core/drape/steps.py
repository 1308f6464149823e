"""Pipeline steps of the drape: build the tool, drape the ply, export the draped pattern.

The drape step uses the scene's generator angle, or the minimum-energy search's optimum when
the scene has a ``search`` section. Scenes give mm and degrees; everything here is SI.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.drape.fields import energy_field, summary
from preform.drape.net import drape
from preform.drape.ply import PlyOutline
from preform.drape.result import DrapeResult, EnergyField
from preform.pipeline import fidelity
from preform.pipeline.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene

MM = 1e-3


@dataclass(frozen=True)
class DrapedPly:
    """The ``drape`` product: the net and its strain energy under the fabric's law."""

    result: DrapeResult
    energy: EnergyField


def build_surface(scene: Scene, registry: Any) -> Any:
    """The scene's tool surface [m]."""
    tool = scene.tool
    return registry.surface_type(tool.surface).build(tool, scene.base_dir)


def drape_settings(scene: Scene, surface: Any) -> dict[str, Any]:
    """Keyword arguments of :func:`preform.drape.net.drape` from a scene (SI units), with the
    fidelity knobs resolved against the tool (``preform.pipeline.fidelity``)."""
    ply, start = scene.ply, scene.start
    if ply is None or start is None:
        raise ValueError("a drape needs the scene sections 'ply' and 'start'")
    knobs = fidelity.resolve(scene, float(surface.size))
    assert knobs.node_spacing_mm is not None
    if ply.outline_mm is not None:
        outline = PlyOutline.polygon(np.asarray(ply.outline_mm, dtype=float) * MM)
    else:
        size = ply.size_mm or (1000.0, 1000.0)
        outline = PlyOutline.rectangle(
            (size[0] * MM, size[1] * MM), offset_m=(-ply.offset_mm[0] * MM, -ply.offset_mm[1] * MM)
        )
    settings: dict[str, Any] = {
        "node_spacing_m": knobs.node_spacing_mm * MM,
        "ply": outline,
        "start_xy_m": (start.point_mm[0] * MM, start.point_mm[1] * MM),
        "orientation_rad": float(np.radians(start.orientation_deg)),
        "generators": start.generators,
        "tolerance": knobs.solver_tolerance,
        "substeps": knobs.generator_substeps,
    }
    if start.generators == "polyline":
        from preform.drape.generators import PlanPolylines

        if start.generator_polylines_mm is None:
            raise ValueError("generators: polyline needs start.generator_polylines_mm")
        first, second = (np.asarray(p, dtype=float) * MM for p in start.generator_polylines_mm)
        settings["generators"] = PlanPolylines(first, second)
        settings["orientation_rad"] = None
    return settings


def record_knobs(ctx: CaseContext, surface: Any) -> fidelity.Knobs:
    """Resolve the scene's fidelity knobs and record them as scalar results of the case."""
    knobs = fidelity.resolve(ctx.scene, float(surface.size))
    for key, value in knobs.as_dict().items():
        ctx.summary[key if key == "fidelity" else f"knob_{key}"] = value
    return knobs


def run_surface(ctx: CaseContext) -> dict[str, Any]:
    return {"surface": build_surface(ctx.scene, ctx.registry)}


def run_drape(ctx: CaseContext) -> dict[str, Any]:
    settings = drape_settings(ctx.scene, ctx.products["surface"])
    record_knobs(ctx, ctx.products["surface"])
    optimum = ctx.products.get("optimum")
    if optimum is not None:
        # the search may also have chosen the orientation, the start or curved generators
        alpha = float(optimum["generator_angle_rad"])
        for key, setting in (
            ("orientation_rad", "orientation_rad"),
            ("start_xy_m", "start_xy_m"),
            ("generators", "generators"),
        ):
            if optimum.get(key) is not None:
                settings[setting] = optimum[key]
    else:
        assert ctx.scene.start is not None
        alpha = float(np.radians(ctx.scene.start.generator_angle_deg))
    if settings["orientation_rad"] is None:
        alpha_arg: float | None = None
    else:
        alpha_arg = alpha
    result = drape(ctx.products["surface"], generator_angle_rad=alpha_arg, **settings)
    energy = energy_field(result, ctx.products["shear_law"])
    ctx.summary.update(summary(result, energy))
    ctx.summary["generator_angle_deg"] = float(np.degrees(result.generator_angle))
    return {"drape": DrapedPly(result, energy)}


def _needs_optimum(scene: Scene) -> tuple[str, ...]:
    return ("optimum",) if scene.search is not None else ()


def write_cells_csv(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.tables import cells_table, write_table

    ply: DrapedPly = ctx.products["drape"]
    write_table(cells_table(ply.result, ply.energy), ctx.case_dir / "cells.csv")
    return {"cells_csv": "cells.csv"}


def write_vtu(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.vtu import write_drape_vtu

    ply: DrapedPly = ctx.products["drape"]
    write_drape_vtu(ply.result, ply.energy, ctx.case_dir / "drape.vtu")
    return {"vtu": "drape.vtu"}


def write_fibre_pattern_png(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.fig_drape import fibre_pattern_figure

    ply: DrapedPly = ctx.products["drape"]
    alpha = np.degrees(ply.result.generator_angle)
    every = max(1, round(5e-3 / ply.result.node_spacing))  # a tow line every ~5 mm
    fibre_pattern_figure(
        ply.result,
        ply.energy,
        ctx.case_dir / "fibre_pattern.png",
        title=f"{ctx.fabric.name}: generator angle {alpha:.1f}°",
        tow_every=every,
    )
    return {"fibre_pattern_png": "fibre_pattern.png"}


def write_flat_pattern(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.flat_pattern import (
        flat_pattern,
        write_flat_pattern_csv,
        write_flat_pattern_dxf,
        write_flat_pattern_svg,
    )

    ply: DrapedPly = ctx.products["drape"]
    pattern = flat_pattern(ply.result)
    write_flat_pattern_csv(pattern, ctx.case_dir / "flat_pattern.csv")
    write_flat_pattern_dxf(pattern, ctx.case_dir / "flat_pattern.dxf")
    write_flat_pattern_svg(pattern, ctx.case_dir / "flat_pattern.svg", title=ctx.fabric.name)
    ctx.summary["flat_pattern_area_mm2"] = pattern.area_mm2
    return {"flat_pattern": ["flat_pattern.csv", "flat_pattern.dxf", "flat_pattern.svg"]}


STEPS = [
    Step(
        "surface",
        ("surface",),
        (),
        "1",
        run_surface,
        "Build the scene's tool surface.",
        scene_sections=("tool",),
    ),
    Step(
        "drape",
        ("drape",),
        ("surface", "shear_law"),
        "1",
        run_drape,
        "Pin-jointed net on the tool, its shear field and strain energy.",
        scene_sections=("tool", "ply", "start"),
        extra_requires=_needs_optimum,
    ),
]

EXPORTERS = [
    Step(
        "cells_csv",
        ("cells_csv",),
        ("drape",),
        "1",
        write_cells_csv,
        "cells.csv: one row per cell (shear, energy, status)",
        writes_files=True,
    ),
    Step("vtu", ("vtu",), ("drape",), "1", write_vtu, "drape.vtu for ParaView", writes_files=True),
    Step(
        "fibre_pattern_png",
        ("fibre_pattern_png",),
        ("drape",),
        "1",
        write_fibre_pattern_png,
        "fibre_pattern.png: top view with tows, 3D view by shear",
        writes_files=True,
    ),
    Step(
        "flat_pattern",
        ("flat_pattern",),
        ("drape",),
        "1",
        write_flat_pattern,
        "flat_pattern.csv/.dxf/.svg: the ply outline in the flat",
        writes_files=True,
    ),
]
