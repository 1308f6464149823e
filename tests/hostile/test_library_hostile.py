"""Hostile library entries: values no fabric has, and sizes that would exhaust the machine.

Every physical field of every registered architecture and shear law (found from its
``Plausible`` metadata, so a field added later is covered without editing this file) is given a
value far too large, far too small, non-finite in every spelling YAML lets through, and a
boolean; each must come back from the real loader as one located error
``FILE:LINE:COL: fabric.path: message`` naming the field and saying why (and, for a range, the
likely unit mistake). Overrides (``accept_out_of_range``) are accepted with a located warning and
kept in the entry's data; size limits refuse a huge repeat before anything is allocated.

Why: issue 10, items 8 and 9. Before, ``width_mm: inf`` loaded with a warning, ``width_mm: true``
was read as 1 mm, a 3100 mm tow and an 11.9e6 tex tow ran every scene to "ok", a polynomial law
negative inside its fitted range was accepted, and ``harness: 3001`` took minutes and
gigabytes to validate.
"""

from __future__ import annotations

import copy
import math
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import annotated_types
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from preform.library import bundled_library_dir, load_library, validate_files
from preform.material import LIMITS_ENV, SIZE_LIMITS, Plausible, plausible_fields
from preform.testing import PluginSandbox
from preform.validation import format_path

#: CPU seconds of this process (not wall time, which a loaded machine inflates) within which
#: an oversized input must be refused: the guard is against building it first (minutes,
#: gigabytes), not a speed target.
REFUSAL_CPU_S = 2.0

MARK = "__HOSTILE_VALUE__"

# -- base entries: every optional physical field given, all values inside their ranges --------

WOVEN: dict[str, Any] = {
    "name": "hostile-woven",
    "architecture": "woven",
    "source": "test",
    "note": "every optional field given",
    "tow_types": {
        "glass": {
            "fibre": "glass",
            "linear_density_tex": 1190.0,
            "width_mm": 3.1,
            "height_mm": 0.32,
            "fibre_density_g_cm3": 2.55,
            "fibre_modulus_GPa": 72.0,
            "filament_diameter_um": 17.0,
            "compaction": {
                "fibre_wave_ratio": 350.0,
                "max_volume_fraction": 0.785,
                "coupling_compliance_per_GPa": 0.01,
                "confining_pressure_kPa": 100.0,
            },
        }
    },
    "warp": {"tow_spacing_mm": 4.0, "tow_type": "glass"},
    "weft": {"tow_spacing_mm": 4.0, "tow_type": "glass"},
    "weave": {"pattern": "plain"},
    "shear_law": {
        "law": "friction_compaction",
        "friction_coefficient": 0.3,
        "pretension_N": 100.0,
        "fabric_thickness_mm": 2.0,
        "pretension_width_mm": 150.0,
    },
}

WARP_KNIT: dict[str, Any] = {
    "name": "hostile-knit",
    "architecture": "warp_knit",
    "source": "test",
    "note": "every optional field given",
    "nominal_areal_density_g_m2": 936.0,
    "tow_layers": [
        {
            "orientation_deg": 45.0,
            "spacing_mm": 2.58,
            "fibre": "glass",
            "linear_density_tex": 1200.0,
            "tow_width_mm": 2.58,
            "tow_height_mm": 0.39,
            "offset_mm": 0.5,
            "filament_diameter_um": 17.0,
        },
        {
            "orientation_deg": -45.0,
            "spacing_mm": 2.58,
            "fibre": "glass",
            "linear_density_tex": 1200.0,
            "tow_width_mm": 2.58,
            "tow_height_mm": 0.39,
        },
    ],
    "threads": [
        {
            "knitting_sequence": "1-0/1-2",
            "overlap_length_mm": 7.0,
            "stitch_length_mm": 2.5,
            "gauge_needles_per_inch": 5.0,
            "needle_distance_mm": 5.08,
            "linear_density_tex": 7.6,
            "fibre": "polyester",
            "failure_strain": 0.25,
            "yarn_modulus_GPa": 10.0,
        }
    ],
    "placement": [[1], [1]],
    "shear_law": {
        "law": "stitch_polynomial",
        "parallel_force_coefficients_N_per_mm": [0.0, 4.0e-3, 9.0e-5],
        "perpendicular_force_coefficients_N_per_mm": [0.0, 3.0e-4, 1.0e-5],
        "failure_angle_deg": 35.0,
        "failure_width_deg": 5.0,
        "post_failure_force_coefficients_N_per_mm": [0.03, 0.0, 0.0, 1.0e-6],
        "max_angle_deg": 60.0,
        "max_angle_perpendicular_deg": 50.0,
        "locking_angle_deg": 55.0,
        "beyond_range": "hold",
    },
}


def with_law(name: str, law: dict[str, Any]) -> dict[str, Any]:
    entry = copy.deepcopy(WOVEN)
    entry["name"] = name
    entry["shear_law"] = law
    return entry


