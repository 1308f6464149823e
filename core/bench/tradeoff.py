"""The speed/accuracy trade of a scene's fidelity knobs, measured (``preform bench tradeoff``).

One fabric, one scene with a ``search`` section (default: the bundled ``hemisphere-min-energy``
and ``E-BX-318``, whose asymmetric law moves the optimum off 90°), run through the pipeline's
own steps (surface → shear law → energy_vs_angle → optimum → drape), so what is timed is what
``preform pipeline run`` runs. The settings:

- the three presets (``draft``, ``standard``, ``fine``), node spacing from the preset;
- one knob at a time around ``standard``: node spacing (a fraction of the tool's size), solver
  tolerance, energy-table step (0 = the law itself), scan step, refinement tolerance, drape
  budget, and curved generators (``optimise_curved_generators`` at the straight optimum,
  budget-limited); and for a tool read from a STEP or IGES file, the tessellation tolerance
  (``tool.tessellation_tolerance_mm``, the facets' largest distance from the CAD surface);
- the **reference**: every knob at its finest (:data:`REFERENCE`), and the same one step less
  fine (:data:`REFERENCE_CHECK`), whose distance from the reference bounds the reference's own
  error, i.e. the smallest error this study can resolve.

Every knob is set through the scene (hand-set ``ply.node_spacing_mm``, ``numerics``,
``search``) and resolved by :func:`preform.base.fidelity.resolve`; the scene's own hand-set
knobs are cleared first, so the presets choose what the scene does not set.

Per setting: wall time [s] (best of ``repeat`` when a run is short; the machine may be shared),
peak traced memory [bytes] of one drape-and-judge at the optimum (the search keeps no nets, so
this is the case's peak; traced on a separate run because tracing slows numpy), and the errors
against the reference of the optimum's comparable energy (relative), of the optimum generator
angle [deg] and of the largest |shear| at the optimum [deg]. On a bare hemisphere also the
error of the largest |shear| at the reference's optimum angle against the continuum Chebyshev
net (:func:`preform.drape.engine.chebyshev.chebyshev_angle`), evaluated at the same cell centres: the
net's discretisation error alone, free of the search's.

Curved generators change the model (they lower the energy the straight reference measures),
so their rows are reported (signed energy difference = the saving) but kept off the Pareto
front.
"""

from __future__ import annotations

import csv
import math
import os
import tempfile
import time
import tracemalloc
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import click
import numpy as np

from preform.base import fidelity
from preform.command_line import InputError, echo_json, json_option, library_options
from preform.pipeline.scene import (
    NumericsSection,
    Scene,
    SceneError,
    load_scene,
    resolve_scene_path,
)

#: Bundled scene and fabric of the default study.
DEFAULT_SCENE = "hemisphere-min-energy"
DEFAULT_MATERIAL = "E-BX-318"

#: Ladders of the knobs varied one at a time around ``standard`` (the standard's own value is
#: the standard row). Node spacing as a fraction of the tool's size (a hemisphere's radius).
SPACING_FRACTIONS: tuple[float, ...] = (1 / 10, 1 / 20, 1 / 40, 1 / 80, 1 / 160)
SOLVER_TOLERANCES: tuple[float, ...] = (1e-4, 1e-6, 1e-9, 1e-12)
#: Sub-steps per node spacing when marching geodesic generators (tools without closed forms).
GENERATOR_SUBSTEPS: tuple[int, ...] = (4, 8, 32)
TABLE_STEPS_DEG: tuple[float, ...] = (2.0, 1.0, 0.5, 0.25, 0.0)
SCAN_STEPS_DEG: tuple[float, ...] = (15.0, 10.0, 5.0, 2.5)
REFINE_TOLERANCES_DEG: tuple[float, ...] = (4.0, 2.0, 1.0, 0.25, 0.0625)
DRAPE_BUDGETS: tuple[int, ...] = (30, 60, 120)
#: Tessellation tolerances [mm] of a STEP or IGES tool (``tool.tessellation_tolerance_mm``).
TESSELLATION_TOLERANCES_MM: tuple[float, ...] = (0.5, 0.2, 0.1, 0.02)
#: Drape budgets of the curved-generator optimisation.
CURVED_BUDGETS: tuple[int, ...] = (40, 120)
#: Curved-generator options when the scene gives none: mirror-tied families suit a dome
#: started at its pole (``preform.optimise.curved``), and halve the unknowns.
CURVED_DEFAULT: dict[str, Any] = {"terms": 2, "mirror_families": True}

