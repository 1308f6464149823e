"""The ``layup`` section of a scene: a stack of plies, in stacking order (tool side first).

Each ply names its fabric, its orientation in the 0/±45/90 convention, and how its generator
angle is chosen; the section's keys carry their unit (mm, degrees) like the rest of a scene.
What a ply's orientation means (``docs/scenes.md``, "Layups"):

    The first fibre family of the ply (the first generator: a woven fabric's warp, a
    warp-knit's first tow layer) leaves the start point in the plan direction
    ``reference_direction_deg + orientation_deg``, measured counter-clockwise from the x axis
    seen from above (``start.orientation_deg`` of the ply's drape). The second family leaves
    it at the ply's generator angle α from the first (90° for a fabric laid down unsheared, or
    the least-energy angle), so a [0/45/-45/90] stack of a balanced weave has its warps at 0,
    45, −45 and 90° from the reference direction at the start point.

The ply's drape is the scene's own (tool, part, ply size, node spacing, fidelity) with these
set; ``part_outline_mm`` replaces the scene's ``part.plan_outline_mm`` for that ply (a
drop-off: a ply that covers only part of the part). ``preform.stack`` runs the plies.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene

_STRICT = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
#: Most plies of one stack: far beyond any preform (a hundred 0.3 mm plies is a 30 mm wall),
#: and each ply is a drape.
MAX_PLIES = 200
#: The scene outputs a ply gives when the layup names none: its drape, cell table, VTU and
#: fibre pattern (``preform scenes outputs`` lists every one).
DEFAULT_PLY_OUTPUTS = ("drape", "cells_csv", "vtu", "fibre_pattern_png")


class LayupPly(BaseModel):
    """One ply of the stack."""

    model_config = _STRICT
    name: str | None = Field(
        default=None,
        min_length=1,
        description="Name of the ply (its results sub-folder); default ply-<k>-<fabric>, k "
        "from 1 on the tool side.",
    )
    fabric: str = Field(min_length=1, description="The ply's fabric (a library name).")
    orientation_deg: float = Field(
        default=0.0,
        ge=-180.0,
        le=180.0,
        description="Ply angle [deg] from the layup's reference direction, counter-clockwise "
        "seen from above: the plan direction of the first fibre family at the start point.",
    )
    start_point_mm: tuple[float, float] | None = Field(
        default=None,
        description="Start point in plan (x, y) [mm]; default the scene's start.point_mm.",
    )
    generator_angle_deg: float | Literal["least_energy"] = Field(
        default=90.0,
        description="Angle between the two fibre families at the start [deg] (0 < α < 180), "
        "or least_energy: the scene's search (or the default 30-150° one) chooses it.",
    )
    thickness_mm: float | None = Field(
        default=None,
        gt=0,
        description="The ply's nominal (unsheared) thickness t0 [mm]; default the scene's "
        "export.nominal_thickness_mm, else the fabric's sheared unit cell's or derived one.",
    )
    part_outline_mm: list[tuple[float, float]] | None = Field(
        default=None,
        max_length=10_000,
        description="Plan outline (x, y) [mm] of the region this ply covers (a drop-off); "
        "replaces the scene's part.plan_outline_mm for this ply.",
    )

    @field_validator("generator_angle_deg")
    @classmethod
    def _angle(cls, v: float | str) -> float | str:
        if isinstance(v, float | int) and not 0.0 < float(v) < 180.0:
            raise ValueError(f"a generator angle lies in (0, 180) degrees, got {v:g}")
        return v

    @field_validator("part_outline_mm")
    @classmethod
    def _outline(cls, v: list[tuple[float, float]] | None) -> list[tuple[float, float]] | None:
        if v is not None and len(v) < 3:
            raise ValueError("a ply's part outline needs at least 3 vertices")
        return v  # one that crosses itself: the layup step's check (preform.stack.validate)


class LayupSection(BaseModel):
    """The stack: plies in stacking order, tool side first."""

    model_config = _STRICT
    reference_direction_deg: float = Field(
        default=0.0,
        description="Plan direction of the 0° ply [deg from the x axis, counter-clockwise].",
    )
    plies: list[LayupPly] = Field(
        min_length=1, max_length=MAX_PLIES, description="The plies, tool side first."
    )
    ply_outputs: list[str] = Field(
        default_factory=lambda: list(DEFAULT_PLY_OUTPUTS),
        min_length=1,
        description="The outputs each ply gives in its sub-folder (any drape output).",
    )

    @model_validator(mode="after")
    def _unique_names(self) -> LayupSection:
        names = [n for n in self.ply_names() if n is not None]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise ValueError(f"ply names must differ (each names a folder): {repeated}")
        return self

    def ply_names(self) -> list[str]:
        """Every ply's name: its own, else ply-<k>-<fabric> (k from 1, tool side)."""
        return [p.name or f"ply-{k}-{p.fabric}" for k, p in enumerate(self.plies, start=1)]


def layup_of(scene: Scene) -> LayupSection:
    """The scene's layup section; a ValueError for a scene without one."""
    if scene.layup is None:
        raise ValueError(f"scene {scene.name!r} has no layup section")
    return scene.layup
