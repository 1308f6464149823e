"""The base every fabric architecture's parameter model derives from, and the value checks all
parameter models share.

A library entry is validated into the pydantic model its ``architecture`` tag selects. Models
keep the YAML's datasheet units (the unit is in the field name: ``tow_width_mm``) so that a
model round-trips to the same YAML; physical objects built from a model (unit cells, shear
laws) convert to SI once, when they are built.

Three kinds of value check, from hard to soft:

* **Model layer, always** (``ParamsModel``): a number must be finite (``inf``, ``Infinity``,
  ``nan``, ``1e999`` refused, also when YAML hands them over as text) and must not be a boolean
  (YAML reads ``true``/``yes``/``on`` as booleans and pydantic would take them as 1). Text that
  spells a finite number (``"12"``, and ``1e3``, which YAML 1.1 reads as text because it has no
  dot) is accepted as that number: it is what the user meant, and it still passes every check
  below. Hard physical limits (a width > 0) are ordinary pydantic constraints.
* **Size limits, at the model layer** (``size_limit``): integers that set how much a model
  allocates (tows in a repeat, levels, courses of a lapping notation) are refused above a limit
  before anything is built; ``PREFORM_LIMITS=name=value,...`` raises a limit on purpose.
* **Plausible ranges** (``Plausible``, metadata on a field): a value outside the range of any
  real fabric is almost always a unit mistake. ``plausibility_checks`` walks any validated
  model and the library loader turns every value outside its range into a located error with a
  guess at the unit that was meant, unless the entry lists the field in ``accept_out_of_range``
  (then it is a located warning, and the override is part of the entry's data).
"""

from __future__ import annotations

import functools
import math
import os
import typing
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, model_validator
from pydantic_core import InitErrorDetails, PydanticCustomError, ValidationError

if TYPE_CHECKING:
    from preform.geometry.sheared_cell import ShearedCell
    from preform.geometry.unit_cell import FloatArray, UnitCell

#: Where in an entry a problem is: a path of field names and list indices,
#: e.g. ("weave", "matrix", 2).
Location = tuple[str | int, ...]


# -- the model layer: finite, non-boolean numbers -------------------------------------------------


def _has_numeric_leaf(annotation: Any) -> bool:
    """True when a field annotation holds int or float values somewhere (not bool, not models)."""
    if annotation is bool:
        return False
    if annotation in (int, float):
        return True
    if isinstance(annotation, type):
        return False
    return any(_has_numeric_leaf(arg) for arg in typing.get_args(annotation) if arg is not Ellipsis)


@functools.cache
def _numeric_fields(model: type[BaseModel]) -> frozenset[str]:
    """The fields of a model class whose annotation holds an int or a float: worked out once
    per class, not at every entry validated (the check runs on every nested model)."""
    return frozenset(
        name for name, info in model.model_fields.items() if _has_numeric_leaf(info.annotation)
    )


def _boolean_errors(value: Any, loc: tuple[str | int, ...] = ()) -> Iterator[InitErrorDetails]:
    if isinstance(value, bool):
        yield InitErrorDetails(
            type=PydanticCustomError(
                "bool_not_number",
                "{value} is a boolean, not a number (YAML reads true/false, yes/no and on/off "
                "as booleans); write the number",
                {"value": "true" if value else "false"},
            ),
            loc=loc,
            input=value,
        )
    elif isinstance(value, list | tuple):
        for i, item in enumerate(value):
            yield from _boolean_errors(item, (*loc, i))
    elif isinstance(value, dict):  # dict[str, float]: the values
        for key, item in value.items():
            yield from _boolean_errors(item, (*loc, key))