#: One entry per registered model variant, so every marked field is present in some entry.
BASES: dict[str, dict[str, Any]] = {
    "woven": WOVEN,
    "warp_knit": WARP_KNIT,
    "polynomial-force": with_law(
        "hostile-poly-force",
        {
            "law": "polynomial",
            "force_coefficients_N_per_mm": [0.0, 1.2e-3, 2.5e-5],
            "force_coefficients_negative_N_per_mm": [0.0, 1.0e-3],
            "max_angle_deg": 60.0,
            "max_angle_negative_deg": 50.0,
            "locking_angle_deg": 50.0,
            "failure_angle_deg": 35.0,
        },
    ),
    "polynomial-torque": with_law(
        "hostile-poly-torque",
        {
            "law": "polynomial",
            "torque_coefficients_N_per_m": [0.0, 1.0, 0.02],
            "torque_coefficients_negative_N_per_m": [0.0, 0.5],
            "max_angle_deg": 60.0,
        },
    ),
    "tabulated-force": with_law(
        "hostile-table-force",
        {
            "law": "tabulated",
            "angle_deg": [0.0, 20.0, 40.0, 60.0],
            "force_N_per_mm": [0.0, 0.05, 0.2, 0.8],
            "angle_negative_deg": [0.0, 30.0, 60.0],
            "force_negative_N_per_mm": [0.0, 0.02, 0.1],
            "locking_angle_deg": 50.0,
            "failure_angle_deg": 35.0,
        },
    ),
    "tabulated-torque": with_law(
        "hostile-table-torque",
        {
            "law": "tabulated",
            "angle_deg": [0.0, 30.0, 60.0],
            "torque_N_per_m": [0.0, 30.0, 100.0],
            "angle_negative_deg": [0.0, 60.0],
            "torque_negative_N_per_m": [0.0, 50.0],
        },
    ),
    "stitch-yarn": {
        **copy.deepcopy(WARP_KNIT),
        "name": "hostile-stitch-yarn",
        "shear_law": {
            "law": "stitch_yarn",
            "ply_friction_coefficient": 0.3,
            "yarn_failure_strain": 0.25,
        },
    },
}


@pytest.fixture
def sandbox(preform_plugins: PluginSandbox) -> PluginSandbox:
    preform_plugins.load_builtins()
    return preform_plugins


def _builtin_registry() -> Any:
    """A registry with only the built-in plugins, for generating cases at collection time."""
    sandbox = PluginSandbox()
    sandbox.load_builtins()
    return sandbox.registry


# -- writing an entry with one value replaced, and finding where it stands --------------------


def set_at(entry: dict[str, Any], path: tuple[str | int, ...], value: Any) -> dict[str, Any]:
    out = copy.deepcopy(entry)
    node: Any = out
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value
    return out


@dataclass(frozen=True)
class Written:
    """A library file with one hostile value: where it is, and the fabric's name."""

    file: Path
    line: int
    column: int
    name: str


def write_entry(tmp_path: Path, entry: dict[str, Any], raw: str | None = None) -> Written:
    """Dump ``[entry]``; the value ``MARK`` (if any) is replaced by the raw YAML text ``raw``
    and its 1-based line and column are returned."""
    text = yaml.safe_dump([entry], sort_keys=False, allow_unicode=True)
    line = column = 0
    if raw is not None:
        for number, content in enumerate(text.splitlines(), start=1):
            at = content.find(MARK)
            if at >= 0:
                line, column = number, at + 1
                break
        assert line, "the marker was not written"
        text = text.replace(f"'{MARK}'", raw).replace(MARK, raw)
    path = tmp_path / "fabrics.yaml"
    path.write_text(text, encoding="utf-8")
    return Written(path, line, column, str(entry["name"]))


def load_errors(sandbox: PluginSandbox, written: Written) -> tuple[list[str], list[str]]:
    _, errors, warnings = validate_files([written.file], sandbox.registry)
    return [str(e) for e in errors], [str(w) for w in warnings]


def assert_one_located(errors: list[str], written: Written, label: str, *words: str) -> str:
    """Exactly one error, at the written value, naming ``label``, containing ``words``."""
    assert len(errors) == 1, errors
    prefix = f"{written.file}:{written.line}:{written.column}: {label}: "
    assert errors[0].startswith(prefix), (errors[0], prefix)
    for word in words:
        assert word in errors[0], (word, errors[0])
    assert "Traceback" not in errors[0]
    return errors[0]


# -- generated cases ---------------------------------------------------------------------------


@dataclass(frozen=True)
class FieldCase:
    """One range-checked value of one base entry."""

    base: str
    path: tuple[str | int, ...]
    field: str
    rule: Plausible
    hard_low: float | None
    hard_high: float | None

    @property
    def id(self) -> str:
        return f"{self.base}:{format_path(self.path)}"


def _hard_bounds(model_cls: Any, name: str) -> tuple[float | None, float | None]:
    low = high = None
    for meta in model_cls.model_fields[name].metadata:
        if isinstance(meta, annotated_types.Gt | annotated_types.Ge):
            low = float(meta.gt if isinstance(meta, annotated_types.Gt) else meta.ge)
        if isinstance(meta, annotated_types.Lt | annotated_types.Le):
            high = float(meta.lt if isinstance(meta, annotated_types.Lt) else meta.le)
    return low, high


def _owner(model: Any, path: tuple[str | int, ...]) -> Any:
    """The model instance holding the last field of ``path``."""
    node = model
    for part in path[:-1]:
        node = (
            node[part] if isinstance(part, int) or isinstance(node, dict) else getattr(node, part)
        )
    return node


def field_cases() -> list[FieldCase]:
    """Every range-checked value of every base, one per field of each model (the second tow
    layer repeats the first)."""
    from preform.library import validate_entry
    from preform.material import plausibility_checks
    from preform.yamlsource import load_yaml_text

    registry = _builtin_registry()
    cases: list[FieldCase] = []
    seen: set[tuple[str, tuple[str | int, ...]]] = set()
    for base_name, entry in BASES.items():
        doc = load_yaml_text(yaml.safe_dump(entry, sort_keys=False), "base.yaml")[0]
        fabric, errors, _ = validate_entry(doc, (), doc.data, registry)
        assert fabric is not None and not errors, (base_name, errors)
        for check in plausibility_checks(fabric):
            path = check.path
            field_path = path[:-1] if isinstance(path[-1], int) else path
            template = tuple(p for p in field_path if not isinstance(p, int))
            if (base_name, template) in seen:
                continue
            seen.add((base_name, template))
            owner = _owner(fabric, field_path)
            low, high = _hard_bounds(type(owner), str(field_path[-1]))
            cases.append(FieldCase(base_name, path, str(field_path[-1]), check.rule, low, high))
    return cases


