"""The scene's ``export`` section: what the downstream exporters need (the user's mesh, the
reference direction, thickness, seam allowance). Lengths in mm, as everywhere in a scene."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator


def prefix_problem(prefix: str) -> str | None:
    """Why ``prefix`` cannot start the names of the exporters' sets, distributions and
    orientations (an Abaqus name: a letter, then letters, digits or _, at most 60 with the
    suffixes the exporters add), or None."""
    name = prefix.upper()
    if not name or not name[0].isalpha() or len(name) > 60 or not name.replace("_", "").isalnum():
        return f"prefix must be a letter then letters, digits or _ (≤ 60), got {prefix!r}"
    if not name.isascii():
        return f"prefix must be ASCII letters, digits or _, got {prefix!r}"
    return None


class DartSpec(BaseModel):
    """A V-shaped dart cut out of the pattern: the triangle apex, mouth_mm[0], mouth_mm[1]
    in the flat [mm] (u fibres along x, v along y, the start node at the origin)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    apex_mm: tuple[float, float] = Field(description="Tip of the dart, inside the pattern [mm].")
    mouth_mm: tuple[tuple[float, float], tuple[float, float]] = Field(
        description="The two ends of the dart's mouth, on or beyond the pattern's edge [mm]."
    )

    @model_validator(mode="after")
    def _not_flat(self) -> DartSpec:
        (ax, ay), ((bx, by), (cx, cy)) = self.apex_mm, self.mouth_mm
        if abs((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)) <= 0.0:
            raise ValueError("a dart's apex and mouth must not lie on one line (no area)")
        return self


class CutSpec(BaseModel):
    """A straight cut (a slit) in the flat [mm], from one point to the other."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    from_mm: tuple[float, float] = Field(description="One end of the cut [mm].")
    to_mm: tuple[float, float] = Field(description="The other end of the cut [mm].")

    @model_validator(mode="after")
    def _has_length(self) -> CutSpec:
        if self.from_mm == self.to_mm:
            raise ValueError("a cut needs two different end points")
        return self


class ExportSection(BaseModel):
    """Options of the mesh-mapping and cutting-pattern exporters."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    mesh: str | None = Field(
        default=None,
        description="The user's shell mesh of the part (Abaqus .inp, Nastran .bdf, or any "
        "format meshio reads, e.g. .stl, .obj, .vtu), relative to the scene file.",
    )
    mesh_unit_mm: float = Field(
        default=1.0, gt=0, description="Length of one mesh file unit [mm] (1000 for metres)."
    )
    reference_direction: tuple[float, float, float] = Field(
        default=(1.0, 0.0, 0.0),
        description="Global direction the fibre angles are measured from (projected into "
        "each element).",
    )
    nominal_thickness_mm: float | None = Field(
        default=None,
        gt=0,
        description="Undeformed ply thickness t0 [mm] of every exported thickness (t0 · t/t0); "
        "default: the sheared unit cell's thickness at zero shear where the fabric has one, "
        "else its derived thickness_mm.",
    )
    thickness_cap_ratio: float | None = Field(
        default=None,
        gt=1,
        description="Compaction limit of t/t0: elements above it are reported, not capped.",
    )
    max_gap_mm: float | None = Field(
        default=None,
        gt=0,
        description="Largest distance [mm] from an element centroid to the draped net for "
        "the element to count as covered (default: the node spacing).",
    )
    seam_allowance_mm: float = Field(
        default=0.0, ge=0, description="Seam allowance around the cutting pattern [mm]."
    )
    darts: tuple[DartSpec, ...] = Field(
        default=(),
        description="V-shaped darts removed from the cutting pattern, in the flat [mm].",
    )
    cuts: tuple[CutSpec, ...] = Field(
        default=(), description="Straight cuts (slits) in the cutting pattern, in the flat [mm]."
    )
    layer_materials: tuple[int, int] = Field(
        default=(1, 1),
        description="Material numbers of the u and v fibre layers (ANSYS MAT, LS-DYNA MID of "
        "the composite form); each a unidirectional material along its own x axis.",
    )
    u_layer_fraction: float = Field(
        default=0.5,
        gt=0,
        lt=1,
        description="Share of the ply thickness in the u layer (0.5: a balanced fabric).",
    )
    lsdyna_form: Literal["beta", "composite"] = Field(
        default="beta",
        description="LS-DYNA include: beta (*ELEMENT_SHELL_BETA, u fibres and thickness) or "
        "composite (*ELEMENT_SHELL_COMPOSITE, both families as two layers; needs t0).",
    )
    prefix: str = Field(
        default="PREFORM", description="Name prefix of Abaqus sets, distributions, orientations."
    )
    part_id: int = Field(
        default=1, ge=1, description="LS-DYNA PID of elements whose mesh gives none."
    )

    @field_validator("prefix")
    @classmethod
    def _prefix(cls, v: str) -> str:
        # refused here, when the scene is validated, not when the include is written
        problem = prefix_problem(v)
        if problem is not None:
            raise ValueError(problem)
        return v

    @field_validator("layer_materials")
    @classmethod
    def _material_numbers(cls, v: tuple[int, int]) -> tuple[int, int]:
        if min(v) < 1:
            raise ValueError("material numbers start at 1")
        return v

    @field_validator("reference_direction")
    @classmethod
    def _nonzero(cls, v: tuple[float, float, float]) -> tuple[float, float, float]:
        if sum(x * x for x in v) == 0:
            raise ValueError("the reference direction must not be the zero vector")
        return v