class ParamsModel(BaseModel):
    """Base of every parameter model of a library entry (fabrics, their parts, shear laws).

    Frozen, unknown keys refused, numbers finite (also when written as text: ``inf``,
    ``Infinity``, ``1e999``) and never booleans, wherever an int or float is expected,
    including inside lists. Derive nested models from it too, so that a boolean deep in an
    entry is refused where it stands.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _no_boolean_numbers(cls, data: Any) -> Any:
        # A model-level "before" check rather than a per-field one: pydantic forbids "before"
        # validators on discriminator fields, and each error still gets its exact location.
        if not isinstance(data, dict):
            return data
        numeric = _numeric_fields(cls)
        errors: list[InitErrorDetails] = []
        for name, value in data.items():
            if name in numeric:
                errors += _boolean_errors(value, (name,))
        if errors:
            raise ValidationError.from_exception_data(cls.__name__, errors)
        return data


# -- size limits ----------------------------------------------------------------------------------

#: Default size limits: name → (largest value, what it counts, why that is enough).
SIZE_LIMITS: dict[str, tuple[int, str, str]] = {
    "weave_repeat": (
        128,
        "tows in one weave repeat (harness, twill over + under, basket group × 2, RC_wp, RC_wt)",
        "the largest satins in use are 12–16 harness; checking a repeat of n tows costs ~n³ "
        "(0.1 s at 128, 0.7 s at 256, minutes at 3000)",
    ),
    "weave_levels": (
        64,
        "levels or layers of a weave",
        "thick 3D weaves have of the order of 10–20 layers",
    ),
    "lapping_courses": (
        64,
        "courses in one repeat of a knitting sequence",
        "atlas laps, the longest common repeats, run over 4–12 courses",
    ),
    "needle_gap": (
        1000,
        "needle-gap number in a knitting sequence",
        "a guide bar shogs a few needle spaces; the numbers name gaps near the origin",
    ),
    "empty_guides": (
        64,
        "empty guides between loaded guides",
        "part-set threading leaves a few guides empty",
    ),
    "tow_layers": (32, "tow layers of a stitch-bonded fabric", "multiaxials have up to 6–8 layers"),
    "thread_levels": (16, "stitching thread levels (guide bars)", "machines have 1–4 guide bars"),
    "placement_row": (
        1000,
        "entries in one row of a placement matrix",
        "one entry per tow across the unit cell",
    ),
    "polynomial_terms": (
        16,
        "coefficients of one shear polynomial",
        "fits of picture-frame curves use 3–7 terms; more only fit noise",
    ),
    "table_points": (
        10_000,
        "points of one tabulated shear curve",
        "a picture-frame test logs a few hundred points",
    ),
}

#: Environment variable raising size limits on purpose: ``name=value`` pairs, comma-separated.
LIMITS_ENV = "PREFORM_LIMITS"


def size_limit_value(name: str) -> int:
    """The active limit ``name``: its default, or the value ``PREFORM_LIMITS`` gives it.

    A malformed ``PREFORM_LIMITS`` raises ValueError naming the problem (a limit silently left at
    its default would be as surprising as one silently dropped)."""
    default = SIZE_LIMITS[name][0]
    raw = os.environ.get(LIMITS_ENV, "").strip()
    if not raw:
        return default
    for item in raw.split(","):
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or key not in SIZE_LIMITS:
            import difflib  # for the message only: off the path of a good listing

            close = difflib.get_close_matches(key, SIZE_LIMITS, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(
                f"{LIMITS_ENV}: {item.strip()!r} is not NAME=VALUE with a known limit{hint}; "
                f"limits: {', '.join(SIZE_LIMITS)}"
            )
        if key == name:
            try:
                value = int(text.strip())
            except ValueError:
                raise ValueError(
                    f"{LIMITS_ENV}: {key} needs a whole number, got {text!r}"
                ) from None
            if value < 1:
                raise ValueError(f"{LIMITS_ENV}: {key} must be at least 1, got {value}")
            return value
    return default


def check_size(name: str, value: int) -> int:
    """``value`` if it is within the size limit ``name``; else a ValueError saying which limit,
    its value, and how to raise it."""
    try:
        limit = size_limit_value(name)
    except ValueError as exc:
        raise PydanticCustomError("size_limit_env", str(exc)) from None
    if value > limit:
        _, what, why = SIZE_LIMITS[name]
        raise PydanticCustomError(
            "size_limit",
            "{value} is above the size limit {name} = {limit} ({what}; {why}); refused before "
            "building anything. To go further on purpose set {env}={name}=N",
            {
                "value": value,
                "name": name,
                "limit": limit,
                "what": what,
                "why": why,
                "env": LIMITS_ENV,
            },
        )
    return value


def size_limit(name: str) -> AfterValidator:
    """Pydantic annotation: ``Annotated[int, Field(ge=1), size_limit("weave_repeat")]``.

    Applied to a list it limits the list's length."""
    if name not in SIZE_LIMITS:
        raise KeyError(f"unknown size limit {name!r}; known: {', '.join(SIZE_LIMITS)}")

    def check(value: Any) -> Any:
        if isinstance(value, int):
            check_size(name, value)
        elif value is not None:
            check_size(name, len(value))
        return value

    return AfterValidator(check)


