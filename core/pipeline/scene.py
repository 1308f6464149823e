"""Scenes: what to drape onto what, and which outputs to produce. YAML, validated like fabrics.

Lengths are millimetres and angles degrees in a scene (the unit is in every field name); steps
convert to SI when they build their objects. The ``tool`` block is validated against the
registered surfaces, like a fabric's ``architecture``.
"""

from __future__ import annotations

import contextlib
import difflib
import os
from importlib import resources
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator

from preform.base.export_section import ExportSection
from preform.base.limits import MAX_POLYGON_VERTICES
from preform.pipeline.layup_section import LayupSection
from preform.registry import LazyLoadError, Registry
from preform.validation import located_errors, unknown_field_message
from preform.yamlsource import Document, SourceError, YamlSourceError, load_yaml


class _Strict(BaseModel):
    """A scene's model: frozen, unknown keys refused, numbers finite."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class PlySection(_Strict):
    """The fabric ply: its node spacing and its outline in the flat."""

    node_spacing_mm: float | None = Field(
        default=None,
        gt=0,
        description="Pin-jointed net node spacing d [mm]; when absent the fidelity preset "
        "chooses it from the tool's size.",
    )
    size_mm: tuple[float, float] | None = Field(
        default=None, description="Rectangular ply size [mm] along the two fibre families."
    )
    outline_mm: list[tuple[float, float]] | None = Field(
        default=None,
        max_length=MAX_POLYGON_VERTICES,
        description="Polygonal ply outline in the flat [mm], in the fibre (u, v) frame with the "
        "start node at the origin; replaces size_mm.",
    )
    offset_mm: tuple[float, float] = Field(
        default=(0.0, 0.0),
        description="Position of the start node in the ply, from the ply centre [mm] (u, v).",
    )

    @field_validator("size_mm")
    @classmethod
    def _positive(cls, v: tuple[float, float] | None) -> tuple[float, float] | None:
        if v is not None and (v[0] <= 0 or v[1] <= 0):
            raise ValueError("ply size must be positive in both directions")
        return v

    @field_validator("outline_mm")
    @classmethod
    def _polygon(cls, v: list[tuple[float, float]] | None) -> list[tuple[float, float]] | None:
        if v is not None and len(v) < 3:
            raise ValueError("a ply outline needs at least 3 vertices")
        return v


class StartSection(_Strict):
    """Where and how the two generator fibre paths start."""

    point_mm: tuple[float, float] = Field(
        default=(0.0, 0.0), description="Start point in plan (x, y) [mm], put on the tool."
    )
    orientation_deg: float = Field(
        default=0.0, description="Plan direction of the first generator [deg from the x axis]."
    )
    generator_angle_deg: float = Field(
        default=90.0,
        gt=0.0,
        lt=180.0,
        description="Angle between the two generators at the start point [deg]. The fabric's "
        "reference direction bisects the first generator and the reversed second one, so "
        "angles below 90 shear the generators in the negative (for warp-knits: "
        "perpendicular-to-stitch) sense.",
    )
    generators: Literal["geodesic", "plan", "polyline"] = Field(
        default="geodesic",
        description="Generator paths: geodesics on the tool, straight lines in plan, or the "
        "plan polylines given in generator_polylines_mm.",
    )
    generator_polylines_mm: tuple[list[tuple[float, float]], list[tuple[float, float]]] | None = (
        Field(
            default=None,
            description="With generators: polyline, the two generator paths in plan [mm], each "
            "starting at the start point.",
        )
    )


class PartSection(_Strict):
    """The part: the region of the tool that is made (``preform.drape.engine.part``). The net is
    draped over the tool as far as the ply reaches and clipped to the part; energies and
    extremes are of the part. Several fields together mean their intersection. Without this
    section the part is the tool's own (a bare hemisphere: z ≥ 0; other tools: every cell the
    net puts on them). ``faces`` selects named or numbered faces of a mesh or CAD tool."""

    z_min_mm: float | None = Field(
        default=None, description="Height cut: the part is the tool at z ≥ z_min_mm [mm]."
    )
    plan_outline_mm: list[tuple[float, float]] | None = Field(
        default=None,
        max_length=MAX_POLYGON_VERTICES,
        description="Plan outline (x, y) [mm] of the part seen from above, a closed polygon; "
        "a closed curve on a tool whose plan view is one-to-one is its projected points.",
    )
    faces: list[int | str] | None = Field(
        default=None,
        min_length=1,
        description="Faces of a tool read from a file that make the part: CAD face numbers "
        "(from 1) or names (STEP/IGES face labels, OBJ g/o groups).",
    )
    area_mm2: float | None = Field(
        default=None,
        gt=0,
        description="The part's area on the tool [mm²], when known (reported against the "
        "covered area; a bare hemisphere's own part knows its area).",
    )

    @field_validator("plan_outline_mm")
    @classmethod
    def _polygon(cls, v: list[tuple[float, float]] | None) -> list[tuple[float, float]] | None:
        if v is not None and len(v) < 3:
            raise ValueError("a part outline needs at least 3 vertices")
        return v


class RangeDeg(_Strict):
    """A closed range of angles [deg] to search."""

    min: float
    max: float
    step: float | None = Field(default=None, gt=0, description="Scan step [deg].")


class SearchSection(_Strict):
    """The minimum-energy search over generator choices (see ``preform.optimise.search``)."""

    generator_angle_deg: RangeDeg | None = Field(
        default=None, description="Range of generator angles to search [deg] (default 30-150)."
    )
    scan_step_deg: float | None = Field(
        default=None, gt=0, description="Step of the global scan [deg] (fidelity knob)."
    )
    tolerance_deg: float | None = Field(
        default=None, gt=0, description="Refinement tolerance on the optimum [deg] (knob)."
    )
    max_drapes: int | None = Field(
        default=None, ge=3, description="Most drapes the search may run (fidelity knob)."
    )
    min_coverage: float = Field(
        default=0.0,
        ge=0,
        le=1,
        description="Angles whose drape covers less of the part than this are infeasible.",
    )
    part_area_mm2: float | None = Field(
        default=None,
        gt=0,
        description="Area of the part [mm²] that coverage is judged against (default: the "
        "part's own area when known, e.g. 2πR² for a bare hemisphere, else the largest area "
        "any scanned drape covers).",
    )
    max_wrinkle_area_share: float | None = Field(
        default=None,
        ge=0,
        le=1,
        description="An angle whose drape has more than this share of its covered part area "
        "past jamming or stitch failure (where the fabric wrinkles) cannot be made. Default: "
        "no cap (wrinkle_area_tolerance alone).",
    )
    wrinkle_area_tolerance: float = Field(
        default=0.02,
        ge=0,
        le=1,
        description="An angle can be made when the share of its covered part area past "
        "jamming or stitch failure is at most this above the least share any searched angle "
        "reaches (feasibility first, by area; 0: least wrinkle, then least energy; 1: least "
        "energy alone). Default 0.02 [C].",
    )
    uncovered_shear_deg: float | None = Field(
        default=None,
        gt=0,
        lt=90,
        description="Price uncovered part area at the shear energy of this angle [deg] (the "
        "larger of the two senses), a stated choice, the same rule for every architecture; the "
        "case is then partial. Default: no price (the energy is the part's alone).",
    )
    layout: dict[str, Any] | None = Field(
        default=None,
        description="Also search the orientation and start point (Nelder-Mead): "
        "{orientation: true, start_point: true, ...}; see preform.optimise.search.",
    )
    curved_generators: dict[str, Any] | None = Field(
        default=None,
        description="Optimise curved generators after the angle: {terms: 2, ...}.",
    )
    relax: bool | dict[str, Any] = Field(
        default=False,
        description="Beyond the paper: relax the whole net towards least energy afterwards.",
    )


class NumericsSection(_Strict):
    """Hand-set numerical knobs; each overrides the fidelity preset (preform.base.fidelity)."""

    solver_tolerance: float | None = Field(
        default=None, gt=0, lt=1e-2, description="Solver tolerance relative to the spacing d."
    )
    generator_substeps: int | None = Field(
        default=None, ge=1, le=1024, description="Sub-steps per d when marching generators."
    )
    energy_table_step_deg: float | None = Field(
        default=None,
        ge=0,
        le=10,
        description="Step of the shear law's energy table (search and drape energy) [deg]; 0 = exact.",
    )


class LimitsSection(_Strict):
    """Resource limits of one case. Each protects the machine from an input that would take it
    over (a ply of 10^10 nodes, a 2 GB mesh, a case that never ends). Raise one on purpose here;
    the value in force is recorded with the case (``limit_*`` in its summary)."""

    case_timeout_s: float | None = Field(
        default=None,
        gt=0,
        description="Wall-time limit of one case [s]; past it the case is stopped and recorded "
        "timed_out. Default: the run's --case-timeout.",
    )
    max_nodes: int = Field(
        default=20_000_000,
        ge=1,
        description="Most pin-jointed-net nodes one drape may have (ply size / node spacing, "
        "squared) [-]; about 130 bytes each.",
    )
    max_mesh_mb: float = Field(
        default=512.0,
        gt=0,
        description="Largest tool or FE (export.mesh) mesh file read [MB]; larger files are "
        "refused before reading.",
    )


class ShearSection(_Strict):
    """Angles at which shear curves are tabulated."""

    angles_deg: RangeDeg = Field(default_factory=lambda: RangeDeg(min=0, max=60, step=1))


class Scene(_Strict):
    """A validated scene."""

    name: str = Field(min_length=1, description="Name of the scene; names the results folder.")
    description: str = ""
    tool: Any = Field(
        default=None, description="Tool surface: {surface: NAME, ...dimensions in mm}."
    )
    ply: PlySection | None = None
    part: PartSection | None = Field(
        default=None, description="The part made on the tool (default: the tool's own)."
    )
    start: StartSection | None = None
    search: SearchSection | None = None
    shear: ShearSection | None = None
    fidelity: Literal["draft", "standard", "fine"] | None = Field(
        default=None,
        description="Preset of the numerical knobs (default standard); hand-set knobs win.",
    )
    numerics: NumericsSection | None = None
    limits: LimitsSection = Field(
        default_factory=LimitsSection,
        description="Resource limits of a case (time, net size, mesh file size).",
    )
    materials: str | None = Field(
        default=None, description="Glob of fabric names this scene applies to (default all)."
    )
    export: ExportSection | None = Field(
        default=None, description="Mapping onto your FE mesh and the cutting pattern."
    )
    layup: LayupSection | None = Field(
        default=None,
        description="A stack of plies, tool side first, each draped on the tool offset by the "
        "plies below (preform.stack); one case per scene, not per fabric.",
    )
    outputs: list[str] = Field(min_length=1, description="Products and files to produce.")
    #: Directory of the scene file (resolves relative tool mesh paths); not from YAML.
    _base_dir: str = PrivateAttr(default=".")
    #: The validated sections of plugins' steps (``Step.sections``), by key.
    _sections: dict[str, BaseModel] = PrivateAttr(default_factory=dict)

    def section(self, key: str) -> Any:
        """The validated section ``key`` (a field of the scene or a plugin step's), or None."""
        return getattr(self, key) if key in type(self).model_fields else self._sections.get(key)

    def plugin_sections_data(self) -> dict[str, Any]:
        """The plugin steps' sections as scene data (JSON types), as a scene file holds them:
        what a scene derived from this one (a layup's ply) carries over."""
        return {
            key: value.model_dump(mode="json") if isinstance(value, BaseModel) else value
            for key, value in self._sections.items()
        }

    @property
    def base_dir(self) -> str:
        """Directory of the scene file, against which relative paths in it resolve."""
        return self._base_dir

    def located_at(self, base_dir: str) -> Scene:
        """This scene, with relative paths resolving against ``base_dir``."""
        scene = self.model_copy()
        scene._base_dir = base_dir
        return scene


class SceneError(Exception):
    def __init__(self, errors: list[SourceError]) -> None:
        self.errors = errors
        super().__init__("\n".join(str(e) for e in errors))


def bundled_scene_dir() -> Path:
    return Path(str(resources.files("preform.materials") / "scenes"))


#: The scene ``preform pipeline run`` runs when given none: the founding paper's study, the
#: minimum-energy drape of every fabric over a hemisphere.
DEFAULT_SCENE = "hemisphere-min-energy"


def default_scene_path() -> Path:
    return bundled_scene_dir() / f"{DEFAULT_SCENE}.yaml"


def resolve_scene_path(spec: str) -> Path:
    """A scene file path, or the name of a bundled scene (``hemisphere``; ``default``).

    A bare name of a bundled scene (no directory part, no ``.yaml``/``.yml`` suffix) is the
    bundled scene even when the current directory holds a file or folder of that name (a
    results folder called ``unit-cell`` must not capture ``--scene unit-cell``); write a path
    (``./unit-cell``, ``unit-cell.yaml``) for a file of your own."""
    if spec == "default":
        return default_scene_path()
    path = Path(spec)
    written_as_path = (
        "/" in spec or os.sep in spec or spec.startswith(".") or path.suffix in (".yaml", ".yml")
    )
    bundled = bundled_scene_dir() / f"{spec}.yaml"
    if not written_as_path and bundled.is_file():
        return bundled
    return path


def bundled_scene_names() -> list[str]:
    """The names of the bundled scenes, sorted (``--scene NAME``)."""
    return sorted(path.stem for path in bundled_scene_dir().glob("*.yaml"))


def missing_scene_message(spec: str) -> str:
    """Why ``spec`` names no scene, with the bundled scenes' names to choose from."""
    return (
        f"no scene file {spec!r} and no bundled scene of that name; the bundled scenes: "
        f"{', '.join(bundled_scene_names())} (`preform scenes list`)"
    )


def validate_scene_data(doc: Document, data: Any, registry: Registry) -> Scene:
    """Validate one scene document; raises SceneError with located errors.

    The scene's own fields are validated by :class:`Scene`, a plugin step's section by the
    model its step declares, the tool block by its registered surface; then each registered
    step that owns a section of the scene checks it (``Step.check``), and the outputs are
    planned. No step is imported here but through the registry.
    """
    if not isinstance(data, dict):
        raise SceneError([doc.error((), "a scene must be a mapping")])
    owners = registry.providers("sections")
    fields = Scene.model_fields
    errors = [
        doc.error((key,), unknown_field_message(key, sorted({*fields, *owners})))
        for key in data
        if key not in fields and key not in owners
    ]
    try:
        own = {key: value for key, value in data.items() if key in fields}
        scene = Scene.model_validate(own).located_at(str(Path(doc.file).resolve().parent))
    except ValidationError as exc:
        errors += located_errors(doc, (), data, exc, Scene)
    sections = _plugin_sections(doc, data, registry, owners, errors)
    if errors:
        raise SceneError(errors)
    scene._sections.update(sections)
    tool = data.get("tool")
    if tool is not None:
        known = registry.names("surfaces")
        name = tool.get("surface") if isinstance(tool, dict) else None
        if name not in known:
            close = difflib.get_close_matches(str(name), known, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            where = (
                ("tool", "surface") if isinstance(tool, dict) and "surface" in tool else ("tool",)
            )
            errors.append(
                doc.error(
                    where,
                    f"unknown surface {name!r}{hint}; "
                    f"registered surfaces: {', '.join(known) or 'none'}",
                )
            )
        else:
            try:
                params = registry.surface_type(str(name)).params
            except LazyLoadError as exc:  # a plugin's lazily registered surface
                errors.append(doc.error(("tool", "surface"), str(exc)))
            else:
                try:
                    scene = scene.model_copy(update={"tool": params.model_validate(tool)})
                except ValidationError as exc:
                    errors += located_errors(doc, ("tool",), tool, exc, params, "tool")
    # the checks of the steps owning a section the scene holds (one that cannot load: the plan)
    for name in dict.fromkeys(owners[key] for key in owners if key in data and not errors):
        with contextlib.suppress(LazyLoadError):
            check = registry.step(name).check
            errors += check(scene, doc, registry) if check is not None else []
    from preform.pipeline.planner import PlanError, plan

    try:
        plan(scene, registry)
    except PlanError as exc:
        for index, message in exc.problems:
            errors.append(doc.error(("outputs", index) if index is not None else (), message))
    if errors:
        raise SceneError(errors)
    return scene


def _plugin_sections(
    doc: Document | None,
    data: dict[str, Any],
    registry: Registry,
    owners: dict[str, str],
    errors: list[SourceError],
) -> dict[str, Any]:
    """The sections of plugins' steps in ``data``, each validated by its step's model; their
    problems, located in ``doc``, go to ``errors`` (raised at once without a ``doc``)."""
    sections: dict[str, Any] = {}
    for key in (key for key in data if key in owners and key not in Scene.model_fields):
        try:
            model = registry.step(owners[key]).sections[key]
            sections[key] = model.model_validate(data[key]) if model is not None else data[key]
        except (LazyLoadError, ValidationError) as exc:
            if doc is None:
                raise
            errors += (
                located_errors(doc, (key,), data[key], exc, model, key)
                if isinstance(exc, ValidationError)
                else [doc.error((key,), str(exc))]
            )
    return sections


def load_scene(path: str | Path, registry: Registry) -> tuple[Scene, dict[str, Any]]:
    """Load a scene file (one document); returns the scene and its raw data."""
    try:
        docs = load_yaml(path)
    except YamlSourceError as exc:
        raise SceneError(exc.errors) from None
    if len(docs) != 1:
        line, column = docs[1].locate(()) if len(docs) > 1 else (1, 1)
        message = "a scene file holds exactly one YAML document"
        raise SceneError([SourceError(str(path), line, column, "", message)])
    return validate_scene_data(docs[0], docs[0].data, registry), docs[0].data


def scene_from_data(data: dict[str, Any], base_dir: str, registry: Registry) -> Scene:
    """Rebuild a scene from data that already validated (worker processes)."""
    fields = Scene.model_fields
    scene = Scene.model_validate({k: v for k, v in data.items() if k in fields})
    scene = scene.located_at(base_dir)
    scene._sections.update(
        _plugin_sections(None, data, registry, registry.providers("sections"), [])
    )
    tool = data.get("tool")
    if isinstance(tool, dict):
        params = registry.surface_type(str(tool.get("surface"))).params
        scene = scene.model_copy(update={"tool": params.model_validate(tool)})
    return scene