FIELD_CASES = field_cases()
SCALAR_CASES = [c for c in FIELD_CASES if c.rule.measure is None]


def test_every_plausible_field_of_every_registered_model_is_generated(
    sandbox: PluginSandbox,
) -> None:
    """The cases cover every marked field of every registered architecture and shear law, so a
    field added to a model without a test entry here fails this test."""
    registry = sandbox.registry
    generated = {
        tuple(p for p in c.path if not isinstance(p, int) and p != "glass") for c in FIELD_CASES
    }
    expected = set()
    for tag in registry.names("architectures"):
        expected |= {path for path, _ in plausible_fields(registry.architecture(tag))}
    for law in registry.names("shear_laws"):
        params = registry.shear_law_type(law).params
        expected |= {("shear_law", *path) for path, _ in plausible_fields(params)}
    assert expected, "no field carries a plausible range"
    assert expected <= generated, sorted(expected - generated)
    assert len(FIELD_CASES) >= 40


#: Fields whose upper end is also bounded by another field: (changes to that field, a value
#: above the plausible range that the other field allows).
COMPANIONS: dict[str, tuple[dict[str, float], float]] = {
    # the drop must end inside the fitted range (60°): fail at 5° and drop over 50°
    "failure_width_deg": ({"failure_angle_deg": 5.0}, 50.0),
}


def _large_value(case: FieldCase) -> float | None:
    """Far above the range, or between it and a hard upper bound when there is one."""
    if case.field in COMPANIONS:
        return COMPANIONS[case.field][1]
    high = case.rule.high
    if case.hard_high is None:
        return high * 1000.0 if high > 0 else 1e6
    if case.hard_high > high:
        return 0.5 * (high + case.hard_high)
    return None  # the plausible range ends at the hard limit: nothing to test beyond it


def _scaled_coefficients(case: FieldCase, factor: float) -> list[float]:
    values = list(_value_at(BASES[case.base], case.path))
    return [v * factor for v in values]


def _value_at(entry: dict[str, Any], path: tuple[str | int, ...]) -> Any:
    node: Any = entry
    for part in path:
        node = node[part]
    return node


#: Measured quantities in degrees (the last angle of a table) cannot pass 90°: a hard limit.
LARGE = [
    c
    for c in FIELD_CASES
    if (c.rule.unit != "deg" if c.rule.measure is not None else _large_value(c) is not None)
]
TABLE_ENDS = [c for c in FIELD_CASES if c.rule.measure is not None and c.rule.unit == "deg"]


@pytest.mark.parametrize("case", TABLE_ENDS, ids=[c.id for c in TABLE_ENDS])
def test_a_table_in_radians_is_a_located_range_error(
    sandbox: PluginSandbox, tmp_path: Path, case: FieldCase
) -> None:
    """Angles of a table given in radians all lie inside [0, 90]: only the range catches them."""
    radians = [math.radians(a) for a in _value_at(BASES[case.base], case.path)]
    raw = yaml.safe_dump(radians, default_flow_style=True).strip()
    written = write_entry(tmp_path, set_at(BASES[case.base], case.path, MARK), raw)
    errors, _ = load_errors(sandbox, written)
    label = f"{written.name}.{format_path(case.path)}"
    assert_one_located(
        errors, written, label, f"gives {case.rule.what} of 1.0472 deg", "given in radians?"
    )


@pytest.mark.parametrize("case", LARGE, ids=[c.id for c in LARGE])
def test_far_too_large_is_a_located_range_error(
    sandbox: PluginSandbox, tmp_path: Path, case: FieldCase
) -> None:
    entry = BASES[case.base]
    if case.rule.measure is not None:
        # Scale the whole polynomial until its peak over the fitted range is 1000× the bound.
        peak = case.rule.measure(_value_at(entry, case.path), _owner_data(case))
        assert peak and peak > 0
        value: Any = _scaled_coefficients(case, case.rule.high * 1000.0 / peak)
        raw = yaml.safe_dump(value, default_flow_style=True).strip()
        words = ["gives", case.rule.what, f"plausible range {case.rule.describe()}"]
    else:
        value = _large_value(case)
        raw = repr(value)
        words = [f"{case.field.split('[')[0]}", f"= {value:g} is outside the plausible range"]
        words.append(f"{case.rule.describe()} for {case.rule.what}")
    for name, companion in COMPANIONS.get(case.field, ({}, 0.0))[0].items():
        entry = set_at(entry, (*case.path[:-1], name), companion)
    written = write_entry(tmp_path, set_at(entry, case.path, MARK), raw)
    errors, _ = load_errors(sandbox, written)
    label = f"{written.name}.{format_path(case.path)}"
    assert_one_located(errors, written, label, *words, "accept_out_of_range", case.rule.reason)


def _owner_data(case: FieldCase) -> Any:
    """The validated params model holding a measured field (for its fitted range)."""
    registry = _builtin_registry()
    law = BASES[case.base]["shear_law"]
    return registry.shear_law_type(law["law"]).params.model_validate(law)


SMALL = [c for c in SCALAR_CASES if c.rule.low > 0]


def _without_failure(entry: dict[str, Any]) -> dict[str, Any]:
    """The entry without a stitch-failure drop (which must end inside the fitted range)."""
    out = copy.deepcopy(entry)
    for name in (
        "failure_angle_deg",
        "failure_width_deg",
        "post_failure_force_coefficients_N_per_mm",
    ):
        out["shear_law"].pop(name, None)
    return out


