"""The library entry of a warp-knitted (stitch-bonded, NCF) fabric: ``architecture: warp_knit``.

Fields keep the datasheet units named in them (mm, tex, deg, needles per inch) so an entry
round-trips to the same YAML; ``geometry()`` converts to SI once. Optional fields default to
None (not to their meaning) so that ``model_dump(exclude_none=True)`` gives back what was
written.
"""

from __future__ import annotations

import dataclasses
import math
from functools import cached_property
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field, field_validator

from preform.geometry.fibres import FIBRES, fibre
from preform.material import (
    FILAMENT_DIAMETER,
    TOW_HEIGHT,
    TOW_LINEAR_DENSITY,
    TOW_SPACING,
    TOW_WIDTH,
    FabricBase,
    Location,
    ParamsModel,
    Plausible,
    check_size,
    size_limit,
)

from .geometry import ThreadLevel, TowLayer, TowType, WarpKnitGeometry
from .lapping import LappingSyntaxError, parse_lapping

if TYPE_CHECKING:  # annotations only: listing a library never builds a cell
    from preform.geometry.sheared_cell import ShearedCell
    from preform.geometry.unit_cell import FloatArray, UnitCell

MM = 1e-3
#: Relative gap between the derived and the datasheet areal density that ``check`` reports.
AREAL_DENSITY_WARNING = 0.05


def _known_fibre(name: str) -> str:
    if name not in FIBRES:
        raise ValueError(f"unknown fibre {name!r}; known fibres: {', '.join(sorted(FIBRES))}")
    return name


# Ranges of the stitching; reasons in docs/ranges.md.
TOW_OFFSET = Plausible(
    -200.0,
    200.0,
    "mm",
    "a tow offset",
    "an offset past one tow spacing (≤ 200 mm) only repeats the same pattern",
)
OVERLAP_LENGTH = Plausible(
    0.1,
    100.0,
    "mm",
    "a loop (overlap) length",
    "about 2 × stitch length + 2 × fabric thickness: a few mm, ≈ 30 mm for thick multiaxials",
)
STITCH_LENGTH = Plausible(
    0.1,
    50.0,
    "mm",
    "a stitch length",
    "stitch-bonding machines knit courses 1–6 mm apart",
)
GAUGE = Plausible(
    0.5,
    60.0,
    "needles per inch",
    "a machine gauge",
    "warp-knitting machines run from E1.5 to E44 (needles per inch)",
)
NEEDLE_DISTANCE = Plausible(
    0.3,
    60.0,
    "mm",
    "a needle distance",
    "25.4 mm / gauge for gauges E0.5–E60 (0.4–51 mm)",
)
STITCH_LINEAR_DENSITY = Plausible(
    0.5,
    1000.0,
    "tex",
    "a stitching-yarn linear density",
    "stitch yarns are 2–30 tex (76 dtex polyester = 7.6 tex), glass stitching up to ≈ 70 tex",
)
YARN_FAILURE_STRAIN = Plausible(
    0.005,
    1.0,
    "",
    "a stitching yarn's strain at break",
    "polyester filament yarns break at ≈ 0.10–0.35 strain, glass at ≈ 0.03–0.05",
)
YARN_MODULUS = Plausible(
    0.1,
    300.0,
    "GPa",
    "a stitching yarn's tensile modulus",
    "polyester filament ≈ 5–15 GPa, aramid ≈ 60–120 GPa, glass ≈ 72 GPa",
)
AREAL_DENSITY = Plausible(
    5.0,
    20000.0,
    "g/m²",
    "a fabric areal density",
    "the lightest spread-tow NCF ≈ 50 g/m², the heaviest multiaxials ≈ 5000 g/m²",
)


class _Part(ParamsModel):
    pass