#: The converged reference: every knob at its finest (spacing as a fraction of tool size).
REFERENCE: dict[str, Any] = {
    "spacing_fraction": 1 / 320,
    "solver_tolerance": 1e-12,
    "generator_substeps": 64,
    "energy_table_step_deg": 0.0,
    "scan_step_deg": 2.5,
    "tolerance_deg": 0.0625,
    "max_drapes": 200,
    "tessellation_tolerance_mm": 0.005,
}
#: The reference one step less fine in every knob: its distance from the reference bounds the
#: reference's own error (assuming the errors shrink as the knobs are refined).
REFERENCE_CHECK: dict[str, Any] = {
    "spacing_fraction": 1 / 160,
    "solver_tolerance": 1e-9,
    "generator_substeps": 32,
    "energy_table_step_deg": 0.25,
    "scan_step_deg": 5.0,
    "tolerance_deg": 0.125,
    "max_drapes": 200,
    "tessellation_tolerance_mm": 0.01,
}
#: ``--quick``: a coarse stand-in reference, affordable in a test.
QUICK_REFERENCE: dict[str, Any] = {
    "spacing_fraction": 1 / 40,
    "solver_tolerance": 1e-12,
    "generator_substeps": 16,
    "energy_table_step_deg": 0.0,
    "scan_step_deg": 5.0,
    "tolerance_deg": 0.5,
    "max_drapes": 60,
    "tessellation_tolerance_mm": 0.02,
}

#: Runs shorter than this [s] are repeated (best of ``repeat``); longer ones are timed once.
_REPEAT_BELOW_S = 5.0

CSV_COLUMNS = (
    "label",
    "knob",
    "value",
    "fidelity",
    "node_spacing_mm",
    "solver_tolerance",
    "energy_table_step_deg",
    "scan_step_deg",
    "tolerance_deg",
    "max_drapes",
    "tessellation_tolerance_mm",
    "curved_max_drapes",
    "drapes",
    "wall_s",
    "time_ratio",
    "peak_mb",
    "memory_ratio",
    "optimum_angle_deg",
    "energy_J",
    "max_abs_shear_deg",
    "energy_rel_diff",
    "energy_rel_error",
    "angle_error_deg",
    "max_shear_error_deg",
    "chebyshev_max_shear_error_deg",
    "chebyshev_field_error_deg",
    "noise_limited",
    "on_front",
    "pareto_angle",
    "pareto_energy",
)


@dataclass(frozen=True)
class Setting:
    """One point of the study: a scene variant and what was varied in it."""

    label: str
    #: "preset", a knob name, "curved_generators", "reference" or "reference_check".
    knob: str
    value: str
    scene: Scene


@dataclass
class TradeoffRow:
    """Measurements of one setting (units in the names; errors against the reference)."""

    label: str
    knob: str
    value: str
    fidelity: str
    node_spacing_mm: float
    solver_tolerance: float
    energy_table_step_deg: float
    scan_step_deg: float
    tolerance_deg: float
    max_drapes: int
    curved_max_drapes: int | None
    drapes: int
    wall_s: float
    peak_mb: float
    optimum_angle_deg: float
    #: The optimum's energy of the part [J] (plus priced uncovered area if the scene asks).
    energy_J: float
    max_abs_shear_deg: float
    noise_limited: bool
    #: A STEP or IGES tool's tessellation tolerance [mm] (NaN for other tools).
    tessellation_tolerance_mm: float = math.nan
    chebyshev_max_shear_error_deg: float = math.nan
    chebyshev_field_error_deg: float = math.nan
    time_ratio: float = math.nan
    memory_ratio: float = math.nan
    energy_rel_diff: float = math.nan
    energy_rel_error: float = math.nan
    angle_error_deg: float = math.nan
    max_shear_error_deg: float = math.nan
    #: Straight-generator rows compete on the front; curved rows change the model.
    on_front: bool = True
    pareto_angle: bool = False
    pareto_energy: bool = False

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class TradeoffResult:
    """The rows, which one is the reference, and how converged the reference is."""

    scene: str
    material: str
    rows: list[TradeoffRow]
    reference_label: str
    baseline_label: str
    #: Errors of the one-step-less-fine reference against the reference (None with --quick).
    reference_check: dict[str, float] | None = field(default=None)

    def row(self, label: str) -> TradeoffRow:
        return next(r for r in self.rows if r.label == label)


# -- scenes ----------------------------------------------------------------------------------


