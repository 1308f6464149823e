"""Layups (preform.stack): plies on the offset tool, the stack's maps, its status, its scene
section's located errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import preform
from preform.pipeline.scene import SceneError, load_scene
from preform.plugin_manager import default_host
from preform.stack.steps import stack_words

R_MM = 100.0
T_MM = 0.5

#: A small ply at the pole shears little (below every fabric's locking angle), so its draped
#: thickness is its nominal one everywhere and the tool under ply k is exactly R + k·t.
SMALL = {
    "name": "small-stack",
    "tool": {"surface": "hemisphere", "radius_mm": R_MM},
    "ply": {"node_spacing_mm": 4.0, "size_mm": [60, 60]},
    "start": {"point_mm": [0, 0]},
    "layup": {
        "plies": [
            {"fabric": "plain-weave-600", "orientation_deg": 0, "thickness_mm": T_MM},
            {"fabric": "plain-weave-600", "orientation_deg": 90, "thickness_mm": T_MM},
            {"fabric": "satin-4hs-crowfoot", "orientation_deg": 45, "thickness_mm": T_MM},
        ],
        "ply_outputs": ["drape"],
    },
    "outputs": ["layup", "stack_csv"],
}


@pytest.fixture(scope="module")
def small() -> preform.Layup:
    return preform.layup(SMALL)


def test_ply_k_is_draped_on_the_sphere_of_radius_r_plus_k_t(small: preform.Layup) -> None:
    assert small.status == "ok", small.error or small.reasons
    layers = small.stack.layers
    assert len(layers) == 3
    for k, layer in enumerate(layers):
        nodes = layer.result.nodes[np.isfinite(layer.result.nodes[..., 0])]
        radius = np.linalg.norm(nodes, axis=1) * 1e3
        assert np.abs(radius - (R_MM + k * T_MM)).max() < 1e-9
        assert small.plies[k]["offset_mm"] == pytest.approx(k * T_MM, abs=1e-12)
        # the 0/90/45 convention: the first family leaves the pole along the ply angle
        assert np.degrees(layer.result.orientation) == pytest.approx(
            [0.0, 90.0, 45.0][k], abs=1e-9
        )


def test_the_stack_total_is_the_sum_of_its_plies(small: preform.Layup) -> None:
    table = small.to_pandas()
    plies = [c for c in table.columns if c.startswith("thickness_mm_")]
    assert len(plies) == 3
    assert np.allclose(table[plies].sum(axis=1), table["total_thickness_mm"], atol=1e-12)
    # independent truth: a ply is present where the station lies inside its square, turned
    # by the ply angle (the plan is within 0.5 mm of the flat this near the pole; a margin of
    # one node spacing leaves out the stations a cell's edge may put either way)
    x, y = table["x_mm"].to_numpy(), table["y_mm"].to_numpy()
    inside, clear = np.zeros(len(table), int), np.ones(len(table), bool)
    for angle in np.radians([0.0, 90.0, 45.0]):
        u = np.abs(np.cos(angle) * x + np.sin(angle) * y)
        v = np.abs(-np.sin(angle) * x + np.cos(angle) * y)
        reach = np.maximum(u, v)
        inside += reach < 30.0
        clear &= np.abs(reach - 30.0) > 4.0
    assert clear.sum() > 50
    assert (table["plies_present"].to_numpy()[clear] == inside[clear]).all()
    assert np.allclose(table["total_thickness_mm"].to_numpy()[clear], inside[clear] * T_MM)
    assert small.summary["stack"] == "all 3 plies ok"


def test_a_drop_off_ply_is_present_only_inside_its_outline(tmp_path: Path) -> None:
    half = 15.0
    scene = {
        **SMALL,
        "layup": {
            "plies": [
                {"fabric": "plain-weave-600", "thickness_mm": T_MM},
                {
                    "fabric": "plain-weave-600",
                    "thickness_mm": T_MM,
                    "orientation_deg": 45,
                    "part_outline_mm": [[-half, -half], [half, -half], [half, half], [-half, half]],
                },
                {"fabric": "plain-weave-600", "thickness_mm": T_MM, "orientation_deg": 90},
            ],
            "ply_outputs": ["drape", "cells_csv"],
        },
        "outputs": ["layup", "stack_csv", "stack_thickness_png"],
    }
    stack = preform.layup(scene, out_dir=tmp_path)
    assert stack.status == "ok", stack.error or stack.reasons
    table = stack.to_pandas()
    x, y = table["x_mm"].abs(), table["y_mm"].abs()
    d = 4.0  # the node spacing: a station within a cell of the outline may go either way
    inside = (x < half - d) & (y < half - d)
    outside = (x > half + d) | (y > half + d)
    assert inside.sum() > 10 and outside.sum() > 10
    assert (table.loc[inside, "plies_present"] == 3).all()
    assert (table.loc[outside, "plies_present"] == 2).all()
    assert np.allclose(table.loc[outside, "total_thickness_mm"], 2 * T_MM, atol=1e-9)
    # the drop-off ply's own part is the outline; the plies above see its mean thickness
    assert stack.plies[2]["offset_mm"] == pytest.approx(2 * T_MM, abs=1e-9)
    folder = stack.case_dir
    assert folder is not None
    for name in ("stack.csv", "stack_thickness.png", "summary.json"):
        assert (folder / name).is_file()
    for record in stack.plies:
        assert (folder / record["name"] / "cells.csv").is_file()
        assert (folder / record["name"] / "summary.json").is_file()


def test_a_ply_not_ok_makes_the_stack_not_ok_in_words() -> None:
    records = [
        {"ply": 1, "name": "a", "status": "ok", "error": None, "reasons": []},
        {"ply": 2, "name": "b", "status": "partial", "error": None, "reasons": ["it wrinkles"]},
    ]
    words = stack_words(records)
    assert words.startswith("1 of 2 plies ok, so the stack is not")
    assert "ply 2 (b) partial: it wrinkles" in words


LAYUP_YAML = """\
name: bad-layup
tool: {{surface: hemisphere, radius_mm: 100}}
ply: {{node_spacing_mm: 10, size_mm: [100, 100]}}
start: {{point_mm: [0, 0]{start}}}
layup:
  plies:
    - {{fabric: plain-weave-600, orientation_deg: 0}}
    - {{fabric: plain-weave-600, {second}}}
  ply_outputs: [drape, {ply_output}]
