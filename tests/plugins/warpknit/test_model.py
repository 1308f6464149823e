"""The warp_knit library model and the bundled entries."""

from __future__ import annotations

import re
from importlib.resources import files

import numpy as np
import pytest
import yaml
from pydantic import ValidationError

from preform.plugins.warpknit.geometry import cell_areal_density_g_m2
from preform.plugins.warpknit.model import WarpKnitFabric

ENTRIES = yaml.safe_load(
    files("preform.materials").joinpath("fabrics/warpknit.yaml").read_text(encoding="utf-8")
)
BY_NAME = {e["name"]: e for e in ENTRIES}


def test_bundled_names():
    assert list(BY_NAME) == ["E-BXhd-936", "E-BX-318", "ncf-0-90-tricot"]


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e["name"])
def test_round_trip(entry):
    fabric = WarpKnitFabric.model_validate(entry)
    assert fabric.model_dump(mode="json", exclude_none=True) == entry
    assert fabric.errors() == []
    assert fabric.check() == []
    assert "illustrative" in fabric.note.lower()
    # the illustrative shear law is in the entry and its provenance is in the note
    assert entry["shear_law"]["law"] in ("stitch_polynomial", "polynomial")
    assert "shear law illustrative" in fabric.note.lower()


@pytest.mark.parametrize("name", ["E-BXhd-936", "E-BX-318"])
def test_areal_density_matches_the_product_name(name):
    match = re.search(r"(\d+)$", name)
    assert match is not None
    nominal = float(match.group(1))
    derived = WarpKnitFabric.model_validate(BY_NAME[name]).derived()
    assert derived["areal_density_g_m2"] == pytest.approx(nominal, rel=0.01)
    layers = sum(derived["areal_density_layers_g_m2"])
    assert derived["areal_density_g_m2"] == pytest.approx(
        layers + derived["areal_density_stitch_g_m2"]
    )


def test_stitch_yarn_of_the_chain_stitched_fabric_by_hand():
    # E-BX-318: pillar stitch, so per course one 6 mm loop and a 2.5 mm straight underlap, on
    # 2.5 mm × 5.08 mm (E5) per thread, 7.6 tex.
    derived = WarpKnitFabric.model_validate(BY_NAME["E-BX-318"]).derived()
    assert derived["areal_density_stitch_g_m2"] == pytest.approx(7.6 * (6.0 + 2.5) / (2.5 * 5.08))
    assert derived["areal_density_layers_g_m2"] == pytest.approx([600 / 3.83] * 2)


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e["name"])
def test_cell_agrees_with_derived_and_tiles(entry):
    fabric = WarpKnitFabric.model_validate(entry)
    cell = fabric.unit_cell()
    total = cell_areal_density_g_m2(cell)
    assert total == pytest.approx(fabric.derived()["areal_density_g_m2"], rel=0.01)
    assert cell_areal_density_g_m2(cell.tiled(2, 3)) == pytest.approx(total, rel=1e-9)


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e["name"])
def test_reference_direction_bisects_the_fibre_families(entry):
    """±45° layers: the stitch (0°) bisects them and is the reference for signed shear; 0/90
    layers: the stitch runs along a fibre, so the reference is their 45° bisector."""
    fabric = WarpKnitFabric.model_validate(entry)
    first, second = (layer.orientation_deg for layer in fabric.tow_layers[:2])
    expected = 0.0 if first == -second else 45.0
    assert fabric.reference_direction_deg() == expected
    assert fabric.derived()["stitch_direction_deg"] == 0.0
    assert fabric.unit_cell().reference_direction == pytest.approx(np.radians(expected))


def _with_thread(**changes):
    entry = dict(BY_NAME["ncf-0-90-tricot"])
    entry["threads"] = [{**entry["threads"][0], **changes}]
    return entry


def test_lapping_error_points_at_the_field_with_a_caret():
    with pytest.raises(ValidationError) as info:
        WarpKnitFabric.model_validate(_with_thread(knitting_sequence="1-0/1-2x"))
    (error,) = info.value.errors()
    assert error["loc"] == ("threads", 0, "knitting_sequence")
    assert "1-0/1-2x\n" in error["msg"] and error["msg"].endswith("       ^")


@pytest.mark.parametrize(
    ("changes", "loc"),
    [
        ({"linear_density_tex": -1}, ("threads", 0, "linear_density_tex")),
        ({"fibre": "unobtainium"}, ("threads", 0, "fibre")),
        ({"empty_guides": -1}, ("threads", 0, "empty_guides")),
    ],
)
def test_single_field_problems_raise_at_the_field(changes, loc):
    with pytest.raises(ValidationError) as info:
        WarpKnitFabric.model_validate(_with_thread(**changes))
    assert [e["loc"] for e in info.value.errors()] == [loc]


def test_cross_field_problems_come_from_errors():
    fabric = WarpKnitFabric.model_validate(_with_thread(needle_distance_mm=4.0))
    assert [loc for loc, _ in fabric.errors()] == [("threads", 0, "gauge_needles_per_inch")]
    with pytest.raises(ValueError, match="gauge"):
        fabric.unit_cell()
    placed = WarpKnitFabric.model_validate({**BY_NAME["ncf-0-90-tricot"], "placement": [[1], [2]]})
    assert [loc for loc, _ in placed.errors()] == [("placement", 1, 0)]


def test_datasheet_mismatch_is_a_warning():
    entry = {**BY_NAME["E-BX-318"], "nominal_areal_density_g_m2": 400}
    assert [loc for loc, _ in WarpKnitFabric.model_validate(entry).check()] == [
        ("nominal_areal_density_g_m2",)
    ]


def test_every_field_is_described():
    schema = WarpKnitFabric.model_json_schema()
    for part in ["TowLayerEntry", "ThreadLevelEntry"]:
        for name, prop in schema["$defs"][part]["properties"].items():
            assert prop.get("description"), f"{part}.{name}"
    for name, prop in schema["properties"].items():
        assert prop.get("description"), name