def _cleared(scene: Scene) -> Scene:
    """``scene`` without hand-set knobs, so its preset chooses all of them."""
    if scene.search is None or scene.ply is None or scene.start is None:
        raise ValueError(
            f"scene {scene.name!r}: the trade-off needs a minimum-energy scene with 'ply', "
            "'start' and 'search' sections"
        )
    span = scene.search.generator_angle_deg
    search = scene.search.model_copy(
        update={
            "generator_angle_deg": None if span is None else span.model_copy(update={"step": None}),
            "scan_step_deg": None,
            "tolerance_deg": None,
            "max_drapes": None,
            "curved_generators": None,
        }
    )
    ply = scene.ply.model_copy(update={"node_spacing_mm": None})
    return scene.model_copy(
        update={"ply": ply, "search": search, "numerics": None, "fidelity": None}
    )


def _variant(
    base: Scene,
    *,
    preset: str = "standard",
    spacing_mm: float | None = None,
    numerics: dict[str, Any] | None = None,
    search: dict[str, Any] | None = None,
    tool: dict[str, Any] | None = None,
) -> Scene:
    """``base`` (cleared) at ``preset`` with the given knobs hand-set."""
    assert base.ply is not None and base.search is not None
    update: dict[str, Any] = {"fidelity": preset}
    if tool:
        update["tool"] = base.tool.model_copy(update=tool)
    if spacing_mm is not None:
        update["ply"] = base.ply.model_copy(update={"node_spacing_mm": spacing_mm})
    if numerics:
        update["numerics"] = NumericsSection(**numerics)
    if search:
        update["search"] = base.search.model_copy(update=search)
    return base.model_copy(update=update)


def _pinned(base: Scene, knobs: dict[str, Any], tool_size_m: float) -> Scene:
    """Every knob hand-set (the reference and its check)."""
    return _variant(
        base,
        preset="fine",
        spacing_mm=knobs["spacing_fraction"] * tool_size_m * 1e3,
        numerics={
            "solver_tolerance": knobs["solver_tolerance"],
            "generator_substeps": knobs["generator_substeps"],
            "energy_table_step_deg": knobs["energy_table_step_deg"],
        },
        search={
            "scan_step_deg": knobs["scan_step_deg"],
            "tolerance_deg": knobs["tolerance_deg"],
            "max_drapes": knobs["max_drapes"],
        },
        tool=(
            {"tessellation_tolerance_mm": knobs["tessellation_tolerance_mm"]}
            if _is_cad(base)
            else None
        ),
    )


def _tessellation_tolerance_mm(scene: Scene) -> float:
    """The tessellation tolerance in force [mm] of a tool read from a STEP or IGES file (the
    tool block says, ``tessellation_tolerance_in_force_mm``); NaN for any other tool."""
    in_force = getattr(scene.tool, "tessellation_tolerance_in_force_mm", None)
    value = in_force() if callable(in_force) else None
    return math.nan if value is None else float(value)


def _is_cad(scene: Scene) -> bool:
    """Whether the scene's tool is tessellated from CAD (it has a tessellation tolerance)."""
    return math.isfinite(_tessellation_tolerance_mm(scene))


def _fraction_label(fraction: float) -> str:
    return f"L/{round(1 / fraction)}"