class TowLayerEntry(_Part):
    """One layer of parallel, non-interlacing reinforcement tows."""

    orientation_deg: float = Field(
        ge=-180.0,
        le=180.0,
        description="Tow direction [deg] from the stitch (machine) direction towards the "
        "cross direction, e.g. 0, 90, +45, -45.",
    )
    spacing_mm: Annotated[float, TOW_SPACING] = Field(
        gt=0.0,
        description="Centre-to-centre distance between neighbouring tows, normal to them [mm].",
    )
    fibre: str = Field(description="Fibre of the tows: one of preform's known fibres (glass, ...).")
    linear_density_tex: Annotated[float, TOW_LINEAR_DENSITY] = Field(
        gt=0.0, description="Linear density of one tow [tex = g/km]."
    )
    tow_width_mm: Annotated[float, TOW_WIDTH] = Field(
        gt=0.0, description="Tow width in the fabric plane [mm]."
    )
    tow_height_mm: Annotated[float, TOW_HEIGHT] = Field(
        gt=0.0,
        description="Tow height (thickness of one tow as built, in the unit cell) [mm]. The "
        "cell's thickness (derived thickness_mm) stacks these with the stitch threads; the "
        "sheared cell, and the draped preform's thickness, Vf and permeability, start from it.",
    )
    filament_diameter_um: Annotated[float | None, FILAMENT_DIAMETER] = Field(
        default=None,
        gt=0.0,
        description="Filament diameter [µm], for the preform's permeability; default: the "
        "fibre's typical value (illustrative).",
    )
    offset_mm: Annotated[float | None, TOW_OFFSET] = Field(
        default=None,
        description="Normal distance of the first tow's centreline from the cell origin [mm] "
        "(default 0); moves the tows against the needles.",
    )

    _fibre_known = field_validator("fibre")(_known_fibre)


class ThreadLevelEntry(_Part):
    """One level of stitching threads, knitted by one guide bar."""

    knitting_sequence: str = Field(
        description="Lapping notation of the guide bar, course by course: '1-0/0-1' pillar "
        "(chain), '1-0/1-2' tricot, '1-0/2-3' cord, '1-0/3-4' satin; may end in '/' or '//'.",
    )
    overlap_length_mm: Annotated[float, OVERLAP_LENGTH] = Field(
        gt=0.0,
        description="Thread length of one loop (overlap), from leaving the underlap plane "
        "through the stack, round the needle and back [mm].",
    )
    stitch_length_mm: Annotated[float, STITCH_LENGTH] = Field(
        gt=0.0, description="Course spacing (stitch length) along the machine direction [mm]."
    )
    gauge_needles_per_inch: Annotated[float | None, GAUGE] = Field(
        default=None,
        gt=0.0,
        description="Machine gauge E [needles per inch]; the needle distance is 25.4 mm / E. "
        "Give this, needle_distance_mm, or both (they must agree).",
    )
    needle_distance_mm: Annotated[float | None, NEEDLE_DISTANCE] = Field(
        default=None, gt=0.0, description="Distance between adjacent needles D [mm]."
    )
    empty_guides: Annotated[int | None, size_limit("empty_guides")] = Field(
        default=None,
        ge=0,
        description="Empty guides between two loaded guides (default 0: fully threaded).",
    )
    linear_density_tex: Annotated[float, STITCH_LINEAR_DENSITY] = Field(
        gt=0.0, description="Linear density of the stitching yarn [tex = g/km] (76 dtex = 7.6 tex)."
    )
    fibre: str | None = Field(
        default=None, description="Fibre of the stitching yarn (default polyester)."
    )
    failure_strain: Annotated[float | None, YARN_FAILURE_STRAIN] = Field(
        default=None,
        gt=0.0,
        description="Tensile strain at break of the stitching yarn [-] (the stitch_yarn law "
        "breaks the stitch there); none: the law needs it in its own block.",
    )
    yarn_modulus_GPa: Annotated[float | None, YARN_MODULUS] = Field(
        default=None,
        gt=0.0,
        description="Tensile modulus of the stitching yarn [GPa], linear to break; default the "
        "fibre's modulus (polyester 10 GPa).",
    )

    @field_validator("knitting_sequence")
    @classmethod
    def _sequence_parses(cls, text: str) -> str:
        # Courses are counted before parsing so that a huge sequence is refused unread.
        check_size("lapping_courses", text.rstrip("/ \t").count("/") + 1)
        try:
            sequence = parse_lapping(text)
        except LappingSyntaxError as err:
            raise ValueError(
                f"{err.message} at character {err.position + 1}\n{err.caret_diagram()}"
            ) from None
        low, high = sequence.gap_span
        check_size("needle_gap", max(abs(low), abs(high)))
        return text

    @field_validator("fibre")
    @classmethod
    def _fibre_known(cls, name: str | None) -> str | None:
        return None if name is None else _known_fibre(name)