outputs: [layup, {output}]
"""


def _errors(tmp_path: Path, **fields: str) -> list[str]:
    values = {"start": "", "second": "orientation_deg: 90", "ply_output": "vtu", "output": "stack_csv"}
    values.update(fields)
    path = tmp_path / "bad.yaml"
    path.write_text(LAYUP_YAML.format(**values))
    with pytest.raises(SceneError) as info:
        load_scene(path, default_host().registry)
    return [str(e).replace(f"{path}:", "") for e in info.value.errors]


def test_layup_scene_errors_are_located(tmp_path: Path) -> None:
    # the field's own check: at the value (line 8, column 54)
    (error,) = _errors(tmp_path, second="generator_angle_deg: 200")
    assert error.startswith("8:54: layup.plies[1].generator_angle_deg: a generator angle"), error
    # what needs the scene around it: at the key
    (error,) = _errors(tmp_path, start=", orientation_deg: 30")
    assert error.startswith("4:27: start.orientation_deg: with a layup each ply"), error
    (error,) = _errors(tmp_path, ply_output="no_such_output")
    assert error.startswith("9:24: layup.ply_outputs[1]: unknown output 'no_such_output'"), error
    (error,) = _errors(tmp_path, output="vtu")
    assert error.startswith("10:18: outputs[1]: with a layup, 'vtu' is an output of each ply")
    (error,) = _errors(tmp_path, second="start_point_mm: [500, 0]")
    assert error.startswith("8:33: layup.plies[1].start_point_mm: the start point"), error
    assert error.endswith("move layup.plies[1].start_point_mm onto it"), error