def tradeoff_settings(scene: Scene, tool_size_m: float, *, quick: bool = False) -> list[Setting]:
    """The settings of the study (module docstring); the reference first.

    ``tool_size_m`` [m] is the tool's typical length (``Surface.size``) that spacing fractions
    refer to. ``quick`` keeps a coarse reference, the ``draft`` and ``standard`` presets and
    two coarser spacings: enough to exercise everything in seconds.
    """
    base = _cleared(scene)
    standard = fidelity.resolve(_variant(base), tool_size_m)
    settings: list[Setting] = []
    reference = QUICK_REFERENCE if quick else REFERENCE
    settings.append(
        Setting("reference", "reference", "finest", _pinned(base, reference, tool_size_m))
    )
    if not quick:
        settings.append(
            Setting(
                "reference-1",
                "reference_check",
                "one step less fine",
                _pinned(base, REFERENCE_CHECK, tool_size_m),
            )
        )
    presets = ("draft", "standard") if quick else ("draft", "standard", "fine")
    for preset in presets:
        settings.append(Setting(preset, "preset", preset, _variant(base, preset=preset)))
    std_fraction = (standard.node_spacing_mm or 0.0) / (tool_size_m * 1e3)
    fractions = SPACING_FRACTIONS[:2] if quick else SPACING_FRACTIONS
    for fraction in fractions:
        if math.isclose(fraction, std_fraction, rel_tol=1e-9):
            continue
        spacing = fraction * tool_size_m * 1e3
        settings.append(
            Setting(
                f"d={spacing:.4g}mm",
                "node_spacing_mm",
                _fraction_label(fraction),
                _variant(base, spacing_mm=spacing),
            )
        )
    if _is_cad(base):
        own = _tessellation_tolerance_mm(base)
        for value in TESSELLATION_TOLERANCES_MM[:1] if quick else TESSELLATION_TOLERANCES_MM:
            if math.isclose(value, own):
                continue
            settings.append(
                Setting(
                    f"tess={value:g}mm",
                    "tessellation_tolerance_mm",
                    f"{value:g}",
                    _variant(base, tool={"tessellation_tolerance_mm": value}),
                )
            )
    if quick:
        return settings
    numerics_ladders: tuple[tuple[str, Sequence[float], str], ...] = (
        ("solver_tolerance", SOLVER_TOLERANCES, "tol={:g}"),
        ("generator_substeps", GENERATOR_SUBSTEPS, "substeps={:g}"),
        ("energy_table_step_deg", TABLE_STEPS_DEG, "table={:g}deg"),
    )
    for knob, ladder, fmt in numerics_ladders:
        for value in ladder:
            if value == getattr(standard, knob):
                continue
            label = "table=exact" if knob == "energy_table_step_deg" and value == 0 else None
            settings.append(
                Setting(
                    label or fmt.format(value),
                    knob,
                    f"{value:g}",
                    _variant(base, numerics={knob: value}),
                )
            )
    search_ladders: tuple[tuple[str, Sequence[float], str], ...] = (
        ("scan_step_deg", SCAN_STEPS_DEG, "scan={:g}deg"),
        ("tolerance_deg", REFINE_TOLERANCES_DEG, "refine={:g}deg"),
        ("max_drapes", DRAPE_BUDGETS, "budget={:g}"),
    )
    for knob, ladder, fmt in search_ladders:
        for value in ladder:
            if value == getattr(standard, knob):
                continue
            settings.append(
                Setting(fmt.format(value), knob, f"{value:g}", _variant(base, search={knob: value}))
            )
    options = dict(scene.search.curved_generators or CURVED_DEFAULT) if scene.search else {}
    for budget in CURVED_BUDGETS:
        settings.append(
            Setting(
                f"curved,{budget}",
                "curved_generators",
                f"max_drapes={budget}",
                _variant(base, search={"curved_generators": {**options, "max_drapes": budget}}),
            )
        )
    return settings


# -- running ---------------------------------------------------------------------------------


def _run_case(setting: Setting, fabric: Any, registry: Any, case_dir: Path) -> Any:
    """The pipeline steps of a minimum-energy drape, in order; returns the case context."""
    from preform.drape.steps import run_drape, run_surface
    from preform.optimise.search_steps import run_energy_vs_angle, run_optimum
    from preform.pipeline.core_steps import run_shear_law
    from preform.step import CaseContext

    ctx = CaseContext(fabric=fabric, scene=setting.scene, registry=registry, case_dir=case_dir)
    for step in (run_surface, run_shear_law, run_energy_vs_angle, run_optimum, run_drape):
        ctx.products.update(step(ctx))
    return ctx


def _peak_bytes(run: Callable[[], Any]) -> int:
    """Peak traced memory [bytes] of ``run()`` above what was allocated before it."""
    started = not tracemalloc.is_tracing()
    if started:
        tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        before, _ = tracemalloc.get_traced_memory()
        run()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        if started:
            tracemalloc.stop()
    return max(peak - before, 0)


def _is_bare_hemisphere(scene: Scene) -> bool:
    tool = scene.tool
    return (
        getattr(tool, "surface", None) == "hemisphere"
        and getattr(tool, "flange_half_width_mm", None) is None
    )