# -- plausible ranges -----------------------------------------------------------------------------

#: Unit mistakes worth suggesting, per field unit: (unit the user may have meant, how many field
#: units one of them is). A value v written in that unit is v·factor in the field's unit.
UNIT_MISTAKES: dict[str, tuple[tuple[str, float], ...]] = {
    "mm": (("µm", 1e-3), ("m", 1e3), ("cm", 10.0), ("inches", 25.4)),
    "tex": (("dtex", 0.1), ("denier", 1.0 / 9.0), ("g/m (kilotex)", 1e3)),
    "g/cm³": (("kg/m³", 1e-3),),
    "GPa": (("MPa", 1e-3), ("Pa", 1e-9)),
    "N": (("mN", 1e-3), ("kN", 1e3)),
    "deg": (("radians", 180.0 / math.pi),),
    "g/m²": (("kg/m²", 1e3), ("oz/yd²", 33.906)),
    "N/mm": (("N/m", 1e-3),),
    "N·m/m²": (("N·mm/mm²", 1e3),),
    "needles per inch": (("needles per cm", 2.54),),
    "1/GPa": (("1/MPa", 1e3), ("1/Pa", 1e9)),
    "": (("percent", 1e-2),),
}


@dataclass(frozen=True)
class Plausible:
    """Field metadata: the range [low, high] in ``unit`` of any real fabric's value.

    ``what`` names the quantity ("a tow width"), ``reason`` says where the bounds come from.
    On a list of numbers the range applies to each item. ``measure(value, model)`` replaces the
    value by a derived quantity in ``unit`` (e.g. the peak force of a polynomial over its
    fitted range); it returns None when there is nothing to check. Use it as
    ``Field(gt=0, ...)`` plus ``Annotated[float, Plausible(...)]`` or in ``Field``'s metadata::

        width_mm: Annotated[float, Plausible(0.05, 50, "mm", "a tow width", "...")] = Field(gt=0)
    """

    low: float
    high: float
    unit: str
    what: str
    reason: str
    measure: Callable[[Any, Any], float | None] | None = None

    def contains(self, value: float) -> bool:
        return self.low <= value <= self.high

    def unit_hint(self, value: float) -> str | None:
        """The unit the value was probably written in, when reading it so lands in range."""
        for unit, factor in UNIT_MISTAKES.get(self.unit, ()):
            if self.contains(value * factor):
                return unit
        return None

    def describe(self) -> str:
        return f"{self.low:g}–{self.high:g} {self.unit}".rstrip()

    def __get_pydantic_json_schema__(self, core_schema: Any, handler: Any) -> dict[str, Any]:
        # Editors reading `preform schema` see the range next to the field.
        schema: dict[str, Any] = handler(core_schema)
        schema["x-plausible-range"] = {
            "low": self.low,
            "high": self.high,
            "unit": self.unit,
            "of": self.what,
            "why": self.reason,
        }
        return schema


