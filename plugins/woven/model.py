"""The woven fabric library entry: ``architecture: woven`` (datasheet units in field names).

An entry names its tow types, gives the warp-wise and weft-wise tow sets (spacing and which
tow type sits on which level and tow), and a weave: either a generator with its parameters
(``weave: {pattern: satin, harness: 5, move: 2}``) or the explicit general description
(``pattern: general`` with levels and the weaving matrix, PHYSICS §1.1)::

    tow_types:
      glass-1190: {fibre: glass, linear_density_tex: 1190, width_mm: 3.1, height_mm: 0.32}
    warp: {tow_spacing_mm: 4.0, tow_type: glass-1190}
    weft: {tow_spacing_mm: 4.0, tow_type: glass-1190}
    weave: {pattern: plain}

``tow_type`` is one name (every tow of every level of that direction), or a list with one item
per level of that direction (levels in id order: for generated 3D weaves stuffers, then
binders), each item a name or a list of names, one per tow of the repeat (hybrids).
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field, ValidationInfo, field_validator

from preform.geometry.fibres import FIBRES, Fibre
from preform.material import (
    FIBRE_DENSITY,
    FIBRE_MODULUS,
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
from preform.plugins.woven import weaves
from preform.plugins.woven.geometry import TowType, WeaveDescription, WovenUnitCell
from preform.plugins.woven.tow_jamming import (
    DEFAULT_CONFINING_PRESSURE_PA,
    FIBRE_COMPACTION_SOURCE,
    TowCompaction,
    compaction_for,
)

if TYPE_CHECKING:  # annotations only: listing a library never builds a cell
    from preform.geometry.sheared_cell import ShearedCell
    from preform.geometry.unit_cell import FloatArray, UnitCell
    from preform.plugins.woven.crossover import CrossoverGeometry

TowTypeAssignment = str | tuple[str | tuple[str, ...], ...]


#: Tows in one repeat of a generated weave (harness, over/under, group): a repeat of n tows
#: builds an n × n weaving matrix, so the size is limited before anything is built.
RepeatCount = Annotated[int, Field(ge=1), size_limit("weave_repeat")]
#: Layers or levels of a weave.
LayerCount = Annotated[int, size_limit("weave_levels")]


#: Hexagonal packing of round fibres, π/(2√3): no fibre fraction can exceed it.
HEXAGONAL_PACKING = math.pi / (2.0 * math.sqrt(3.0))
MAX_FRACTION = Plausible(
    0.3,
    HEXAGONAL_PACKING,
    "",
    "a maximum attainable fibre fraction",
    "square packing π/4 ≈ 0.785 to hexagonal π/(2√3) ≈ 0.907 (Gutowski's V_a ≈ 0.75–0.85)",
)
WAVE_RATIO = Plausible(
    1.0,
    1e4,
    "",
    "Gutowski's fibre-wave ratio β",
    "350 fitted to AS4 carbon beds (Gutowski 1987); A_s goes as β⁻⁴",
)
COUPLING = Plausible(
    0.0,
    100.0,
    "1/GPa",
    "the Cai–Gutowski coupling compliance",
    "a fibre bed's compliances are ≈ 1/E_f ≈ 0.004–0.1 /GPa",
)
CONFINING_PRESSURE = Plausible(
    0.0,
    2000.0,
    "kPa",
    "a through-thickness pressure on a dry preform",
    "hand lay-up ≈ 0, vacuum bag ≈ 100 kPa, RTM and press forming up to ≈ 1–2 MPa",
)


class TowCompactionEntry(ParamsModel):
    """How a tow compacts laterally when sheared fabric squeezes it (``tow_types.*.compaction``).

    One model for the sheared unit cell and the woven shear law (docs/physics.md, "One tow"):
    the tow compacts at constant height under Gutowski's law until its lateral stress reaches
    the confining pressure, its floats nest further, and past the weave's jamming fraction it
    jams (the cell thickens, the law holds its torque: the fabric wrinkles). Every field
    defaults to the fibre family's value (``preform.plugins.woven.tow_jamming``), with its
    source.
    """

    fibre_wave_ratio: Annotated[float | None, WAVE_RATIO] = Field(
        default=None,
        gt=0.0,
        description="Gutowski β [-], span-to-height ratio of fibre waves, A_s = 3πE_f/β⁴; "
        "default: the fibre family's (350, Gutowski 1987, AS4 carbon; illustrative for glass).",
    )
    max_volume_fraction: Annotated[float | None, MAX_FRACTION] = Field(
        default=None,
        gt=0.0,
        lt=1.0,
        description="Gutowski V_a [-], the maximum attainable fibre fraction; default π/4 "
        "(square packing).",
    )
    coupling_compliance_per_GPa: Annotated[float | None, COUPLING] = Field(
        default=None,
        ge=0.0,
        description="Cai–Gutowski F_bl [1/GPa]; 0 reduces the bundle stress to Gutowski's [C].",
    )
    confining_pressure_kPa: Annotated[float | None, CONFINING_PRESSURE] = Field(
        default=None,
        gt=0.0,
        description="Through-thickness pressure holding the tow flat [kPa]: where the tow's "
        "lateral stress reaches it, the tow stops compacting at its interlacings. Default "
        f"{DEFAULT_CONFINING_PRESSURE_PA * 1e-3:g} kPa, a vacuum-bagged preform [C].",
    )

    def settings(self, fibre_name: str) -> TowCompaction:
        """The SI constants, the fibre family's defaults where a field is not given."""
        base = compaction_for(fibre_name)
        pressure = self.confining_pressure_kPa
        coupling = self.coupling_compliance_per_GPa
        return TowCompaction(
            confining_pressure_Pa=base.confining_pressure_Pa
            if pressure is None
            else pressure * 1e3,
            fibre_wave_ratio=self.fibre_wave_ratio or base.fibre_wave_ratio,
            max_fraction=self.max_volume_fraction or base.max_fraction,
            packing_margin=base.packing_margin,
            coupling_compliance=base.coupling_compliance if coupling is None else coupling * 1e-9,
        )