@pytest.mark.parametrize("case", SMALL, ids=[c.id for c in SMALL])
def test_far_too_small_is_a_located_range_error(
    sandbox: PluginSandbox, tmp_path: Path, case: FieldCase
) -> None:
    value = case.rule.low / 1000.0
    entry = BASES[case.base]
    if case.base == "warp_knit" and case.field == "max_angle_deg":
        entry = _without_failure(entry)
    written = write_entry(tmp_path, set_at(entry, case.path, MARK), repr(value))
    errors, _ = load_errors(sandbox, written)
    label = f"{written.name}.{format_path(case.path)}"
    assert_one_located(
        errors, written, label, f"= {value:g} is outside the plausible range", case.rule.what
    )


#: Non-finite spellings as YAML passes them on: text (inf, Infinity, nan, 1e999 without a dot)
#: and YAML's own .inf, which the reader refuses before the model sees it.
NON_FINITE = ["inf", "-inf", "Infinity", "-Infinity", "nan", "NaN", "1e999", "-1e999", ".inf"]


@pytest.mark.parametrize("case", FIELD_CASES, ids=[c.id for c in FIELD_CASES])
def test_non_finite_in_every_spelling_is_a_located_error(
    sandbox: PluginSandbox, tmp_path: Path, case: FieldCase
) -> None:
    """inf, -inf, Infinity, nan, 1e999 (text to YAML) and .inf: one located error each, at the
    value, saying it is not finite. For a list field the value replaces one item."""
    path = case.path
    if case.rule.measure is not None:
        path = (*path, 1)
    for spelling in NON_FINITE:
        written = write_entry(tmp_path, set_at(BASES[case.base], path, MARK), spelling)
        errors, _ = load_errors(sandbox, written)
        label = f"{written.name}.{format_path(path)}"
        if spelling == ".inf":  # the YAML reader's message, entry named by its index
            label = f"[0].{format_path(path)}"
        assert_one_located(errors, written, label, "non-finite number", spelling)


@pytest.mark.parametrize("case", FIELD_CASES, ids=[c.id for c in FIELD_CASES])
def test_boolean_is_a_located_error(
    sandbox: PluginSandbox, tmp_path: Path, case: FieldCase
) -> None:
    """``true`` was read as 1: a 1 mm tow, a friction coefficient of 1, a 1° fitted range."""
    path = case.path if case.rule.measure is None else (*case.path, 0)
    written = write_entry(tmp_path, set_at(BASES[case.base], path, MARK), "true")
    errors, _ = load_errors(sandbox, written)
    label = f"{written.name}.{format_path(path)}"
    assert_one_located(errors, written, label, "true is a boolean, not a number")


# -- the issue's examples, word for word ---------------------------------------------------------


@pytest.mark.parametrize(
    ("path", "raw", "words"),
    [
        (("tow_types", "glass", "width_mm"), "3100", ["width_mm = 3100", "0.05–50 mm", "µm?"]),
        (("tow_types", "glass", "height_mm"), "35", ["height_mm = 35", "µm?"]),
        (("tow_types", "glass", "linear_density_tex"), "11.9e6", ["1.19e+07", "1–100000 tex"]),
        (("tow_types", "glass", "fibre_modulus_GPa"), "72.0e+9", ["given in Pa?"]),
        (("tow_types", "glass", "fibre_density_g_cm3"), "2550", ["given in kg/m³?"]),
        (("warp", "tow_spacing_mm"), "4000", ["given in µm?"]),
        (("shear_law", "friction_coefficient"), "30", ["percent?"]),
    ],
    ids=["width 3100 mm", "height 35 mm", "11.9e6 tex", "modulus in Pa", "density kg/m3",
         "spacing in um", "friction in percent"],
)  # fmt: skip
def test_unit_mistakes_are_named(
    sandbox: PluginSandbox, tmp_path: Path, path: tuple[str, ...], raw: str, words: list[str]
) -> None:
    written = write_entry(tmp_path, set_at(WOVEN, path, MARK), raw)
    errors, _ = load_errors(sandbox, written)
    assert_one_located(errors, written, f"hostile-woven.{format_path(path)}", *words)


def test_radians_for_degrees_and_kg_for_g_are_named(sandbox: PluginSandbox, tmp_path: Path) -> None:
    entry = set_at(WARP_KNIT, ("nominal_areal_density_g_m2",), MARK)
    written = write_entry(tmp_path, entry, "0.936")
    errors, _ = load_errors(sandbox, written)
    assert_one_located(
        errors, written, "hostile-knit.nominal_areal_density_g_m2", "given in kg/m²?"
    )
    entry = set_at(WARP_KNIT, ("shear_law", "failure_angle_deg"), MARK)
    written = write_entry(tmp_path, entry, "0.61")  # 35° in radians
    errors, _ = load_errors(sandbox, written)
    assert_one_located(
        errors, written, "hostile-knit.shear_law.failure_angle_deg", "given in radians?"
    )