class PlausibilityCheck(NamedTuple):
    """One range-checked value of a validated model: where, what was found, and its range.

    A named tuple, not a frozen dataclass: as immutable and compared by value, without execing
    generated methods at every start-up (issue 15l)."""

    path: Location
    field: str
    value: float
    rule: Plausible

    @property
    def inside(self) -> bool:
        return self.rule.contains(self.value)

    def outside(self) -> str:
        """``width_mm = 3100 is outside the plausible range 0.05–50 mm for a tow width``."""
        rule = self.rule
        shown = f"{self.field} = {self.value:g}"
        if rule.measure is not None:
            shown = f"{self.field} gives {rule.what} of {self.value:g} {rule.unit}".rstrip()
        return f"{shown} is outside the plausible range {rule.describe()} for {rule.what}"

    def message(self, override_path: str) -> str:
        """Why the value is refused, the likely unit mistake, and how to keep it on purpose."""
        rule = self.rule
        text = self.outside()
        hint = rule.unit_hint(self.value)
        if hint:
            text += f"; was it given in {hint}?"
        elif rule.unit:
            text += f"; check the unit ({rule.unit})"
        return (
            f"{text} (range: {rule.reason}). If the value is right, add "
            f"'{override_path}' to this entry's accept_out_of_range"
        )


def _rules(info: Any) -> list[Plausible]:
    return [m for m in getattr(info, "metadata", ()) if isinstance(m, Plausible)]


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def plausibility_checks(model: BaseModel, base: Location = ()) -> list[PlausibilityCheck]:
    """Every value of a validated model (and of the models inside it) that carries a
    ``Plausible`` range, with its path from ``base``; in range or not.

    Generic over any pydantic model: a plugin's architecture or law gets its ranges checked by
    marking its fields, nothing else."""
    out: list[PlausibilityCheck] = []
    for name, rules, may_nest in _checked_fields(type(model)):
        value = getattr(model, name, None)
        where = (*base, name)
        for rule in rules:
            if value is None:
                continue
            if rule.measure is not None:
                measured = rule.measure(value, model)
                if measured is not None:
                    out.append(PlausibilityCheck(where, name, float(measured), rule))
            elif _is_number(value):
                out.append(PlausibilityCheck(where, name, float(value), rule))
            elif isinstance(value, list | tuple):
                out += [
                    PlausibilityCheck((*where, i), f"{name}[{i}]", float(v), rule)
                    for i, v in enumerate(value)
                    if _is_number(v)
                ]
        if may_nest:
            out += _nested_checks(value, where)
    return out


@functools.cache
def _checked_fields(model: type[BaseModel]) -> list[tuple[str, list[Plausible], bool]]:
    """Per field of a model class: its name, its ranges, and whether its value may hold a
    model (whose fields are checked in turn); worked out once per class, so that validating a
    library does not walk every number of a weaving matrix looking for models."""
    return [
        (name, _rules(info), _may_hold_model(info.annotation))
        for name, info in model.model_fields.items()
    ]


def _may_hold_model(annotation: Any) -> bool:
    """False only when the annotation rules a model out (numbers, text, Literal tags and
    containers of them); anything it cannot read (Any, a bare container, a forward reference)
    may hold one."""
    origin = typing.get_origin(annotation)
    if origin is typing.Literal:
        return False
    args = typing.get_args(annotation)
    if origin is typing.Annotated:
        return _may_hold_model(args[0])
    if args:
        return any(_may_hold_model(arg) for arg in args if arg is not Ellipsis)
    if annotation in (int, float, str, bool, bytes, type(None)):
        return False
    if isinstance(annotation, type) and origin is None:
        return issubclass(annotation, BaseModel) or not issubclass(
            annotation, int | float | str | bytes
        )
    return True


def _nested_checks(value: Any, where: Location) -> list[PlausibilityCheck]:
    if isinstance(value, BaseModel):
        return plausibility_checks(value, where)
    if isinstance(value, list | tuple):
        return [c for i, v in enumerate(value) for c in _nested_checks(v, (*where, i))]
    if isinstance(value, dict):
        return [c for k, v in value.items() for c in _nested_checks(v, (*where, str(k)))]
    return []