class TowTypeEntry(ParamsModel):
    """One named kind of tow (datasheet units)."""

    fibre: str = Field(description=f"Fibre material, one of: {', '.join(sorted(FIBRES))}.")
    linear_density_tex: Annotated[float, TOW_LINEAR_DENSITY] = Field(
        gt=0, description="Linear density of the tow [tex = g/km]."
    )
    width_mm: Annotated[float, TOW_WIDTH] = Field(
        gt=0, description="Tow width in the fabric plane [mm] (Tw0)."
    )
    height_mm: Annotated[float, TOW_HEIGHT] = Field(
        gt=0,
        description="Tow height (thickness of one tow as built, in the unit cell) [mm]. The "
        "cell's thickness (derived thickness_mm) stacks these with the crimp; the sheared "
        "cell, and the draped preform's thickness, Vf and permeability, start from it. Not "
        "the shear law's fabric_thickness_mm, a free (uncompressed) thickness fitted to shear "
        "data.",
    )
    fibre_density_g_cm3: Annotated[float | None, FIBRE_DENSITY] = Field(
        default=None,
        gt=0,
        description="Fibre density [g/cm³]; default: the fibre's handbook value.",
    )
    fibre_modulus_GPa: Annotated[float | None, FIBRE_MODULUS] = Field(
        default=None, gt=0, description="Fibre axial modulus [GPa]; default: the fibre's value."
    )
    filament_diameter_um: Annotated[float | None, FILAMENT_DIAMETER] = Field(
        default=None,
        gt=0,
        description="Filament diameter [µm], for the preform's permeability; default: the "
        "fibre's typical value (illustrative).",
    )
    compaction: TowCompactionEntry | None = Field(
        default=None,
        description="How the tow compacts laterally under shear (one model for the sheared "
        "cell and the shear law); defaults by fibre family, each with its source: "
        + "; ".join(f"{k}: {v}" for k, v in sorted(FIBRE_COMPACTION_SOURCE.items())),
    )

    @field_validator("fibre")
    @classmethod
    def _known_fibre(cls, value: str) -> str:
        if value not in FIBRES:
            raise ValueError(f"unknown fibre {value!r}; known fibres: {', '.join(sorted(FIBRES))}")
        return value

    def tow_type(self, name: str) -> TowType:
        """The SI tow type of this entry."""
        base = FIBRES[self.fibre]
        fibre = Fibre(
            base.name,
            self.fibre_density_g_cm3 or base.density_g_cm3,
            self.fibre_modulus_GPa * 1e9 if self.fibre_modulus_GPa else base.modulus_Pa,
            self.filament_diameter_um * 1e-6
            if self.filament_diameter_um
            else base.filament_diameter_m,
        )
        return TowType(
            name=name,
            fibre=fibre,
            linear_density_tex=self.linear_density_tex,
            width=self.width_mm * 1e-3,
            height=self.height_mm * 1e-3,
            compaction=(self.compaction or TowCompactionEntry()).settings(self.fibre),
        )