def chebyshev_errors(scene: Scene, surface: Any, alpha_rad: float) -> tuple[float, float]:
    """Errors [deg] of a drape of ``scene`` at generator angle ``alpha_rad`` [rad] against the
    continuum Chebyshev net on a sphere of ``surface.radius`` [m]: of the largest |shear| and
    of the shear field (largest pointwise difference), both over the counted cells, the
    continuum evaluated at the cell centres (arc length 2R·asin(d/2R) per chord d).

    NaN for anything but a bare hemisphere with geodesic generators (the oracle's premises).
    """
    from preform.drape.engine.chebyshev import chebyshev_angle
    from preform.drape.engine.net import drape
    from preform.drape.steps import drape_settings

    settings = drape_settings(scene, surface)
    if not _is_bare_hemisphere(scene) or settings.generators != "geodesic":
        return math.nan, math.nan
    result = drape(surface, settings, generator_angle_rad=alpha_rad)
    counted = result.valid & result.in_part
    if not counted.any():
        return math.nan, math.nan
    radius = float(surface.radius)
    step = 2.0 * radius * math.asin(result.node_spacing / (2.0 * radius))
    (i0, j0), (ni, nj) = result.start_index, result.shape
    u = (np.arange(ni - 1) - i0 + 0.5) * step
    v = (np.arange(nj - 1) - j0 + 0.5) * step
    continuum = chebyshev_angle(u[:, None], v[None, :], radius, alpha_rad) - 0.5 * math.pi
    net = result.shear[counted]
    cont = continuum[counted]
    max_error = abs(float(np.abs(net).max()) - float(np.abs(cont).max()))
    field_error = float(np.abs(net - cont).max())
    return math.degrees(max_error), math.degrees(field_error)


def measure(
    setting: Setting, fabric: Any, registry: Any, *, repeat: int = 1
) -> tuple[TradeoffRow, Any]:
    """Run one setting (timed, best of ``repeat`` for short runs) and trace its memory.

    Returns the row (errors not yet filled) and the case context of the last run.
    """
    with tempfile.TemporaryDirectory(prefix="preform-tradeoff-") as folder:
        best = math.inf
        ctx: Any = None
        for attempt in range(max(repeat, 1)):
            clock = time.perf_counter()
            ctx = _run_case(setting, fabric, registry, Path(folder))
            best = min(best, time.perf_counter() - clock)
            if attempt == 0 and best > _REPEAT_BELOW_S:
                break
        from preform.drape.steps import run_drape

        peak = _peak_bytes(lambda: run_drape(ctx))
    surface = ctx.products["surface"]
    knobs = fidelity.resolve(setting.scene, float(surface.size))
    summary = ctx.summary
    optimum = ctx.products["optimum"]
    curved = setting.scene.search.curved_generators if setting.scene.search else None
    drapes = int(summary["search_drapes"]) + int(summary.get("curved_drapes", 0)) + 1
    row = TradeoffRow(
        label=setting.label,
        knob=setting.knob,
        value=setting.value,
        fidelity=knobs.fidelity,
        node_spacing_mm=float(knobs.node_spacing_mm or math.nan),
        solver_tolerance=knobs.solver_tolerance,
        energy_table_step_deg=knobs.energy_table_step_deg,
        scan_step_deg=knobs.scan_step_deg,
        tolerance_deg=knobs.tolerance_deg,
        max_drapes=knobs.max_drapes,
        curved_max_drapes=None if not curved else int(curved.get("max_drapes", 120)),
        drapes=drapes,
        wall_s=best,
        peak_mb=peak / 1e6,
        optimum_angle_deg=math.degrees(float(optimum["generator_angle_rad"])),
        energy_J=float(optimum["energy_J"]),
        max_abs_shear_deg=float(summary["max_abs_shear_deg"]),
        noise_limited=bool(summary.get("optimum_noise_limited", False)),
        tessellation_tolerance_mm=_tessellation_tolerance_mm(setting.scene),
        on_front=not curved,
    )
    return row, ctx


def pareto_front(times: Sequence[float], errors: Sequence[float]) -> list[bool]:
    """Which points no other point beats: another with time ≤ and error ≤, one of them <."""
    t = np.asarray(times, dtype=float)
    e = np.asarray(errors, dtype=float)
    out = []
    for k in range(len(t)):
        if not (math.isfinite(t[k]) and math.isfinite(e[k])):
            out.append(False)
            continue
        better = (t <= t[k]) & (e <= e[k]) & ((t < t[k]) | (e < e[k]))
        out.append(not bool(better.any()))
    return out