@pytest.mark.parametrize(
    ("path", "raw"),
    [
        (("tow_types", "glass", "width_mm"), "inf"),
        (("warp", "tow_spacing_mm"), "inf"),
        (("weft", "tow_spacing_mm"), "Infinity"),
        (("tow_types", "glass", "height_mm"), "1e999"),
        (("tow_types", "glass", "width_mm"), "true"),
        (("tow_types", "glass", "width_mm"), "yes"),
        (("tow_types", "glass", "linear_density_tex"), "on"),
    ],
)
def test_the_issue_values_fail_at_the_model_layer(
    sandbox: PluginSandbox, tmp_path: Path, path: tuple[str, ...], raw: str
) -> None:
    """Refused by the model itself (pydantic), not only by the loader: a fabric built in
    Python from the same data fails the same way."""
    from preform.plugins.woven.model import WovenFabric

    written = write_entry(tmp_path, set_at(WOVEN, path, MARK), raw)
    errors, _ = load_errors(sandbox, written)
    assert_one_located(errors, written, f"hostile-woven.{format_path(path)}")
    data = yaml.safe_load(written.file.read_text())[0]
    with pytest.raises(ValueError, match=r"finite|boolean"):
        WovenFabric.model_validate({k: v for k, v in data.items() if k != "shear_law"})