def _check_assignment(value: TowTypeAssignment) -> TowTypeAssignment:
    if isinstance(value, str):
        if not value:
            raise ValueError("tow type name is empty")
        return value
    if not value:
        raise ValueError("give a tow type name or a non-empty list, one item per level")
    for item in value:
        if not item or (not isinstance(item, str) and not all(item)):
            raise ValueError("empty tow type name or list in the per-level assignment")
    return value


class TowSet(ParamsModel):
    """The weft-wise tows: spacing and tow types."""

    tow_spacing_mm: Annotated[float, TOW_SPACING] = Field(
        gt=0, description="Centre-to-centre distance between neighbouring tows [mm] (Ts)."
    )
    tow_type: TowTypeAssignment = Field(
        description=(
            "Tow type name for every tow, or a list with one item per level of this direction "
            "(in level-id order), each a name or a list of names, one per tow of the repeat."
        )
    )

    _tow_type = field_validator("tow_type")(_check_assignment)


class WarpTowSet(TowSet):
    """The warp-wise tows (stuffers and binders of a 3D weave): spacing and tow types."""

    binder_tow_type: str | None = Field(
        default=None,
        min_length=1,
        description=(
            "Tow type of the binder levels of a 3D weave, when tow_type is a single name for "
            "the stuffers."
        ),
    )


# -- weaves --------------------------------------------------------------------------------
class PlainWeave(ParamsModel):
    """Plain weave (2 × 2 repeat)."""

    pattern: Literal["plain"] = Field(description="Plain weave.")

    def description(self) -> WeaveDescription:
        return weaves.plain()


class TwillWeave(ParamsModel):
    """over/under twill: warp over ``over`` weft tows, then under ``under``, shifted by one."""

    pattern: Literal["twill"] = Field(description="Twill weave.")
    over: RepeatCount = Field(description="Weft tows each warp tow passes over per repeat.")
    under: RepeatCount = Field(description="Weft tows each warp tow passes under per repeat.")

    @field_validator("under")
    @classmethod
    def _repeat_in_limit(cls, value: int, info: ValidationInfo) -> int:
        over = info.data.get("over")
        if over is not None:
            check_size("weave_repeat", over + value)  # the repeat is over + under tows
        return value

    def description(self) -> WeaveDescription:
        return weaves.twill(self.over, self.under)


class SatinWeave(ParamsModel):
    """Regular warp-faced satin: warp i under only at weft (move·i) mod harness."""

    pattern: Literal["satin"] = Field(description="Regular n-harness satin.")
    harness: Annotated[int, size_limit("weave_repeat")] = Field(
        description="Harness number n (repeat n × n), at least 5."
    )
    move: int = Field(description="Move number m: 1 < m < n − 1 and gcd(m, n) = 1.")

    @field_validator("harness")
    @classmethod
    def _regular_harness(cls, value: int) -> int:
        if value < 5:
            hint = "; use pattern: crowfoot for the 4-harness satin" if value == 4 else ""
            raise ValueError(f"a regular satin needs at least 5 harnesses, got {value}{hint}")
        return value

    @field_validator("move")
    @classmethod
    def _regular_move(cls, value: int, info: ValidationInfo) -> int:
        harness = info.data.get("harness")
        if harness is not None:
            problem = weaves.satin_move_problem(harness, value)
            if problem:
                raise ValueError(problem)
        return value

    def description(self) -> WeaveDescription:
        return weaves.satin(self.harness, self.move)