def plausible_fields(model: type[BaseModel]) -> Iterator[tuple[tuple[str, ...], Plausible]]:
    """Every field of a model class (and of the model classes its fields hold) that carries a
    ``Plausible`` range, as (field names from the class, range). Collections are looked
    through without an index: for the documentation and for generated tests."""
    for name, info in model.model_fields.items():
        for rule in _rules(info):
            yield (name,), rule
        for inner in _model_classes(info.annotation):
            for path, rule in plausible_fields(inner):
                yield (name, *path), rule


def _model_classes(annotation: Any) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found: list[type[BaseModel]] = []
    for arg in typing.get_args(annotation):
        for cls in _model_classes(arg):
            if cls not in found:
                found.append(cls)
    return found


# Ranges shared by architectures (a tow is a tow whatever holds it); reasons in docs/ranges.md.
TOW_LINEAR_DENSITY = Plausible(
    1.0,
    1e5,
    "tex",
    "a tow linear density",
    "finest glass yarns ≈ 5 tex, 1K carbon 66 tex; largest: 50K carbon ≈ 3.5e3 tex, glass "
    "direct rovings ≈ 9.6e3 tex, 400K textile-grade carbon ≈ 3e4 tex",
)
TOW_WIDTH = Plausible(
    0.05,
    50.0,
    "mm",
    "a tow width",
    "fine yarns ≈ 0.2 mm wide; the widest spread-tow tapes ≈ 25–50 mm",
)
TOW_HEIGHT = Plausible(
    0.005,
    5.0,
    "mm",
    "a tow height",
    "spread tows ≈ 0.02 mm thick; heavy rovings ≈ 1 mm",
)
TOW_SPACING = Plausible(
    0.05,
    200.0,
    "mm",
    "a tow spacing",
    "at least a fine tow's width; light transverse tows of quasi-UD fabrics lie tens of mm apart",
)
FIBRE_DENSITY = Plausible(
    0.8,
    20.0,
    "g/cm³",
    "a fibre density",
    "polyethylene 0.97, carbon 1.8, glass 2.55, steel 7.8, tungsten 19.3 g/cm³",
)
FIBRE_MODULUS = Plausible(
    0.5,
    1200.0,
    "GPa",
    "a fibre axial modulus",
    "thermoplastic yarns from ≈ 1 GPa; ultra-high-modulus pitch carbon ≈ 950 GPa",
)
FILAMENT_DIAMETER = Plausible(
    1.0,
    100.0,
    "µm",
    "a filament diameter",
    "carbon filaments ≈ 5–8 µm, glass 9–24 µm, thick polymer monofilaments ≈ 50 µm",
)


class FabricBase(ParamsModel):
    """Fields every fabric entry carries, whatever its architecture.

    Subclasses narrow ``architecture`` to a ``Literal`` naming themselves, add their parameters,
    and override the hooks below that their architecture can answer.
    """

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

    accept_out_of_range: tuple[str, ...] | None = Field(
        default=None,
        description=(
            "Paths of fields (as errors name them: 'tow_types.glass.width_mm', "
            "'shear_law.pretension_N') whose value is deliberately outside its plausible range. "
            "Each is accepted with a warning and recorded with the entry's data."
        ),
    )

    # -- hooks an architecture overrides ---------------------------------------------------
    def unit_cell(self) -> UnitCell | None:
        """The repeating cell of the fabric in SI units, or None if the architecture has none."""
        return None

    def sheared_cell(self, shear_rad: float) -> ShearedCell | None:
        """The unit cell at shear angle ``shear_rad`` [rad] with its thickness and fibre
        fractions (``preform.geometry.sheared_cell``), or None if the architecture has none.
        Raises ValueError, in words, for a cell that cannot be sheared."""
        return None

    def sheared_thickness(self, shear_rad: FloatArray) -> FloatArray | None:
        """Thickness [m] of ``sheared_cell`` at each shear angle [rad] of an array (the
        preform's table), or None if the architecture has none. This default builds one cell
        per angle; an architecture whose stack takes every angle in one pass overrides it."""
        from preform.geometry.sheared_cell import thickness_per_angle

        return thickness_per_angle(self.sheared_cell, shear_rad)

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
