"""The WovenFabric library model and the bundled woven.yaml entries."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import pytest
import yaml
from pydantic import ValidationError

from preform.plugins.woven.model import WovenFabric

LIBRARY = Path(__file__).parents[3] / "materials" / "fabrics" / "woven.yaml"
ENTRIES: list[dict[str, Any]] = yaml.safe_load(LIBRARY.read_text(encoding="utf-8"))
BY_NAME = {e["name"]: e for e in ENTRIES}


def fabric(name: str, **changes: Any) -> WovenFabric:
    return WovenFabric.model_validate(copy.deepcopy(BY_NAME[name]) | changes)


def test_library_names() -> None:
    assert list(BY_NAME) == [
        "plain-weave-600",
        "plain-weave-150",
        "twill-2x2-glass",
        "satin-4hs-crowfoot",
        "satin-5hs-carbon",
        "satin-8hs-carbon",
        "orthogonal-3d-glass",
    ]


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e["name"])
def test_round_trip_and_clean(entry: dict[str, Any]) -> None:
    model = WovenFabric.model_validate(entry)
    assert model.model_dump(mode="json", exclude_none=True) == entry
    assert model.errors() == []
    assert model.check() == []
    derived = model.derived()
    assert all(isinstance(v, int | float) and math.isfinite(v) for v in derived.values())
    assert model.reference_direction_deg() == 45.0
    if "illustrative" not in entry["source"].lower():
        assert "assumption" in entry["note"]
    else:
        assert "illustrative" in entry["note"].lower()


@pytest.mark.parametrize(
    ("name", "tex", "spacing_mm", "nominal", "locking_deg"),
    [("plain-weave-600", 1190, 4.0, 600, 39.19), ("plain-weave-150", 150, 2.0, 150, 53.13)],
)
def test_table_1_fabrics(
    name: str, tex: float, spacing_mm: float, nominal: float, locking_deg: float
) -> None:
    derived = fabric(name).derived()
    straight = 2 * tex / spacing_mm  # PHYSICS §1.3, both families, no crimp
    # Crimp only adds mass: above tex/spacing, and within 1 % of the nominal weight (which is
    # rounded: 1190/4 + 1190/4 = 595 ≈ 600; crimp of the assumed tow heights is < 0.5 %).
    assert straight <= derived["areal_density_g_m2"] <= straight * 1.005
    assert derived["areal_density_g_m2"] == pytest.approx(nominal, rel=0.01)
    assert derived["locking_angle_deg"] == pytest.approx(locking_deg, abs=0.005)
    assert derived["locking_angle_warp_deg"] == derived["locking_angle_weft_deg"]
    assert 0.5 < derived["tow_volume_fraction_warp"] < 0.7


def test_table_1_shear_laws() -> None:
    assert BY_NAME["plain-weave-600"]["shear_law"] == {
        "law": "friction_compaction",
        "friction_coefficient": 0.3,
        "pretension_N": 100,
        "fabric_thickness_mm": 2.0,
    }
    assert BY_NAME["plain-weave-150"]["shear_law"] == {
        "law": "friction_compaction",
        "friction_coefficient": 0.3,
        "pretension_N": 50,
        "fabric_thickness_mm": 0.6,
    }


def test_unit_cell_and_crossover_geometry_in_si() -> None:
    model = fabric("plain-weave-600")
    cell = model.unit_cell()
    assert cell.area == pytest.approx(8e-3 * 8e-3)
    assert {t.kind for t in cell.tows} == {"warp", "weft"}
    geometry = model.crossover_geometry()
    assert (geometry.tow_width_warp, geometry.tow_spacing_weft) == pytest.approx((3.1e-3, 4e-3))
    assert geometry.tow_height_warp == pytest.approx(0.32e-3)
    three_d = fabric("orthogonal-3d-glass").unit_cell()
    binders = [t for t in three_d.tows if t.kind == "binder"]
    assert binders and all(t.type_name == "glass-binder-300" for t in binders)


def test_derived_keys_carry_units() -> None:
    keys = set(fabric("satin-5hs-carbon").derived())
    assert {
        "areal_density_g_m2",
        "locking_angle_deg",
        "locking_angle_warp_deg",
        "locking_angle_weft_deg",
        "crimp_warp_percent",
        "crimp_weft_percent",
        "fibre_volume_fraction",
        "tow_volume_fraction_warp",
        "cover_factor",
        "gap_fraction",
        "thickness_mm",
    } <= keys


# -- single-field problems: pydantic locates them -----------------------------------------
@pytest.mark.parametrize(
    ("changes", "location", "words"),
    [
        ({"weave": {"pattern": "satin", "harness": 8, "move": 4}}, "move", "valid moves: 3, 5"),
        ({"weave": {"pattern": "satin", "harness": 4, "move": 1}}, "harness", "crowfoot"),
        (
            {
                "weave": {
                    "pattern": "angle_interlock",
                    "stuffer_layers": 1,
                    "weft_layers": 3,
                    "binder_depth": 5,
                }
            },
            "binder_depth",
            "between 2",
        ),
        ({"weave": {"pattern": "twill", "over": 0, "under": 2}}, "over", "greater than"),
        ({"weave": {"pattern": "leno"}}, "weave", "pattern"),
    ],
)
def test_field_errors(changes: dict[str, Any], location: str, words: str) -> None:
    with pytest.raises(ValidationError) as info:
        fabric("satin-5hs-carbon", **changes)
    (error,) = info.value.errors()
    assert error["loc"][0] == "weave" and error["loc"][-1] == location
    assert words in error["msg"] or words in str(error)


def test_unknown_fibre_and_extra_field() -> None:
    tow_types = copy.deepcopy(BY_NAME["plain-weave-150"]["tow_types"])
    tow_types["glass-150"]["fibre"] = "basalt"
    with pytest.raises(ValidationError) as info:
        fabric("plain-weave-150", tow_types=tow_types)
    assert info.value.errors()[0]["loc"] == ("tow_types", "glass-150", "fibre")
    with pytest.raises(ValidationError):
        fabric("plain-weave-150", warp={"tow_spacing_mm": 2.0, "tow_type": "glass-150", "x": 1})


# -- cross-field problems: errors() locates them ------------------------------------------
def general(matrix: list[list[list[int]]], **extra: Any) -> dict[str, Any]:
    return {
        "pattern": "general",
        "warp_levels": 1,
        "weft_levels": 1,
        "repeat_warp": 2,
        "repeat_weft": 2,
        "matrix": matrix,
    } | extra


PLAIN = [[[2, 1], [1, 2]], [[1, 2], [2, 1]]]


def test_general_plain_equals_generated_plain() -> None:
    explicit = fabric("plain-weave-600", weave=general(PLAIN))
    assert explicit.errors() == []
    assert explicit.derived() == fabric("plain-weave-600").derived()


@pytest.mark.parametrize(
    ("weave", "location", "words"),
    [
        (general(PLAIN, repeat_warp=3), ("weave", "matrix"), "rows"),
        (general([[[2, 1], [1, 2]], [[1, 2]]]), ("weave", "matrix", 1), "entries"),
        (general([[[2, 1], [1, 2]], [[1, 2], [2, 5]]]), ("weave", "matrix", 1, 1), "do not exist"),
        (general([[[2, 1], [2]], [[1, 2], [2, 1]]]), ("weave", "matrix", 0, 1), "misses level"),
        (
            general([[[2, 1], [2, 1]], [[2, 1], [1, 2]], [[1, 2], [2, 1]]], repeat_warp=3),
            ("weave", "matrix", 0),
            "floats over",
        ),
        (
            general([[[2, 1], [1, 2], [1, 2]], [[1, 2], [2, 1], [1, 2]]], repeat_weft=3),
            ("weave", "matrix"),
            "never interlaces",
        ),
        (
            general([[[3, 1, 2], [1, 2, 3]]], warp_levels=2, repeat_warp=1),
            ("weave",),
            "no binder holds",
        ),
        (
            general(
                [[[3, 1, 4, 2], [3, 1, 4, 2]]],
                warp_levels=2,
                weft_levels=2,
                repeat_warp=1,
                binder_levels=[2],
            ),
            ("weave", "binder_levels"),
            "no binder holds",
        ),
    ],
)
def test_consistency_errors(weave: dict[str, Any], location: tuple, words: str) -> None:
    model = fabric("plain-weave-600", weave=weave)
    errors = model.errors()
    assert any(loc == location and words in msg for loc, msg in errors), errors
    with pytest.raises(ValueError, match="inconsistent"):
        model.derived()


@pytest.mark.parametrize(
    ("warp", "location", "words"),
    [
        ({"tow_spacing_mm": 4.0, "tow_type": "glass-999"}, ("warp", "tow_type"), "unknown"),
        (
            {"tow_spacing_mm": 4.0, "tow_type": ["glass-1190", "glass-1190"]},
            ("warp", "tow_type"),
            "1 warp-wise level",
        ),
        (
            {"tow_spacing_mm": 4.0, "tow_type": [["glass-1190", "glass-1190", "glass-1190"]]},
            ("warp", "tow_type", 0),
            "repeat has 2",
        ),
        (
            {"tow_spacing_mm": 4.0, "tow_type": [["glass-1190", "nope"]]},
            ("warp", "tow_type", 0, 1),
            "unknown tow type 'nope'",
        ),
        (
            {"tow_spacing_mm": 4.0, "tow_type": "glass-1190", "binder_tow_type": "glass-1190"},
            ("warp", "binder_tow_type"),
            "no binder",
        ),
    ],
)
def test_tow_type_assignment_errors(warp: dict[str, Any], location: tuple, words: str) -> None:
    errors = fabric("plain-weave-600", warp=warp).errors()
    assert [loc for loc, _ in errors] == [location]
    assert words in errors[0][1]


def test_hybrid_per_tow_assignment() -> None:
    tow_types = copy.deepcopy(BY_NAME["plain-weave-600"]["tow_types"])
    tow_types["light"] = {
        "fibre": "carbon",
        "linear_density_tex": 200,
        "width_mm": 1.0,
        "height_mm": 0.1,
    }
    model = fabric(
        "plain-weave-600",
        tow_types=tow_types,
        warp={"tow_spacing_mm": 4.0, "tow_type": [["glass-1190", "light"]]},
    )
    assert model.errors() == []
    derived = model.derived()
    # Warp family: one 1190 tex and one 200 tex tow per 8 mm (crimp is below 1 %).
    assert derived["areal_density_warp_g_m2"] == pytest.approx((1190 + 200) / 8.0, rel=0.01)
    assert {t.type_name for t in model.unit_cell().tows if t.kind == "warp"} == {
        "glass-1190",
        "light",
    }


def test_wide_tows_warn_on_the_tow_type() -> None:
    tow_types = copy.deepcopy(BY_NAME["plain-weave-600"]["tow_types"])
    tow_types["glass-1190"]["width_mm"] = 4.5
    model = fabric("plain-weave-600", tow_types=tow_types)
    assert model.errors() == []
    warnings = model.check()
    assert [loc for loc, _ in warnings] == [("tow_types", "glass-1190", "width_mm")] * 2
    assert model.derived()["locking_angle_deg"] == 0.0


def test_json_schema_documents_every_field() -> None:
    schema = WovenFabric.model_json_schema()
    missing = []
    for owner, block in [("WovenFabric", schema), *schema["$defs"].items()]:
        for field_name, prop in block.get("properties", {}).items():
            if "description" not in prop:
                missing.append(f"{owner}.{field_name}")
    assert missing == []