class CrowfootWeave(ParamsModel):
    """Four-harness satin (crowfoot), irregular: unders in the order 0, 1, 3, 2."""

    pattern: Literal["crowfoot"] = Field(description="Four-harness (crowfoot) satin.")

    def description(self) -> WeaveDescription:
        return weaves.crowfoot()


class BasketWeave(ParamsModel):
    """Basket weave: a plain weave of groups of tows."""

    pattern: Literal["basket"] = Field(description="Basket weave.")
    warp_group: RepeatCount = Field(description="Warp tows woven together as one.")
    weft_group: RepeatCount = Field(description="Weft tows woven together as one.")

    @field_validator("warp_group", "weft_group")
    @classmethod
    def _repeat_in_limit(cls, value: int) -> int:
        return check_size("weave_repeat", 2 * value) // 2  # the repeat is two groups

    def description(self) -> WeaveDescription:
        return weaves.basket(self.warp_group, self.weft_group)


def _min_levels(value: int, info: ValidationInfo) -> int:
    stuffers = info.data.get("stuffer_layers")
    if stuffers is not None and stuffers + value < 2:
        raise ValueError("a 3D weave needs more than two levels: add weft or stuffer layers")
    return value


class OrthogonalWeave(ParamsModel):
    """3D orthogonal weave: binders pass straight through the thickness."""

    pattern: Literal["orthogonal"] = Field(description="3D orthogonal weave.")
    stuffer_layers: LayerCount = Field(ge=0, description="Layers of straight warp stuffer tows.")
    weft_layers: LayerCount = Field(ge=1, description="Layers of weft tows.")

    _weft_layers = field_validator("weft_layers")(_min_levels)

    def description(self) -> WeaveDescription:
        return weaves.orthogonal_3d(self.stuffer_layers, self.weft_layers)


class AngleInterlockWeave(ParamsModel):
    """3D angle-interlock weave: binders step diagonally through ``binder_depth`` weft layers."""

    pattern: Literal["angle_interlock"] = Field(description="3D angle-interlock weave.")
    stuffer_layers: LayerCount = Field(ge=0, description="Layers of straight warp stuffer tows.")
    weft_layers: LayerCount = Field(ge=2, description="Layers of weft tows.")
    binder_depth: LayerCount | None = Field(
        default=None,
        description=(
            "Weft layers each binder passes through, 2..weft_layers; default weft_layers "
            "(through-thickness)."
        ),
    )

    @field_validator("binder_depth")
    @classmethod
    def _depth_in_range(cls, value: int | None, info: ValidationInfo) -> int | None:
        layers = info.data.get("weft_layers")
        if value is not None and layers is not None and not 2 <= value <= layers:
            raise ValueError(f"binder_depth must be between 2 and weft_layers ({layers})")
        return value

    def description(self) -> WeaveDescription:
        return weaves.angle_interlock_3d(self.stuffer_layers, self.weft_layers, self.binder_depth)


class LayerToLayerWeave(ParamsModel):
    """3D layer-to-layer angle interlock: each binder ties two neighbouring weft layers."""

    pattern: Literal["layer_to_layer"] = Field(description="3D layer-to-layer weave.")
    stuffer_layers: LayerCount = Field(ge=0, description="Layers of straight warp stuffer tows.")
    weft_layers: LayerCount = Field(ge=2, description="Layers of weft tows.")

    def description(self) -> WeaveDescription:
        return weaves.layer_to_layer_3d(self.stuffer_layers, self.weft_layers)


#: One crossover of a weaving matrix (level ids bottom to top) and one row of crossovers.
_MatrixEntry = Annotated[tuple[int, ...], size_limit("weave_levels")]
_MatrixRow = Annotated[tuple[_MatrixEntry, ...], size_limit("weave_repeat")]