def _fill_errors(rows: list[TradeoffRow], reference: TradeoffRow, baseline: TradeoffRow) -> None:
    for row in rows:
        row.time_ratio = row.wall_s / baseline.wall_s
        row.memory_ratio = row.peak_mb / baseline.peak_mb if baseline.peak_mb > 0 else math.nan
        row.energy_rel_diff = (row.energy_J - reference.energy_J) / abs(reference.energy_J)
        row.energy_rel_error = abs(row.energy_rel_diff)
        row.angle_error_deg = abs(row.optimum_angle_deg - reference.optimum_angle_deg)
        row.max_shear_error_deg = abs(row.max_abs_shear_deg - reference.max_abs_shear_deg)
    contenders = [r for r in rows if r.on_front]
    times = [r.wall_s for r in contenders]
    for attr, flag in (("angle_error_deg", "pareto_angle"), ("energy_rel_error", "pareto_energy")):
        marks = pareto_front(times, [getattr(r, attr) for r in contenders])
        for row, mark in zip(contenders, marks, strict=True):
            setattr(row, flag, mark)


def run_tradeoff(
    scene: str | os.PathLike[str] = DEFAULT_SCENE,
    material: str = DEFAULT_MATERIAL,
    *,
    quick: bool = False,
    repeat: int = 1,
    progress: Callable[[TradeoffRow], None] | None = None,
    libraries: Sequence[str | os.PathLike[str]] = (),
    bundled: bool = True,
) -> TradeoffResult:
    """Measure the trade for ``material`` on ``scene`` (a file or a bundled scene's name).

    ``repeat``: runs shorter than 5 s are timed this many times, keeping the best.
    ``progress`` is called with each finished row (errors not yet filled). ``libraries`` add
    to the bundled library (``bundled=False`` leaves it out), as ``--library`` does.
    """
    from preform.drape.steps import build_surface
    from preform.library import load_library
    from preform.plugin_manager import default_host

    registry = default_host().registry
    path = resolve_scene_path(str(scene))
    loaded, _ = load_scene(path, registry)
    fabric = load_library(libraries, bundled=bundled, registry=registry).fabric(material)
    surface = build_surface(loaded, registry)
    settings = tradeoff_settings(loaded, float(surface.size), quick=quick)
    rows: list[TradeoffRow] = []
    reference_alpha: float | None = None
    for setting in settings:
        row, ctx = measure(setting, fabric, registry, repeat=repeat)
        if reference_alpha is None:  # the reference runs first
            reference_alpha = math.radians(row.optimum_angle_deg)
        row.chebyshev_max_shear_error_deg, row.chebyshev_field_error_deg = chebyshev_errors(
            setting.scene, ctx.products["surface"], reference_alpha
        )
        rows.append(row)
        if progress is not None:
            progress(row)
    reference = rows[0]
    baseline = next((r for r in rows if r.label == "standard"), reference)
    _fill_errors(rows, reference, baseline)
    check = next((r for r in rows if r.knob == "reference_check"), None)
    summary = None
    if check is not None:
        summary = {
            "energy_rel_error": check.energy_rel_error,
            "angle_error_deg": check.angle_error_deg,
            "max_shear_error_deg": check.max_shear_error_deg,
        }
    return TradeoffResult(
        loaded.name, material, rows, reference.label, baseline.label, reference_check=summary
    )


# -- output ----------------------------------------------------------------------------------


def write_csv(result: TradeoffResult, path: str | os.PathLike[str]) -> None:
    """One row per setting, columns :data:`CSV_COLUMNS` (units in the names; MB = 1e6 bytes)."""
    from preform.base.atomic import atomic_path

    with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(CSV_COLUMNS), extrasaction="ignore")
        writer.writeheader()
        for row in result.rows:
            values = row.as_dict()
            writer.writerow({k: "" if values[k] is None else values[k] for k in CSV_COLUMNS})


#: Relative energy difference below which --quick (no convergence check of its reference)
#: calls two settings equal: the rim cells' staircase alone moves E by more (fidelity notes).
QUICK_ENERGY_RESOLUTION = 1e-3


def error_floors(result: TradeoffResult) -> dict[str, float]:
    """The smallest error each panel can resolve: the reference's own resolution (how far one
    step less fine lands from it), or with ``--quick`` its refinement tolerance for the angle
    and ``QUICK_ENERGY_RESOLUTION`` for the energy. Smaller errors say nothing about a setting
    (a standard run against a quick reference at the same spacing differs by 1e-10)."""
    check = result.reference_check or {}
    ref = result.row(result.reference_label)
    angle = check.get("angle_error_deg") or ref.tolerance_deg
    energy = check.get("energy_rel_error") or QUICK_ENERGY_RESOLUTION
    return {"angle_error_deg": float(angle), "energy_rel_error": float(energy)}


