"""Steps that need nothing but a fabric: its unit cell and its shear law.

Each step is a module-level function of the case context (picklable for worker processes) and
returns the products it provides; exporters write files atomically into the case folder.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.status import CaseFailure
from preform.library import build_shear_law
from preform.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene
    from preform.yamlsource import Document, SourceError


def _scalars(prefix: str, values: Mapping[str, Any]) -> dict[str, Any]:
    """Flatten a nested mapping of derived values to scalar summary entries."""
    out: dict[str, Any] = {}
    for key, value in values.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(_scalars(f"{name}.", value))
        elif isinstance(value, bool | int | float | str) or value is None:
            out[name] = value
    return out


def run_unit_cell(ctx: CaseContext) -> dict[str, Any]:
    cell = ctx.fabric.unit_cell()
    if cell is None:
        raise ValueError(f"architecture {ctx.fabric.architecture!r} provides no unit-cell model")
    ctx.summary.update(_scalars("", ctx.fabric.derived()))
    return {"unit_cell": cell}


def run_shear_law(ctx: CaseContext) -> dict[str, Any]:
    law = build_shear_law(ctx.fabric, ctx.registry)
    if law.locking_angle is not None:
        ctx.summary["locking_angle_deg"] = float(np.degrees(law.locking_angle))
    if law.failure_angle is not None:
        ctx.summary["failure_angle_deg"] = float(np.degrees(law.failure_angle))
    return {"shear_law": law}


def _angles_deg(ctx: CaseContext) -> Any:
    spec = ctx.scene.shear.angles_deg if ctx.scene.shear is not None else None
    lo, hi, step = (spec.min, spec.max, spec.step or 1.0) if spec else (0.0, 60.0, 1.0)
    return np.arange(lo, hi + 0.5 * step, step)


def run_shear_curve(ctx: CaseContext) -> dict[str, Any]:
    from preform.shear.commands import shear_curves

    law_block = ctx.fabric.shear_law or ctx.fabric.default_shear_law()
    law_name = getattr(law_block, "law", None) or (law_block or {}).get("law", "")
    with np.errstate(all="ignore"):
        curves = shear_curves(
            ctx.products["shear_law"], _angles_deg(ctx), ctx.fabric.name, str(law_name)
        )
    # A NaN would reach shear_curve.json as null and the figure as a gap: fail instead, with
    # the first angle (nearest zero) where the law is not finite.
    for sense in ("positive", "negative"):
        for row in curves[sense]:
            bad = [k for k, v in row.items() if k != "angle_deg" and not np.isfinite(v)]
            if bad:
                raise CaseFailure(
                    f"the shear law returned a non-finite {bad[0].split('_')[0]} "
                    f"({row[bad[0]]!r}) at γ = {row['angle_deg']:.4g}°"
                )
    return {"shear_curve": curves}


def write_shear_curve_json(ctx: CaseContext) -> dict[str, Any]:
    from preform.pipeline.runner import write_json

    write_json(ctx.case_dir / "shear_curve.json", ctx.products["shear_curve"])
    return {"shear_curve_json": "shear_curve.json"}


def write_shear_curve_png(ctx: CaseContext) -> dict[str, Any]:
    from preform.shear.commands import plot_shear_curves

    plot_shear_curves(ctx.products["shear_curve"], ctx.case_dir / "shear_curve.png")
    return {"shear_curve_png": "shear_curve.png"}


def write_unit_cell_png(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.fig_unit_cell import unit_cell_figure

    unit_cell_figure(
        ctx.products["unit_cell"],
        ctx.case_dir / "unit_cell.png",
        title=ctx.fabric.name,
        repeats=(2, 2),
    )
    return {"unit_cell_png": "unit_cell.png"}


def write_unit_cell_vtu(ctx: CaseContext) -> dict[str, Any]:
    from preform.export.vtu import write_unit_cell_vtu

    write_unit_cell_vtu(ctx.products["unit_cell"], ctx.case_dir / "unit_cell.vtu")
    return {"unit_cell_vtu": "unit_cell.vtu"}


#: Most angles of a tabulated shear curve (``shear.angles_deg``): far more than any plot shows,
#: and a step of 1e-9° over 60° would otherwise ask for 6·10¹⁰ of them.
MAX_CURVE_ANGLES = 100_000


def scene_problems(scene: Scene, doc: Document, registry: Any) -> list[SourceError]:
    """An empty or too finely stepped ``shear.angles_deg``, before a curve is tabulated (the
    shear_curve step's ``check``)."""
    if scene.shear is None:
        return []
    spec = scene.shear.angles_deg
    step = spec.step or 1.0
    if spec.min > spec.max:
        message = f"min ({spec.min:g}°) must not exceed max ({spec.max:g}°)"
        return [doc.error(("shear", "angles_deg"), message)]
    angles = (spec.max - spec.min) / step + 1
    if angles <= MAX_CURVE_ANGLES:
        return []
    return [
        doc.error(
            ("shear", "angles_deg", "step"),
            f"a step of {step:g}° over [{spec.min:g}°, {spec.max:g}°] gives {angles:.3g} angles, "
            f"more than {MAX_CURVE_ANGLES:,}; use a step of at least "
            f"{(spec.max - spec.min) / (MAX_CURVE_ANGLES - 1):.3g}°",
        )
    ]


STEPS = [
    Step(
        "unit_cell",
        ("unit_cell",),
        (),
        "1",
        run_unit_cell,
        "Build the fabric's repeating cell; records its derived properties.",
    ),
    Step(
        "shear_law",
        ("shear_law",),
        (),
        "1",
        run_shear_law,
        "Build the fabric's shear law from its shear_law block or its default.",
    ),
    Step(
        "shear_curve",
        ("shear_curve",),
        ("shear_law",),
        "1",
        run_shear_curve,
        "Torque, force and energy against shear angle, both senses.",
        sections={"shear": None},
        check=scene_problems,
    ),
]

EXPORTERS = [
    Step.exporter("shear_curve_json", ("shear_curve",), write_shear_curve_json, "shear_curve.json"),
    Step.exporter(
        "shear_curve_png",
        ("shear_curve",),
        write_shear_curve_png,
        "shear_curve.png (paper Fig. 8/9 style)",
    ),
    Step.exporter(
        "unit_cell_png",
        ("unit_cell",),
        write_unit_cell_png,
        "unit_cell.png: 3D view of the repeating cell",
    ),
    Step.exporter(
        "unit_cell_vtu",
        ("unit_cell",),
        write_unit_cell_vtu,
        "unit_cell.vtu: tow paths for ParaView",
    ),
]