class GeneralWeave(ParamsModel):
    """Explicit description (paper Fig. 1, 2): levels, repeat and weaving matrix."""

    pattern: Literal["general"] = Field(description="Explicit levels and weaving matrix.")
    warp_levels: LayerCount = Field(
        ge=1, description="Number of warp-wise levels L_wp (ids 1..L_wp)."
    )
    weft_levels: LayerCount = Field(
        ge=1, description="Number of weft-wise levels L_wt (ids L_wp+1..L_wp+L_wt)."
    )
    repeat_warp: RepeatCount = Field(description="Warp-wise tows in the repeat (RC_wp).")
    repeat_weft: RepeatCount = Field(description="Weft-wise tows in the repeat (RC_wt).")
    binder_levels: tuple[int, ...] | None = Field(
        default=None, description="Warp-wise level ids whose tows are binders (3D weaves)."
    )
    matrix: Annotated[tuple[_MatrixRow, ...], size_limit("weave_repeat")] = Field(
        min_length=1,
        description=(
            "Weaving matrix, RC_wp rows of RC_wt entries; each entry lists every level id once, "
            "bottom to top, at that crossover (plain weave: [[[2, 1], [1, 2]], [[1, 2], [2, 1]]])."
        ),
    )

    @field_validator("binder_levels")
    @classmethod
    def _distinct_binders(cls, value: tuple[int, ...] | None) -> tuple[int, ...] | None:
        if value is not None and len(set(value)) != len(value):
            raise ValueError("binder levels are listed more than once")
        return value

    def description(self) -> WeaveDescription:
        return WeaveDescription(
            warp_levels=self.warp_levels,
            weft_levels=self.weft_levels,
            repeat_warp=self.repeat_warp,
            repeat_weft=self.repeat_weft,
            matrix=self.matrix,
            binder_levels=self.binder_levels or (),
        )


Weave = Annotated[
    PlainWeave
    | TwillWeave
    | SatinWeave
    | CrowfootWeave
    | BasketWeave
    | OrthogonalWeave
    | AngleInterlockWeave
    | LayerToLayerWeave
    | GeneralWeave,
    Field(discriminator="pattern"),
]