PlacementEntry = Annotated[int, Field(ge=0)]
PlacementRow = Annotated[tuple[PlacementEntry, ...], size_limit("placement_row")]


class WarpKnitFabric(FabricBase):
    """A warp-knitted / stitch-bonded (non-crimp) fabric: tow layers held by stitching threads
    (PHYSICS §1.2). The stitch (machine) direction is the reference for signed shear."""

    architecture: Literal["warp_knit"] = Field(
        description="Warp-knitted / stitch-bonded (NCF) fabric."
    )
    tow_layers: Annotated[tuple[TowLayerEntry, ...], size_limit("tow_layers")] = Field(
        description="Tow layers from the technical face (loop side) to the back."
    )
    threads: Annotated[tuple[ThreadLevelEntry, ...], size_limit("thread_levels")] = Field(
        description="Thread levels, one per guide bar, numbered from 1; their underlaps stack "
        "in this order from the face towards the back.",
    )
    placement: Annotated[tuple[PlacementRow, ...] | None, size_limit("tow_layers")] = Field(
        default=None,
        description="Placement matrix: one row per tow layer giving, for its tows in order "
        "across the cell, the thread level (from 1) of the first underlap above the tow; a row "
        "shorter than the layer repeats. 0 means no underlap above. Default: every tow under "
        "thread level 1.",
    )
    nominal_areal_density_g_m2: Annotated[float | None, AREAL_DENSITY] = Field(
        default=None,
        gt=0.0,
        description="Datasheet areal density including the stitch yarn [g/m²], checked against "
        "the derived value.",
    )

    # -- conversion -------------------------------------------------------------------------
    @cached_property
    def geometry(self) -> WarpKnitGeometry:
        """The fabric as the SI geometric model."""
        layers = tuple(
            TowLayer(
                orientation_deg=t.orientation_deg,
                spacing=t.spacing_mm * MM,
                tow=TowType(
                    fibre=t.fibre,
                    linear_density_tex=t.linear_density_tex,
                    width=t.tow_width_mm * MM,
                    height=t.tow_height_mm * MM,
                    filament_diameter=None
                    if t.filament_diameter_um is None
                    else t.filament_diameter_um * 1e-6,
                ),
                offset=(t.offset_mm or 0.0) * MM,
            )
            for t in self.tow_layers
        )
        levels = tuple(
            ThreadLevel(
                sequence=parse_lapping(t.knitting_sequence),
                overlap_length=t.overlap_length_mm * MM,
                stitch_length=t.stitch_length_mm * MM,
                linear_density_tex=t.linear_density_tex,
                needle_distance=None if t.needle_distance_mm is None else t.needle_distance_mm * MM,
                gauge_needles_per_inch=t.gauge_needles_per_inch,
                empty_guides=t.empty_guides or 0,
                fibre=t.fibre or "polyester",
            )
            for t in self.threads
        )
        return WarpKnitGeometry(tow_layers=layers, thread_levels=levels, placement=self.placement)

    # -- FabricBase hooks -------------------------------------------------------------------
    def unit_cell(self) -> UnitCell:
        """The repeating cell in metres (x = stitch direction); raises ValueError on an entry
        with errors."""
        cell = self._checked_geometry().unit_cell()
        return dataclasses.replace(
            cell, reference_direction=math.radians(self.reference_direction_deg())
        )

    def sheared_cell(self, shear_rad: float) -> ShearedCell:
        """The cell at shear angle ``shear_rad`` [rad] about the reference direction
        (``sheared_warp_knit_cell``); raises ValueError on an entry with errors."""
        from preform.plugins.warpknit.sheared_cell import sheared_warp_knit_cell

        geometry = self._checked_geometry()
        return sheared_warp_knit_cell(geometry, shear_rad, self.reference_direction_deg())

    def sheared_thickness(self, shear_rad: FloatArray) -> FloatArray:
        """Thickness [m] of the sheared cell at each angle [rad] of an array, every angle's
        stack in one pass (``sheared_stack``, the same stack ``sheared_cell`` builds); raises
        ValueError on an entry with errors."""
        from preform.plugins.warpknit.sheared_cell import sheared_stack

        geometry = self._checked_geometry()
        return sheared_stack(geometry, shear_rad, self.reference_direction_deg())[2]

    def _checked_geometry(self) -> WarpKnitGeometry:
        """``geometry``; raises ValueError naming the entry's first error."""
        problems = self.errors()
        if problems:
            loc, message = problems[0]
            raise ValueError(f"{'.'.join(map(str, loc))}: {message}")
        return self.geometry

    def derived(self) -> dict[str, Any]:
        """Areal densities [g/m²], stitch direction [deg], cell size and thickness [mm], tow
        fibre volume fractions [-] (elliptical tow section) and each level's stitch."""
        if self.errors():
            return {"stitch_direction_deg": 0.0}
        geo = self.geometry
        layers = [t.areal_density_g_m2 for t in geo.tow_layers]
        stitch = [geo.stitch_areal_density_g_m2(k) for k in range(len(geo.thread_levels))]
        length, width = geo.cell_fit.size
        return {
            "areal_density_g_m2": sum(layers) + sum(stitch),
            "areal_density_layers_g_m2": layers,
            "areal_density_stitch_g_m2": sum(stitch),
            "areal_density_stitch_levels_g_m2": stitch,
            "stitch_direction_deg": 0.0,  # the machine direction, x of the cell
            "reference_direction_deg": self.reference_direction_deg(),
            "stitch": [t.sequence.describe() for t in geo.thread_levels],
            "needle_distance_mm": [t.needle_pitch / MM for t in geo.thread_levels],
            "thickness_mm": geo.thickness / MM,
            "unit_cell_mm": [length / MM, width / MM],
            "tow_fibre_volume_fraction_layers": [
                t.tow.linear_density_tex
                / (1000.0 * fibre(t.tow.fibre).density_g_cm3)
                * 1e-6
                / (math.pi / 4.0 * t.tow.width * t.tow.height)
                for t in geo.tow_layers
            ],
        }

    def errors(self) -> list[tuple[Location, str]]:
        """Placement, machine (gauge, needle distance, stitch length) and loop-length errors;
        a thread without the strain at break the ``stitch_yarn`` law needs."""
        problems = list(self.geometry.problems())
        law = self.shear_law
        if getattr(law, "law", None) == "stitch_yarn" and (
            getattr(law, "yarn_failure_strain", None) is None
        ):
            problems += [
                (
                    ("threads", k, "failure_strain"),
                    "the stitch_yarn shear law needs the stitching yarn's strain at break: give "
                    "failure_strain here (regular polyester filament ≈ 0.2–0.3) or "
                    "yarn_failure_strain in the shear_law",
                )
                for k, thread in enumerate(self.threads)
                if thread.failure_strain is None
            ]
        return problems

    def check(self) -> list[tuple[Location, str]]:
        """Warnings: tows no stitch crosses, cells that fit poorly, wide overlaps, and a
        derived areal density more than 5 % from the datasheet's."""
        if self.errors():
            return []
        out = self.geometry.warnings()
        if self.nominal_areal_density_g_m2 is not None:
            derived = self.geometry.areal_density_g_m2()
            nominal = self.nominal_areal_density_g_m2
            if abs(derived / nominal - 1.0) > AREAL_DENSITY_WARNING:
                out.append(
                    (
                        ("nominal_areal_density_g_m2",),
                        f"the layers and stitch give {derived:.4g} g/m², "
                        f"{100 * (derived / nominal - 1):+.1f} % from the datasheet's {nominal:g}",
                    )
                )
        return out

    def reference_direction_deg(self) -> float:
        """The bisector [deg] of the two fibre families along which positive shear lengthens
        the fabric. For ±θ layers the stitch (machine direction, 0°) bisects them: positive
        shear is then "parallel" shear, stitch in tension. When the stitch runs along a fibre
        family (0/90 layers) no bisector is the stitch and shear does not stretch it to first
        order: the reference is then the bisector of the first two layers (45° for 0/90)."""
        if len(self.tow_layers) < 2:
            return 0.0
        first, second = (layer.orientation_deg for layer in self.tow_layers[:2])
        if abs(first + second) < 1e-9:  # ±θ about the stitch
            return 0.0
        return 0.5 * (first + second)