def test_numbers_written_as_text_are_read_as_numbers(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    """Choice: text that spells a finite number is that number. YAML 1.1 reads 1e3 (no dot) and
    1.19e3 (no exponent sign) as text; a quoted "4.0" is text too. They still pass every range."""
    entry = set_at(WOVEN, ("tow_types", "glass", "linear_density_tex"), MARK)
    written = write_entry(tmp_path, entry, "1.19e3")
    text = written.file.read_text().replace("tow_spacing_mm: 4.0", "tow_spacing_mm: '4.0'", 1)
    written.file.write_text(text)
    lib = load_library([written.file], bundled=False, env=False, registry=sandbox.registry)
    fabric: Any = lib.fabric("hostile-woven")
    assert fabric.tow_types["glass"].linear_density_tex == 1190.0
    assert fabric.warp.tow_spacing_mm == 4.0
    written = write_entry(tmp_path, set_at(WOVEN, ("warp", "tow_spacing_mm"), MARK), "'4e6'")
    errors, _ = load_errors(sandbox, written)
    assert_one_located(errors, written, "hostile-woven.warp.tow_spacing_mm", "= 4e+06")


# -- overrides -----------------------------------------------------------------------------------


def test_an_override_accepts_the_value_records_it_and_warns(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    entry = set_at(WOVEN, ("tow_types", "glass", "width_mm"), 60.0)
    entry = set_at(entry, ("warp", "tow_spacing_mm"), 70.0)
    entry = set_at(entry, ("weft", "tow_spacing_mm"), 70.0)
    entry["accept_out_of_range"] = ["tow_types.glass.width_mm"]
    written = write_entry(tmp_path, entry)
    lib = load_library([written.file], bundled=False, env=False, registry=sandbox.registry)
    fabric = lib.fabric("hostile-woven")
    assert fabric.accept_out_of_range == ("tow_types.glass.width_mm",)
    # Recorded: the override is part of the data the pipeline hashes and stores per case.
    dumped = fabric.model_dump(mode="json", exclude_none=True)
    assert dumped["accept_out_of_range"] == ["tow_types.glass.width_mm"]
    texts = [str(w) for w in lib.warnings]
    line = next(
        n
        for n, content in enumerate(written.file.read_text().splitlines(), start=1)
        if "width_mm: 60.0" in content
    )
    warning = [t for t in texts if "accepted by override" in t]
    assert len(warning) == 1, texts
    assert warning[0].startswith(f"{written.file}:{line}:")
    assert "hostile-woven.tow_types.glass.width_mm: width_mm = 60 is outside" in warning[0]


def test_an_override_is_in_the_case_data_and_its_input_hash(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    """A run's case stores the fabric with its override, and the input hash changes with it:
    a result computed from an accepted out-of-range value is never mistaken for another."""
    from preform.pipeline.runner import make_cases
    from preform.pipeline.scene import load_scene

    scene_path = tmp_path / "scene.yaml"
    scene_path.write_text(
        "name: cell\ntool: {surface: hemisphere, radius_mm: 100}\n"
        "ply: {node_spacing_mm: 20, size_mm: [100, 100]}\n"
        "start: {point_mm: [0, 0], generator_angle_deg: 90}\noutputs: [drape]\n"
    )
    scene = load_scene(scene_path, sandbox.registry)
    hashes = []
    for pretension, overrides in (
        (100.0, None),
        (100.0, ["shear_law.pretension_N"]),  # not needed (a warning), but still data
        (2e4, ["shear_law.pretension_N"]),
    ):
        entry = set_at(WOVEN, ("shear_law", "pretension_N"), pretension)
        if overrides:
            entry["accept_out_of_range"] = overrides
        written = write_entry(tmp_path, entry)
        lib = load_library([written.file], bundled=False, env=False, registry=sandbox.registry)
        (case,) = make_cases(lib, [scene], tmp_path / "out", sandbox.host, discover=False)
        assert case.fabric_data.get("accept_out_of_range") == overrides
        hashes.append(case.input_hash)
    assert len(set(hashes)) == 3  # the first two differ only by the override


def test_an_override_of_a_list_accepts_every_item_and_a_law_field(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    entry = copy.deepcopy(BASES["tabulated-force"])
    entry["shear_law"]["force_N_per_mm"] = [0.0, 50.0, 200.0, 300.0]
    entry["shear_law"]["locking_angle_deg"] = 1.0
    entry["accept_out_of_range"] = ["shear_law.force_N_per_mm", "shear_law.locking_angle_deg"]
    written = write_entry(tmp_path, entry)
    errors, warnings = load_errors(sandbox, written)
    assert errors == []
    accepted = [w for w in warnings if "accepted by override" in w]
    assert len(accepted) == 3, warnings  # two table points and the angle


def test_an_override_without_it_fails_and_a_wrong_path_is_located(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    entry = set_at(WOVEN, ("tow_types", "glass", "height_mm"), 35.0)
    entry["accept_out_of_range"] = ["tow_types.glass.heigth_mm"]
    written = write_entry(tmp_path, entry)
    errors, _ = load_errors(sandbox, written)
    assert len(errors) == 2, errors
    typo = [e for e in errors if "accept_out_of_range[0]" in e]
    assert typo and "names no range-checked value" in typo[0]
    assert "did you mean 'tow_types.glass.height_mm'?" in typo[0]
    assert any("height_mm = 35 is outside" in e for e in errors)


def test_an_unneeded_override_is_a_warning(sandbox: PluginSandbox, tmp_path: Path) -> None:
    entry = copy.deepcopy(WOVEN)
    entry["accept_out_of_range"] = ["warp.tow_spacing_mm"]
    written = write_entry(tmp_path, entry)
    errors, warnings = load_errors(sandbox, written)
    assert errors == []
    assert any(
        "accept_out_of_range[0]: 'warp.tow_spacing_mm' is inside its plausible range" in w
        for w in warnings
    ), warnings


# -- negative polynomial laws ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("base", "field", "coefficients", "words"),
    [
        ("polynomial-force", "force_coefficients_N_per_mm", [0.0, 0.05, -1e-3],
         ["force F_s/L comes out negative", "-0.6 N/mm at 60°", "0–60°"]),
        ("polynomial-force", "force_coefficients_negative_N_per_mm", [0.0, -1e-3],
         ["comes out negative", "0–50°"]),
        ("polynomial-torque", "torque_coefficients_N_per_m", [-0.1, 1.0],
         ["torque C comes out negative", "N·m/m² at 0°"]),
        ("warp_knit", "perpendicular_force_coefficients_N_per_mm", [0.0, -1e-4],
         ["comes out negative", "0–50°"]),
        ("warp_knit", "parallel_force_coefficients_N_per_mm", [0.0, 0.02, -1e-3],
         ["comes out negative", "0–35°"]),
        ("warp_knit", "post_failure_force_coefficients_N_per_mm", [0.03, -1e-3],
         ["comes out negative", "35–60°"]),
    ],
    ids=["force", "force negative sense", "torque", "perpendicular", "parallel", "post failure"],
)  # fmt: skip
def test_a_polynomial_negative_inside_its_range_is_a_located_error(
    sandbox: PluginSandbox,
    tmp_path: Path,
    base: str,
    field: str,
    coefficients: list[float],
    words: list[str],
) -> None:
    entry = set_at(BASES[base], ("shear_law", field), MARK)
    written = write_entry(tmp_path, entry, yaml.safe_dump(coefficients, default_flow_style=True))
    errors, _ = load_errors(sandbox, written)
    assert_one_located(errors, written, f"{written.name}.shear_law.{field}", *words)


def test_the_same_polynomial_is_refused_inside_its_root_and_accepted_before_it(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    """F = 0.05γ − 1e-3γ² turns negative at 50°: fitted to 60° it is refused, fitted to 45° it
    is a valid law (clipped to zero past its root by the beyond-range policy)."""
    entry = set_at(
        BASES["polynomial-force"],
        ("shear_law", "force_coefficients_N_per_mm"),
        [0.0, 0.05, -1e-3],
    )
    errors, _ = load_errors(sandbox, write_entry(tmp_path, entry))
    assert len(errors) == 1 and "comes out negative (-0.6 N/mm at 60°)" in errors[0], errors
    entry["shear_law"]["max_angle_deg"] = 45.0
    errors, _ = load_errors(sandbox, write_entry(tmp_path, entry))
    assert errors == []


def test_a_stitch_failure_drop_that_turns_negative_is_located(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    """P₁ falling steeply right after failure makes the blend towards P₂ negative."""
    entry = copy.deepcopy(WARP_KNIT)
    entry["shear_law"]["parallel_force_coefficients_N_per_mm"] = [0.0, 0.36, -0.01]  # root 36°
    entry["shear_law"]["failure_width_deg"] = 20.0
    written = write_entry(tmp_path, entry)
    errors, _ = load_errors(sandbox, written)
    assert len(errors) == 1 and "hostile-knit.shear_law.failure_width_deg" in errors[0], errors
    assert "comes out negative" in errors[0] and "35–55°" in errors[0]


# -- size limits (item 9) -------------------------------------------------------------------------


def _satin(harness: int) -> dict[str, Any]:
    entry = copy.deepcopy(WOVEN)
    entry["weave"] = {"pattern": "satin", "harness": harness, "move": 2}
    return entry


@pytest.mark.parametrize("harness", [3001, 100001, 10**18])
def test_a_huge_harness_is_refused_at_once(
    sandbox: PluginSandbox, tmp_path: Path, harness: int
) -> None:
    entry = set_at(_satin(5), ("weave", "harness"), MARK)
    written = write_entry(tmp_path, entry, str(harness))
    start = time.process_time()
    errors, _ = load_errors(sandbox, written)
    elapsed = time.process_time() - start
    assert elapsed < REFUSAL_CPU_S, (
        elapsed
    )  # was minutes and gigabytes (3001), out of memory (100001)
    assert_one_located(
        errors,
        written,
        "hostile-woven.weave.harness",
        f"{harness} is above the size limit weave_repeat = {SIZE_LIMITS['weave_repeat'][0]}",
        f"{LIMITS_ENV}=weave_repeat=N",
    )


@pytest.mark.parametrize(
    ("weave", "path", "limit"),
    [
        ({"pattern": "twill", "over": 2, "under": 100000}, ("weave", "under"), "weave_repeat"),
        ({"pattern": "basket", "warp_group": 10**6, "weft_group": 1}, ("weave", "warp_group"), "weave_repeat"),
        ({"pattern": "orthogonal", "stuffer_layers": 10**6, "weft_layers": 2}, ("weave", "stuffer_layers"), "weave_levels"),
        ({"pattern": "angle_interlock", "stuffer_layers": 1, "weft_layers": 10**7}, ("weave", "weft_layers"), "weave_levels"),
        ({"pattern": "layer_to_layer", "stuffer_layers": 1, "weft_layers": 5000}, ("weave", "weft_layers"), "weave_levels"),
        ({"pattern": "general", "warp_levels": 1, "weft_levels": 10**9, "repeat_warp": 2, "repeat_weft": 2, "matrix": [[[2, 1]]]}, ("weave", "weft_levels"), "weave_levels"),
        ({"pattern": "general", "warp_levels": 1, "weft_levels": 1, "repeat_warp": 10**9, "repeat_weft": 2, "matrix": [[[2, 1]]]}, ("weave", "repeat_warp"), "weave_repeat"),
    ],
    ids=["twill", "basket", "orthogonal", "angle interlock", "layer to layer", "general levels", "general repeat"],
)  # fmt: skip
def test_every_woven_size_is_limited(
    sandbox: PluginSandbox,
    tmp_path: Path,
    weave: dict[str, Any],
    path: tuple[str, ...],
    limit: str,
) -> None:
    entry = copy.deepcopy(WOVEN)
    entry["weave"] = weave
    value = _value_at(entry, path)
    written = write_entry(tmp_path, set_at(entry, path, MARK), str(value))
    start = time.process_time()
    errors, _ = load_errors(sandbox, written)
    assert time.process_time() - start < REFUSAL_CPU_S
    assert_one_located(
        errors,
        written,
        f"hostile-woven.{format_path(path)}",
        f"{value} is above the size limit {limit}",
    )


@pytest.mark.parametrize(
    ("weave", "path", "repeat"),
    [
        ({"pattern": "twill", "over": 100, "under": 100}, ("weave", "under"), 200),
        ({"pattern": "basket", "warp_group": 1, "weft_group": 100}, ("weave", "weft_group"), 200),
    ],
    ids=["twill over + under", "basket 2 x group"],
)
def test_the_repeat_a_weave_implies_is_limited(
    sandbox: PluginSandbox,
    tmp_path: Path,
    weave: dict[str, Any],
    path: tuple[str, ...],
    repeat: int,
) -> None:
    """Each number is below the limit, the repeat they make is not."""
    entry = copy.deepcopy(WOVEN)
    entry["weave"] = weave
    written = write_entry(tmp_path, set_at(entry, path, MARK), str(_value_at(entry, path)))
    errors, _ = load_errors(sandbox, written)
    assert_one_located(
        errors, written, f"hostile-woven.{format_path(path)}", f"{repeat} is above the size limit"
    )


@pytest.mark.parametrize(
    ("path", "raw", "limit"),
    [
        (("threads", 0, "knitting_sequence"), "/".join(["1-0", "1-2"] * 50000), "lapping_courses"),
        (("threads", 0, "knitting_sequence"), "1-0/1000000-1000001", "needle_gap"),
        (("threads", 0, "empty_guides"), "100000", "empty_guides"),
        (("placement",), yaml.safe_dump([[1]] * 100, default_flow_style=True).strip(), "tow_layers"),
        (("placement", 0), yaml.safe_dump([1] * 5000, default_flow_style=True).strip(), "placement_row"),
        (("shear_law", "parallel_force_coefficients_N_per_mm"), yaml.safe_dump([0.0] * 40, default_flow_style=True).strip(), "polynomial_terms"),
    ],
    ids=["100000 courses", "needle gap 1e6", "empty guides", "placement rows", "placement row", "polynomial terms"],
)  # fmt: skip
def test_every_warp_knit_size_is_limited(
    sandbox: PluginSandbox, tmp_path: Path, path: tuple[str | int, ...], raw: str, limit: str
) -> None:
    written = write_entry(tmp_path, set_at(WARP_KNIT, path, MARK), raw)
    start = time.process_time()
    errors, _ = load_errors(sandbox, written)
    assert time.process_time() - start < REFUSAL_CPU_S
    assert_one_located(
        errors, written, f"hostile-knit.{format_path(path)}", f"above the size limit {limit}"
    )


def test_many_tow_layers_are_limited(sandbox: PluginSandbox, tmp_path: Path) -> None:
    entry = copy.deepcopy(WARP_KNIT)
    entry["tow_layers"] = [entry["tow_layers"][0]] * 200
    entry["placement"] = None
    del entry["placement"]
    written = write_entry(tmp_path, entry)
    errors, _ = load_errors(sandbox, written)
    assert len(errors) == 1 and "hostile-knit.tow_layers: 200 is above the size limit" in errors[0]


def test_a_limit_can_be_raised_on_purpose(
    sandbox: PluginSandbox, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    entry = _satin(131)  # prime: move 2 is regular
    written = write_entry(tmp_path, entry)
    errors, _ = load_errors(sandbox, written)
    assert len(errors) == 1 and "above the size limit weave_repeat = 128" in errors[0]
    monkeypatch.setenv(LIMITS_ENV, "weave_repeat=200")
    errors, _ = load_errors(sandbox, written)
    assert errors == []


def test_a_malformed_limit_setting_is_said(
    sandbox: PluginSandbox, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(LIMITS_ENV, "weave_repeet=200")
    written = write_entry(tmp_path, _satin(5))
    errors, _ = load_errors(sandbox, written)
    assert len(errors) == 1
    assert (
        "hostile-woven.weave.harness" in errors[0] and "did you mean 'weave_repeat'?" in errors[0]
    )


# -- bundled fabrics and the property over ranges ----------------------------------------------


def test_the_bundled_fabrics_are_valid_without_overrides(sandbox: PluginSandbox) -> None:
    fabrics, errors, warnings = validate_files([bundled_library_dir()], sandbox.registry)
    assert errors == []
    assert len(fabrics) >= 10
    assert all(f.accept_out_of_range is None for f, _ in fabrics)
    assert not [w for w in warnings if "plausible" in str(w)]


def test_every_base_entry_is_valid(sandbox: PluginSandbox, tmp_path: Path) -> None:
    for entry in BASES.values():
        errors, warnings = load_errors(sandbox, write_entry(tmp_path, entry))
        assert errors == [], errors
        assert not [w for w in warnings if "plausible" in w], warnings


def entry_for(case: FieldCase) -> tuple[dict[str, Any], float | None]:
    """The base entry for varying one field alone, and the field's effective hard upper bound.

    Other fields bound some fields: a stitch-failure drop must end inside the fitted range, and
    a needle distance must agree with the gauge. Those companions are set aside here so that
    the value under test is the only thing that can fail."""
    entry = BASES[case.base]
    hard_high = case.hard_high
    if case.base == "warp_knit" and case.field == "max_angle_deg":
        entry = _without_failure(entry)
    if case.field == "failure_width_deg":  # fail at 5°: the drop may then reach 55°
        entry = set_at(entry, (*case.path[:-1], "failure_angle_deg"), 5.0)
        hard_high = 55.0
    if case.field in ("needle_distance_mm", "gauge_needles_per_inch"):
        other = (
            "gauge_needles_per_inch" if case.field == "needle_distance_mm" else "needle_distance_mm"
        )
        entry = copy.deepcopy(entry)
        del entry["threads"][0][other]
    return entry, hard_high


@settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_inside_the_range_validates_outside_fails_located(
    sandbox: PluginSandbox, tmp_path: Path, data: st.DataObject
) -> None:
    """Property: any value inside a field's declared range passes the range check (and the
    model's own limits); any finite value outside it fails with one error located at the
    field. Geometric consistency of a combination (a tow wider than its spacing, a stitch that
    does not fit the cell) is a separate check and may still speak inside the range."""
    case = data.draw(st.sampled_from(SCALAR_CASES), label="field")
    rule = case.rule
    entry, hard_high = entry_for(case)
    inside = data.draw(st.floats(rule.low, rule.high), label="inside")
    if case.hard_low is not None:
        inside = max(inside, math.nextafter(case.hard_low, math.inf))
    if hard_high is not None:
        inside = min(inside, math.nextafter(hard_high, -math.inf))
    written = write_entry(tmp_path, set_at(entry, case.path, MARK), repr(inside))
    errors, _ = load_errors(sandbox, written)
    label = f"{written.name}.{format_path(case.path)}"
    assert not [e for e in errors if "plausible range" in e or "Input should" in e], errors
    high_side = st.floats(rule.high, 1e300, exclude_min=True)
    if hard_high is not None and hard_high > rule.high:
        high_side = st.floats(rule.high, hard_high, exclude_min=True, exclude_max=True)
    elif hard_high is not None:
        high_side = st.nothing()
    outside = data.draw(high_side | st.floats(-1e300, rule.low, exclude_max=True), label="outside")
    written = write_entry(tmp_path, set_at(entry, case.path, MARK), repr(outside))
    errors, _ = load_errors(sandbox, written)
    assert len(errors) == 1, errors
    assert errors[0].startswith(f"{written.file}:{written.line}:{written.column}: {label}: ")


# -- through the command line ---------------------------------------------------------------------


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PREFORM_LIBRARY": ""}
    return subprocess.run(
        [sys.executable, "-m", "preform", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )


@pytest.mark.parametrize(
    ("path", "raw", "words"),
    [
        (("tow_types", "glass", "width_mm"), "3100", "was it given in µm?"),
        (("tow_types", "glass", "width_mm"), "inf", "non-finite number"),
        (("warp", "tow_spacing_mm"), "true", "true is a boolean"),
        (("weave",), "{pattern: satin, harness: 100001, move: 2}", "size limit weave_repeat"),
    ],
    ids=["range", "inf", "boolean", "harness"],
)
def test_the_cli_reports_located_errors_and_exits_1(
    tmp_path: Path, path: tuple[str, ...], raw: str, words: str
) -> None:
    written = write_entry(tmp_path, set_at(WOVEN, path, MARK), raw)
    result = _cli("materials", "validate", str(written.file))
    assert result.returncode == 1, (result.stdout, result.stderr)
    output = result.stdout + result.stderr
    assert "Traceback" not in output
    target = path if path != ("weave",) else ("weave", "harness")
    # the harness sits in the flow mapping written on the marker's line
    assert (
        f"{written.file}:{written.line}:" in output
        and f"hostile-woven.{format_path(target)}" in output
    )
    assert words in output


def test_the_schema_shows_every_range(sandbox: PluginSandbox) -> None:
    """`preform schema` carries each range next to its field, for editors."""
    from preform.schema import library_schema

    schema = library_schema(sandbox.registry)
    found: list[dict[str, Any]] = []

    def walk(node: Any) -> None:
        if isinstance(node, dict):
            if "x-plausible-range" in node:
                found.append(node["x-plausible-range"])
            for value in node.values():
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    walk(schema)
    shown = {(r["low"], r["high"], r["unit"], r["of"]) for r in found}
    expected = {(c.rule.low, c.rule.high, c.rule.unit, c.rule.what) for c in FIELD_CASES}
    assert expected <= shown, expected - shown
