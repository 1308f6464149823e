"""The base every fabric architecture's parameter model derives from.

A library entry is validated into the pydantic model its ``architecture`` tag selects. Models
keep the YAML's datasheet units (the unit is in the field name: ``tow_width_mm``) so that a
model round-trips to the same YAML; physical objects built from a model (unit cells, shear
laws) convert to SI once, when they are built.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, ConfigDict, Field

if TYPE_CHECKING:
    from preform.geometry.unit_cell import UnitCell

#: Where in an entry a problem is: a path of field names and list indices,
#: e.g. ("weave", "matrix", 2).
Location = tuple[str | int, ...]


class FabricBase(BaseModel):
    """Fields every fabric entry carries, whatever its architecture.

    Subclasses narrow ``architecture`` to a ``Literal`` naming themselves, add their parameters,
    and override the hooks below that their architecture can answer.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    name: str = Field(min_length=1, description="Unique name of the fabric across the library.")
    architecture: str = Field(description="Registered architecture that validates this entry.")
    source: str = Field(
        min_length=1,
        description="Provenance: paper, datasheet or test report the values come from.",
    )
    note: str = Field(
        min_length=1,
        description="What the values are; illustrative values must say so here.",
    )
    shear_law: Any = Field(
        default=None,
        description=(
            "Optional shear law block: {law: NAME, ...parameters}. Validated against the "
            "registered shear laws when the library is loaded."
        ),
    )

    # -- hooks an architecture overrides ---------------------------------------------------
    def unit_cell(self) -> UnitCell | None:
        """The repeating cell of the fabric in SI units, or None if the architecture has none."""
        return None

    def derived(self) -> dict[str, Any]:
        """Derived properties (areal density, locking angle, ...), keys carry their units."""
        return {}

    def errors(self) -> list[tuple[Location, str]]:
        """Consistency errors that need the whole entry (matrix size against the repeat, ...),
        each with the path of the field to blame. Single-field errors belong in validators."""
        return []

    def check(self) -> list[tuple[Location, str]]:
        """Warnings about a valid but suspicious entry, each with the field to look at."""
        return []

    def reference_direction_deg(self) -> float:
        """The in-plane direction [deg from the warp/machine direction] bisecting the two fibre
        families, along which positive shear lengthens the fabric: the stitch for a ±45°
        warp-knit; the +45° bisector of warp and weft for a 0/90 fabric."""
        return 0.0

    def default_shear_law(self) -> Any:
        """Shear-law parameters to use when the entry gives no ``shear_law`` block, or None."""
        return None