#: Why ``--quick`` draws no figure: its settings and coarse reference exercise the study, they
#: do not measure the trade (most errors fall below the reference's own resolution, and the
#: few points left make no front).
NO_QUICK_FIGURE = (
    "no tradeoff.png with --quick: a coarse reference and a few settings cannot show the "
    "trade (most errors lie below the reference's resolution); the table is for checking that "
    "the study runs. Run without --quick for the figure"
)


def plot_tradeoff(result: TradeoffResult, path: str | os.PathLike[str]) -> None:
    """Error against wall time (log-log): optimum-angle error and relative energy error, one
    panel each, the Pareto front joined; errors below the reference's resolution (zero for the
    reference itself) drawn on a floor that says so (:func:`error_floors`)."""
    from preform.base.figures import new_figure, save_figure

    fig = new_figure((1400, 650))
    floors = error_floors(result)
    panels = (
        ("angle_error_deg", "pareto_angle", "|optimum angle error| [deg]", "{:.2g}°"),
        ("energy_rel_error", "pareto_energy", "|relative energy error| [-]", "{:.1e}"),
    )
    for index, (attr, flag, ylabel, fmt) in enumerate(panels):
        ax = fig.add_subplot(1, 2, index + 1)
        values = np.array([getattr(r, attr) for r in result.rows], dtype=float)
        floor = floors[attr]
        shown = np.where(np.isfinite(values) & (values > floor), values, floor)
        times = np.array([r.wall_s for r in result.rows])
        labelled: list[Any] = []
        for k, row in enumerate(result.rows):
            colour = "#555555"
            marker = "o"
            if row.knob == "preset":
                colour, marker = "#b2182b", "s"
            elif row.knob in ("reference", "reference_check"):
                colour, marker = "#1a9850", "D"
            elif not row.on_front:
                colour, marker = "#2166ac", "^"
            ax.scatter(times[k], shown[k], c=colour, marker=marker, s=40, zorder=3)
            # Rows that change nothing pile up on the standard's point: name the first only.
            here = np.log10([times[k], shown[k]])
            if any(np.all(np.abs(here - p) < 0.04) for p in labelled):
                continue
            labelled.append(here)
            ax.annotate(
                row.label,
                (times[k], shown[k]),
                fontsize=8,
                xytext=(3, 3),
                textcoords="offset points",
            )
        front = [k for k, r in enumerate(result.rows) if getattr(r, flag)]
        front.sort(key=lambda k: times[k])
        ax.step(
            times[front],
            shown[front],
            where="post",
            color="#f4a582",
            lw=2,
            zorder=2,
            label="Pareto front (straight generators)",
        )
        ax.axhline(
            floor,
            color="#999999",
            lw=0.8,
            ls=":",
            label=f"reference's resolution ({fmt.format(floor)}): smaller errors drawn here",
        )
        top = float(np.nanmax(shown)) if np.isfinite(shown).any() else floor
        ax.set_ylim(floor / 2, max(top * 2, floor * 10))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time per case [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    fig.suptitle(
        f"{result.scene}, {result.material}: error against the reference vs wall time\n"
        "squares: presets; diamonds: reference; triangles: curved generators; dots: one knob"
    )
    fig.tight_layout()
    save_figure(fig, path)


def format_table(result: TradeoffResult) -> str:
    """The table as fixed-width text (the README's)."""
    head = (
        f"{'setting':<16}{'d mm':>7}{'drapes':>7}{'wall s':>8}{'x std':>7}{'peak MB':>8}"
        f"{'alpha':>8}{'E J':>8}{'|g|max':>7}{'dE rel':>9}{'d alpha':>8}{'d|g|':>7}"
        f"{'cheb':>7}{'front':>6}"
    )
    lines = [head]
    for r in result.rows:
        front = ("a" if r.pareto_angle else "") + ("E" if r.pareto_energy else "")
        lines.append(
            f"{r.label:<16}{r.node_spacing_mm:>7.3g}{r.drapes:>7d}{r.wall_s:>8.2f}"
            f"{r.time_ratio:>7.2f}{r.peak_mb:>8.1f}{r.optimum_angle_deg:>8.2f}"
            f"{r.energy_J:>8.4f}{r.max_abs_shear_deg:>7.2f}{r.energy_rel_diff:>9.1e}"
            f"{r.angle_error_deg:>8.2f}{r.max_shear_error_deg:>7.2f}"
            f"{r.chebyshev_max_shear_error_deg:>7.2f}{front or '-':>6}"
        )
    return "\n".join(lines)


def describe_reference(result: TradeoffResult) -> str:
    """Which settings the reference used, and how far one step less fine lands from it."""
    ref = result.row(result.reference_label)
    text = (
        f"reference: d = {ref.node_spacing_mm:.4g} mm, solver tolerance {ref.solver_tolerance:g}"
        f", energy table {'exact law' if ref.energy_table_step_deg == 0 else ref.energy_table_step_deg}"
        f", scan {ref.scan_step_deg:g} deg, refine {ref.tolerance_deg:g} deg, budget "
        f"{ref.max_drapes}: optimum {ref.optimum_angle_deg:.2f} deg, E = {ref.energy_J:.5f} J, "
        f"max |shear| {ref.max_abs_shear_deg:.2f} deg"
    )
    check = result.reference_check
    if check is not None:
        text += (
            f"\nconvergence: one step less fine differs by {check['energy_rel_error']:.1e} in "
            f"energy, {check['angle_error_deg']:.2f} deg in angle, "
            f"{check['max_shear_error_deg']:.2f} deg in max |shear|"
        )
    return text


# -- command line ----------------------------------------------------------------------------

bench = click.Group(
    "bench", help="Measure preform: speed, and the speed/accuracy trade of the fidelity knobs."
)


@bench.command("tradeoff")
@click.option(
    "--scene",
    "scene_spec",
    default=DEFAULT_SCENE,
    show_default=True,
    help="Scene file, or the name of a bundled scene (needs a search section).",
)
@click.option("--material", default=DEFAULT_MATERIAL, show_default=True, help="Fabric name.")
@click.option(
    "--out",
    "out_dir",
    default="./preform-bench",
    show_default=True,
    type=click.Path(file_okay=False),
    metavar="DIR",
    help="Folder for tradeoff.csv and tradeoff.png.",
)
@click.option(
    "--quick",
    is_flag=True,
    help="A few settings and a coarse reference (seconds): the table only, no figure.",
)
@click.option(
    "--repeat",
    default=1,
    show_default=True,
    type=click.IntRange(1, 10),
    help="Time runs under 5 s this many times and keep the best.",
)
@library_options
@json_option
def tradeoff_command(
    scene_spec: str,
    material: str,
    out_dir: str,
    quick: bool,
    repeat: int,
    libraries: tuple[str, ...],
    no_bundled: bool,
    as_json: bool,
) -> None:
    """Wall time, memory and error against a converged reference, per fidelity setting."""

    def show(row: TradeoffRow) -> None:
        click.echo(
            f"  {row.label:<16} {row.wall_s:7.2f} s  alpha* {row.optimum_angle_deg:6.2f} deg  "
            f"E {row.energy_J:.5f} J",
            err=True,
        )

    from preform.library import LibraryError

    try:
        result = run_tradeoff(
            scene_spec,
            material,
            quick=quick,
            repeat=repeat,
            progress=show,
            libraries=libraries,
            bundled=not no_bundled,
        )
    except (SceneError, LibraryError) as exc:
        raise InputError(str(exc)) from None
    except (KeyError, ValueError) as exc:
        raise InputError(str(exc).strip("'\"")) from None
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(result, out / "tradeoff.csv")
    files = [str(out / "tradeoff.csv")]
    if quick:
        note = NO_QUICK_FIGURE
        if (out / "tradeoff.png").exists():
            note += f"; {out / 'tradeoff.png'} is an earlier run's"
    else:
        plot_tradeoff(result, out / "tradeoff.png")
        files.append(str(out / "tradeoff.png"))
        note = ""
    command = f"preform bench tradeoff --scene {scene_spec} --material {material}" + (
        " --quick" if quick else ""
    )
    if as_json:
        echo_json(
            {
                "command": command,
                "scene": result.scene,
                "material": result.material,
                "reference": result.reference_label,
                "baseline": result.baseline_label,
                "reference_check": result.reference_check,
                "rows": [row.as_dict() for row in result.rows],
                "files": files,
                "no_figure": note or None,
            }
        )
        return
    click.echo(f"command: {command}")
    click.echo(format_table(result))
    click.echo(describe_reference(result))
    click.echo("wrote " + " and ".join(files))
    if note:
        click.echo(note)


__all__ = [
    "Setting",
    "TradeoffResult",
    "TradeoffRow",
    "bench",
    "chebyshev_errors",
    "format_table",
    "measure",
    "pareto_front",
    "plot_tradeoff",
    "run_tradeoff",
    "tradeoff_settings",
    "write_csv",
]