# -- the entry -----------------------------------------------------------------------------
class WovenFabric(FabricBase):
    """A woven fabric (2D or 3D) described by tow types, tow sets and a weave."""

    architecture: Literal["woven"] = Field(description="Woven fabric (2D or 3D weave).")
    tow_types: dict[str, TowTypeEntry] = Field(
        min_length=1, description="Named tow types used by the warp and weft tow sets."
    )
    warp: WarpTowSet = Field(description="Warp-wise tows (along the roll; stuffers and binders).")
    weft: TowSet = Field(description="Weft-wise tows (across the roll).")
    weave: Weave = Field(description="Weave pattern: a generator with parameters or `general`.")

    # -- description -> geometry ----------------------------------------------------------
    @cached_property
    def _weave_description(self) -> WeaveDescription:
        return self.weave.description()

    def _assignment_errors(self) -> list[tuple[Location, str]]:
        """Tow type references and their shape against the weave's levels and repeat."""
        weave = self._weave_description
        errors: list[tuple[Location, str]] = []
        for family, tows, levels, repeat in (
            ("warp", self.warp, weave.warp_levels, weave.repeat_warp),
            ("weft", self.weft, weave.weft_levels, weave.repeat_weft),
        ):
            where: Location = (family, "tow_type")
            if isinstance(tows.tow_type, str):
                if tows.tow_type not in self.tow_types:
                    errors.append((where, self._unknown(tows.tow_type)))
                continue
            if len(tows.tow_type) != levels:
                errors.append(
                    (
                        where,
                        f"{len(tows.tow_type)} item(s) given but the weave has {levels} "
                        f"{family}-wise level(s): give one item per level",
                    )
                )
                continue
            for k, item in enumerate(tows.tow_type):
                names = (item,) if isinstance(item, str) else item
                if not isinstance(item, str) and len(item) != repeat:
                    errors.append(
                        (
                            (*where, k),
                            f"{len(item)} tow type(s) given but the repeat has {repeat} "
                            f"{family}-wise tows",
                        )
                    )
                for n, name in enumerate(names):
                    if name not in self.tow_types:
                        loc = (*where, k) if isinstance(item, str) else (*where, k, n)
                        errors.append((loc, self._unknown(name)))
        binder = self.warp.binder_tow_type
        if binder is not None:
            where = ("warp", "binder_tow_type")
            if not weave.binder_levels:
                errors.append((where, "this weave has no binder levels"))
            elif not isinstance(self.warp.tow_type, str):
                errors.append(
                    (where, "give binder types either here or in the tow_type list, not both")
                )
            elif binder not in self.tow_types:
                errors.append((where, self._unknown(binder)))
        return errors

    def _unknown(self, name: str) -> str:
        return f"unknown tow type {name!r}; defined tow types: {', '.join(sorted(self.tow_types))}"

    def _types_of(self, family: str) -> tuple[tuple[TowType, ...], ...]:
        weave = self._weave_description
        if family == "warp":
            tows: TowSet = self.warp
            levels, repeat = range(1, weave.warp_levels + 1), weave.repeat_warp
        else:
            tows = self.weft
            levels = range(weave.warp_levels + 1, weave.level_count + 1)
            repeat = weave.repeat_weft
        built = {name: entry.tow_type(name) for name, entry in self.tow_types.items()}
        result = []
        for k, level in enumerate(levels):
            if isinstance(tows.tow_type, str):
                name = tows.tow_type
                if level in weave.binder_levels and self.warp.binder_tow_type is not None:
                    name = self.warp.binder_tow_type
                result.append((built[name],) * repeat)
                continue
            item = tows.tow_type[k]
            names = (item,) * repeat if isinstance(item, str) else item
            result.append(tuple(built[n] for n in names))
        return tuple(result)

    @cached_property
    def woven_unit_cell(self) -> WovenUnitCell:
        """The woven geometry in SI units (call only on an entry without ``errors()``)."""
        return WovenUnitCell(
            weave=self._weave_description,
            tow_spacing_warp=self.warp.tow_spacing_mm * 1e-3,
            tow_spacing_weft=self.weft.tow_spacing_mm * 1e-3,
            warp_tow_types=self._types_of("warp"),
            weft_tow_types=self._types_of("weft"),
            labels={"fabric": self.name},
        )

    def _entry_location(self, location: tuple[str | int, ...]) -> Location:
        """Map a geometry issue location onto the YAML field to blame."""
        if location[:1] == ("weave",):
            if not isinstance(self.weave, GeneralWeave):
                return ("weave",)
            if location[1:2] == ("binder_levels",) and self.weave.binder_levels is None:
                return ("weave",)
            return location
        if len(location) >= 4 and location[1] == "tow_types":
            family, _, k, i = location[:4]
            tow_type = self.woven_unit_cell.tow_type_at(str(family), int(k), int(i))
            return ("tow_types", tow_type.name, "width_mm")
        return (location[0], "tow_spacing_mm") if location[1:2] == ("tow_spacing",) else location

    # -- FabricBase hooks -----------------------------------------------------------------
    def errors(self) -> list[tuple[Location, str]]:
        """Cross-field errors: tow type references, matrix size and level ids, missing tows,
        tows that never interlace, unbound 3D levels; each with the field to blame."""
        return list(self._errors)

    @cached_property
    def _errors(self) -> tuple[tuple[Location, str], ...]:
        # Worked out once, like the cell they come from (``check`` and every geometric result
        # ask again): they depend on the tow types, sets and weave only, never the law.
        errors = self._assignment_errors()
        if errors:
            return tuple(errors)
        return tuple((self._entry_location(loc), msg) for loc, msg in self.woven_unit_cell.errors())

    def check(self) -> list[tuple[Location, str]]:
        """Warnings (tows at least as wide as their spacing), one per tow type and direction."""
        if self.errors():
            return []
        seen: set[Location] = set()
        warnings: list[tuple[Location, str]] = []
        for loc, msg in self.woven_unit_cell.warnings():
            where = (*self._entry_location(loc), str(loc[0]))
            if where not in seen:
                seen.add(where)
                warnings.append((where[:-1], msg))
        return warnings

    def _require_valid(self) -> WovenUnitCell:
        errors = self.errors()
        if errors:
            listing = "; ".join(f"{'.'.join(map(str, loc))}: {msg}" for loc, msg in errors)
            raise ValueError(f"woven fabric {self.name!r} is inconsistent: {listing}")
        return self.woven_unit_cell

    def unit_cell(self) -> UnitCell:
        """The repeat as a generic unit cell [m]; x along the warp, reference direction 45°."""
        return self._require_valid().to_unit_cell()

    def sheared_cell(self, shear_rad: float) -> ShearedCell:
        """The woven cell at shear angle ``shear_rad`` [rad] (``sheared_woven_cell``)."""
        from preform.plugins.woven.sheared_cell import sheared_woven_cell

        return sheared_woven_cell(self._require_valid(), shear_rad)

    def sheared_thickness(self, shear_rad: FloatArray) -> FloatArray:
        """Thickness [m] of the sheared cell at each angle [rad] of an array, every angle's
        stack in one pass (``sheared_stack``, the same stack ``sheared_cell`` builds)."""
        from preform.plugins.woven.sheared_cell import sheared_stack

        return sheared_stack(self._require_valid(), shear_rad).thickness

    def crossover_geometry(self) -> CrossoverGeometry:
        """Mean crossover description for the friction–compaction shear law (SI units)."""
        return self._require_valid().crossover_geometry()

    def derived(self) -> dict[str, Any]:
        """Derived properties; keys carry units (``_percent``, ``_deg``, ``_mm``, ``_g_m2``,
        fractions without a unit suffix are dimensionless)."""
        cell = self._require_valid()
        lock_warp = math.degrees(cell.locking_angle("warp"))
        lock_weft = math.degrees(cell.locking_angle("weft"))
        return self._jamming_derived(cell) | {
            "areal_density_g_m2": cell.areal_density(),
            "areal_density_warp_g_m2": cell.areal_density("warp"),
            "areal_density_weft_g_m2": cell.areal_density("weft"),
            "crimp_warp_percent": 100.0 * cell.crimp("warp"),
            "crimp_weft_percent": 100.0 * cell.crimp("weft"),
            "locking_angle_deg": min(lock_warp, lock_weft),
            "locking_angle_warp_deg": lock_warp,
            "locking_angle_weft_deg": lock_weft,
            "tow_volume_fraction_warp": cell.tow_volume_fraction("warp"),
            "tow_volume_fraction_weft": cell.tow_volume_fraction("weft"),
            "fibre_volume_fraction": cell.fibre_volume_fraction(),
            "thickness_mm": cell.thickness() * 1e3,
            "cover_factor": cell.cover_factor(),
            "gap_fraction": 1.0 - cell.cover_factor(),
            "levels": cell.weave.level_count,
            "repeat_warp_tows": cell.weave.repeat_warp,
            "repeat_weft_tows": cell.weave.repeat_weft,
        }

    @staticmethod
    def _jamming_derived(cell: WovenUnitCell) -> dict[str, Any]:
        """The one tow model's jamming per family (first tow type of each; docs/physics.md,
        "Compaction and jamming: one tow"); nothing when a tow cannot exist (said elsewhere)."""
        from preform.plugins.woven.sheared_cell import tow_families

        try:
            families = tow_families(cell)
        except ValueError:
            return {}
        shares = cell.interlaced_shares()
        out: dict[str, Any] = {}
        for family in ("warp", "weft"):
            name, tows = next((k, f) for k, f in families.items() if k[0] == family)
            out[f"jamming_angle_{family}_deg"] = math.degrees(tows.jamming_angle)
            out[f"jamming_fraction_{family}"] = tows.jamming_fraction
            out[f"interlaced_share_{family}"] = shares[name]
        out["jamming_angle_deg"] = min(out["jamming_angle_warp_deg"], out["jamming_angle_weft_deg"])
        return out

    def reference_direction_deg(self) -> float:
        """+45° [deg from the warp]: the bisector of warp and weft."""
        return 45.0
