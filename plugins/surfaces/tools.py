"""The ``tool:`` blocks a scene may hold, one pydantic model per surface, and their builders.

Dimensions are millimetres in YAML (the unit is in every field name); builders return surfaces
in metres. Mesh files are resolved against the scene file's directory, then against the bundled
``preform/materials/tools``.

Every tool block also has ``preflight(base_dir, limits)``, which scene validation calls (and the
surface step again, just before building): it returns the built surface when building is cheap
(the analytic tools: a few numbers) so the scene's start point and node spacing can be checked
against it, and a list of problems ``(path inside the tool block, message)``. A mesh is not
read there (it may be large and is read once, by the step); only its file is checked: it exists,
is a regular file (not a device, FIFO or directory) and is no larger than
``limits.max_mesh_mb``.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from preform.plugins.surfaces.basic import Cylinder, Hemisphere, Plane
from preform.plugins.surfaces.cad import (
    DEFAULT_MAX_EDGE_REL,
    DEFAULT_TESSELLATION_ANGLE_DEG,
    DEFAULT_TESSELLATION_TOLERANCE_MM,
    cad_format,
    read_cad,
)
from preform.plugins.surfaces.domes import Cone, EllipsoidDome, FlangedHemisphere, ParaboloidDome
from preform.plugins.surfaces.mesh import MB, MeshFileError, check_mesh_file
from preform.plugins.surfaces.mesh_hygiene import FOLD_ANGLE_DEG
from preform.plugins.surfaces.tool_mesh import ToolMesh, ToolSource, read_tool_file, repaired_tool

MM = 1e-3
#: Run-off of a bare hemisphere below its rim, as a fraction of its radius [-] [C]. Measured
#: (R = 100 mm, d = 2.5 mm, ply 360 mm): R/4 covers the hemisphere for every generator angle
#: in [30°, 150°] exactly as the whole sphere does; R/20 loses 1.5 % of it at 60°, because
#: nodes that dip below the rim are parents of nodes that come back above it.
DEFAULT_RUN_OFF = 0.25
_STRICT = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

#: A problem found before running: (path inside the tool block, message).
Problem = tuple[tuple[str | int, ...], str]


class _Analytic(BaseModel):
    """An analytic tool: building it costs microseconds, so preflight builds it."""

    model_config = _STRICT

    def preflight(self, base_dir: str, limits: Any = None) -> tuple[Any, list[Problem]]:
        """The built surface and no problems, or no surface and why it cannot be built."""
        build = next(_BUILDERS[c] for c in type(self).__mro__ if c in _BUILDERS)
        try:
            return build(self, base_dir), []
        except ValueError as error:
            return None, [((), str(error))]


class PlaneTool(_Analytic):
    surface: Literal["plane"]
    size_mm: tuple[float, float] = Field(
        default=(1000.0, 1000.0), description="Plan size of the flat plate [mm] (x, y)."
    )

    @model_validator(mode="after")
    def _positive(self) -> PlaneTool:
        if min(self.size_mm) <= 0:
            raise ValueError("size_mm must be two positive lengths")
        return self


class HemisphereTool(_Analytic):
    surface: Literal["hemisphere"]
    radius_mm: float = Field(gt=0, description="Sphere radius [mm]; pole at (0, 0, R).")
    flange_half_width_mm: float | None = Field(
        default=None,
        gt=0,
        description="If given, the hemisphere stands on a flat flange (z = 0) reaching this far "
        "from the axis [mm]; otherwise the tool ends at the equator.",
    )
    fillet_radius_mm: float = Field(
        default=0.0,
        ge=0,
        description="Radius of the concave fillet between hemisphere and flange [mm] (needs a "
        "flange).",
    )
    run_off_mm: float | None = Field(
        default=None,
        gt=0,
        description="Bare hemisphere only: how far below the rim the tool continues as the same "
        "sphere for draping [mm], so the fabric runs on over the rim and is trimmed there "
        "(the part is z ≥ 0). Default R/4 (measured: covers the hemisphere for every "
        "generator angle the ply reaches, as the whole sphere does).",
    )

    @model_validator(mode="after")
    def _flange(self) -> HemisphereTool:
        if self.run_off_mm is not None and self.flange_half_width_mm is not None:
            raise ValueError("run_off_mm is for the bare hemisphere (a flange is its run-off)")
        if self.run_off_mm is not None and self.run_off_mm > self.radius_mm:
            raise ValueError(
                f"run_off_mm = {self.run_off_mm:g} mm must not exceed radius_mm = "
                f"{self.radius_mm:g} mm"
            )
        if self.fillet_radius_mm > 0 and self.flange_half_width_mm is None:
            raise ValueError(
                "fillet_radius_mm needs flange_half_width_mm (a fillet joins the "
                "hemisphere to a flange)"
            )
        if self.flange_half_width_mm is not None:
            # The builder's own checks, said here in the scene's millimetres (and found at
            # validation rather than when the case runs).
            r, rho = self.radius_mm, self.fillet_radius_mm
            if not 0 < rho < r:
                raise ValueError(
                    f"a flange needs a fillet: fillet_radius_mm must lie in (0, radius_mm = "
                    f"{r:g}) mm, got {rho:g}"
                )
            foot = (r * r + 2.0 * r * rho) ** 0.5
            if self.flange_half_width_mm <= foot:
                raise ValueError(
                    f"flange_half_width_mm = {self.flange_half_width_mm:g} mm must exceed the "
                    f"fillet's foot radius √(R² + 2Rρ) = {foot:.4g} mm"
                )
        return self


class CylinderTool(_Analytic):
    surface: Literal["cylinder"]
    radius_mm: float = Field(gt=0, description="Cylinder radius [mm].")
    length_mm: float = Field(gt=0, description="Cylinder length [mm].")
    axis: Literal["x", "y"] = Field(default="x", description="Horizontal axis direction.")


class ConeTool(_Analytic):
    surface: Literal["cone"]
    base_radius_mm: float = Field(gt=0, description="Base radius [mm] (on z = 0).")
    height_mm: float = Field(gt=0, description="Height [mm].")
    top_radius_mm: float = Field(default=0.0, ge=0, description="Truncation radius [mm].")

    @model_validator(mode="after")
    def _truncation(self) -> ConeTool:
        if self.top_radius_mm >= self.base_radius_mm:
            raise ValueError(
                f"top_radius_mm = {self.top_radius_mm:g} mm must be below base_radius_mm = "
                f"{self.base_radius_mm:g} mm"
            )
        return self


class EllipsoidTool(_Analytic):
    surface: Literal["ellipsoid"]
    semi_axes_mm: tuple[float, float, float] = Field(
        description="Semi-axes (a, b, c) [mm] of the upper half-ellipsoid dome."
    )


class ParaboloidTool(_Analytic):
    surface: Literal["paraboloid"]
    radius_mm: float = Field(gt=0, description="Base radius R [mm].")
    height_mm: float = Field(gt=0, description="Height h [mm]: z = h(1 − r²/R²).")


class MeshTool(BaseModel):
    model_config = _STRICT
    surface: Literal["mesh"]
    file: str = Field(
        description="STL, OBJ, STEP (.step/.stp) or IGES (.iges/.igs) file, relative to the "
        "scene file (or bundled). STEP and IGES need the extra preform[cad]."
    )
    units: Literal["mm", "m", "in"] | None = Field(
        default=None,
        description="Length unit of an STL or OBJ file (default mm); a STEP or IGES file "
        "declares its own.",
    )
    weld_tolerance_mm: float | None = Field(
        default=None,
        ge=0,
        description="Vertices closer than this [mm] are welded into one, closing cracks "
        "(default: 1e-6 × the mesh's bounding-box diagonal; 0: exact copies only).",
    )
    max_edge_mm: float | None = Field(
        default=None,
        gt=0,
        description="Split triangles until no edge is longer than this [mm]; the surface stays "
        "the same, closest-point queries get faster (default: none for STL/OBJ, 1/20 of the "
        "bounding-box diagonal for STEP/IGES).",
    )
    feature_angle_deg: float | None = Field(
        default=None,
        ge=0,
        le=180,
        description="Where the tool turns by more than this angle [deg] between a net node's "
        "triangle and its parent's (a sharp feature crease), node spacing is measured along the "
        "surface instead of as a chord (docs/physics.md, 'Sharp creases'). Default 180: off, "
        "every spacing a chord; 20 suits tools whose sharp creases lie more than a node "
        "spacing apart.",
    )
    fold_angle_deg: float | None = Field(
        default=None,
        gt=0,
        le=180,
        description="An edge across which the surface turns back by more than this [deg] "
        f"(between its two triangles' normals) is a fold, and the tool is refused (default "
        f"{FOLD_ANGLE_DEG:g}: a triangle turned over; docs/tools.md). Raise it only for a real "
        "edge sharper than that (a wedge thinner than 180° minus it); the edges it lets "
        "through are said as a warning.",
    )
    tessellation_tolerance_mm: float | None = Field(
        default=None,
        ge=0.001,
        description="STEP/IGES only: largest distance between the facets and the CAD surface "
        f"[mm] (default {DEFAULT_TESSELLATION_TOLERANCE_MM:g}; at least 0.001: the triangle "
        "count grows as 1/tolerance).",
    )
    tessellation_angle_deg: float | None = Field(
        default=None,
        gt=0,
        lt=180,
        description="STEP/IGES only: largest angle between neighbouring facets' normals [deg] "
        f"(default {DEFAULT_TESSELLATION_ANGLE_DEG:g}).",
    )

    @model_validator(mode="after")
    def _per_format(self) -> MeshTool:
        if cad_format(self.file) is not None:
            if self.units is not None:
                raise ValueError(
                    "units: a STEP or IGES file declares its own length unit; remove units"
                )
        else:
            for name in ("tessellation_tolerance_mm", "tessellation_angle_deg"):
                if getattr(self, name) is not None:
                    raise ValueError(
                        f"{name} is for STEP and IGES tools; an STL or OBJ file is already "
                        "tessellated"
                    )
        return self

    def tessellation_tolerance_in_force_mm(self) -> float | None:
        """The tessellation tolerance [mm] a STEP or IGES file is read with (the scene's or
        the default); None for an STL or OBJ file, which comes tessellated."""
        if cad_format(self.file) is None:
            return None
        return self.tessellation_tolerance_mm or DEFAULT_TESSELLATION_TOLERANCE_MM

    def preflight(self, base_dir: str, limits: Any = None) -> tuple[Any, list[Problem]]:
        """No surface (reading waits for the step) and the problems of the mesh file."""
        try:
            path = resolve_tool_file(self.file, base_dir)
            check_mesh_file(path, _max_bytes(limits))
        except (FileNotFoundError, MeshFileError) as error:
            return None, [(("file",), str(error))]
        except (OSError, ValueError) as error:
            # A name the system cannot look up at all (too long, an embedded NUL byte).
            why = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
            name = self.file if len(self.file) <= 80 else self.file[:77] + "..."
            return None, [(("file",), f"tool mesh {name!r} cannot be looked up: {why}")]
        return None, []


_UNITS_TO_M = {"mm": 1e-3, "m": 1.0, "in": 0.0254}


def _max_bytes(limits: Any) -> int | None:
    max_mb = getattr(limits, "max_mesh_mb", None)
    return None if max_mb is None else int(float(max_mb) * MB)


def build_plane(p: PlaneTool, base_dir: str) -> Plane:
    return Plane((p.size_mm[0] * MM, p.size_mm[1] * MM))


def build_hemisphere(p: HemisphereTool, base_dir: str) -> Hemisphere | FlangedHemisphere:
    if p.flange_half_width_mm is None:
        run_off = p.run_off_mm if p.run_off_mm is not None else DEFAULT_RUN_OFF * p.radius_mm
        return Hemisphere(p.radius_mm * MM, run_off_m=run_off * MM)
    return FlangedHemisphere(p.radius_mm * MM, p.fillet_radius_mm * MM, p.flange_half_width_mm * MM)


def build_cylinder(p: CylinderTool, base_dir: str) -> Cylinder:
    return Cylinder(p.radius_mm * MM, p.length_mm * MM, p.axis)


def build_cone(p: ConeTool, base_dir: str) -> Cone:
    return Cone(p.base_radius_mm * MM, p.height_mm * MM, top_radius_m=p.top_radius_mm * MM)


def build_ellipsoid(p: EllipsoidTool, base_dir: str) -> EllipsoidDome:
    return EllipsoidDome(tuple(a * MM for a in p.semi_axes_mm))


def build_paraboloid(p: ParaboloidTool, base_dir: str) -> ParaboloidDome:
    return ParaboloidDome(p.radius_mm * MM, p.height_mm * MM)


def resolve_tool_file(name: str, base_dir: str) -> Path:
    """A tool mesh path: relative to the scene, else among the bundled tools."""
    path = Path(name)
    if not path.is_absolute():
        local = Path(base_dir) / path
        if local.exists():
            return local
        bundled = Path(str(resources.files("preform.materials") / "tools")) / path
        if bundled.exists():
            return bundled
    if not path.exists():
        raise FileNotFoundError(
            f"tool mesh {name!r} not found next to the scene ({base_dir}) "
            "nor among the bundled tools"
        )
    return path


def build_mesh(p: MeshTool, base_dir: str, limits: Any = None) -> ToolMesh:
    """Read the tool file and repair it (``preform.plugins.surfaces.mesh_hygiene``, through
    ``tool_mesh.repaired_tool``, as ``read_stl``/``read_obj`` do); ``limits`` (a scene's
    ``limits``) caps the file size, which is checked with ``stat`` before reading (see
    ``check_mesh_file``). A STEP or IGES file is tessellated first
    (``preform.plugins.surfaces.cad``)."""
    path = resolve_tool_file(p.file, base_dir)
    max_bytes = _max_bytes(limits)
    max_edge = None if p.max_edge_mm is None else p.max_edge_mm * MM
    options: dict[str, Any] = {
        "weld_tolerance_m": None if p.weld_tolerance_mm is None else p.weld_tolerance_mm * MM,
        "fold_angle_deg": FOLD_ANGLE_DEG if p.fold_angle_deg is None else p.fold_angle_deg,
        "feature_angle_deg": p.feature_angle_deg,
    }
    kind = cad_format(path)
    if kind is None:
        units = p.units or "mm"
        source = ToolSource(
            str(p.file),
            "OBJ" if path.suffix.lower() == ".obj" else "STL",
            units,
            "scene tool.units" if p.units else "default (scene gives no tool.units)",
        )
        return read_tool_file(
            path, source, _UNITS_TO_M[units], max_bytes=max_bytes, max_edge_m=max_edge, **options
        )
    tolerance = p.tessellation_tolerance_in_force_mm() or DEFAULT_TESSELLATION_TOLERANCE_MM
    angle = p.tessellation_angle_deg or DEFAULT_TESSELLATION_ANGLE_DEG
    cad = read_cad(path, tolerance * MM, float(np.radians(angle)), max_bytes=max_bytes)
    unit, unit_from = (
        (cad.unit, f"declared in the {kind} file")
        if cad.unit is not None
        else ("mm", f"not declared in the {kind} file: OpenCASCADE's default")
    )
    source = ToolSource(str(p.file), kind, unit, unit_from, tolerance * MM, np.radians(angle))
    if max_edge is None:
        extent = cad.vertices[np.unique(cad.faces)]
        diagonal = float(np.linalg.norm(extent.max(axis=0) - extent.min(axis=0)))
        max_edge = DEFAULT_MAX_EDGE_REL * diagonal
    return repaired_tool(
        path,
        cad.vertices,
        cad.faces,
        cad.face_of_triangle,
        cad.face_names,
        source,
        max_edge_m=max_edge,
        **options,
    )


_BUILDERS: dict[type, Any] = {
    PlaneTool: build_plane,
    HemisphereTool: build_hemisphere,
    CylinderTool: build_cylinder,
    ConeTool: build_cone,
    EllipsoidTool: build_ellipsoid,
    ParaboloidTool: build_paraboloid,
}

SURFACES: list[tuple[str, type[BaseModel], Callable[..., Any]]] = [
    ("plane", PlaneTool, build_plane),
    ("hemisphere", HemisphereTool, build_hemisphere),
    ("cylinder", CylinderTool, build_cylinder),
    ("cone", ConeTool, build_cone),
    ("ellipsoid", EllipsoidTool, build_ellipsoid),
    ("paraboloid", ParaboloidTool, build_paraboloid),
    ("mesh", MeshTool, build_mesh),
]
