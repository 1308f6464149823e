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
        assert np.degrees(layer.result.orientation) == pytest.approx([0.0, 90.0, 45.0][k], abs=1e-9)


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
    values = {
        "start": "",
        "second": "orientation_deg: 90",
        "ply_output": "vtu",
        "output": "stack_csv",
    }
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


def _plate_stl(path: Path, half_mm: float = 60.0, n: int = 24) -> Path:
    from preform.plugins.surfaces.mesh import TriangleMesh, write_stl

    s = np.linspace(-half_mm, half_mm, n + 1) * 1e-3
    xx, yy = np.meshgrid(s, s, indexing="ij")
    points = np.column_stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)])
    index = np.arange(points.shape[0]).reshape(xx.shape)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    write_stl(path, TriangleMesh(points, faces))
    return path


def test_a_mesh_tool_is_offset_place_by_place_over_a_drop_off(tmp_path: Path) -> None:
    """Ply 1 covers x < 0 only (a drop-off); ply 2 lies on the plate mesh raised by ply 1's
    thickness over x < 0 and not raised over x > 0 (the vertex-normal offset)."""
    tool = _plate_stl(tmp_path / "plate.stl")
    scene = {
        "name": "plate-drop-off",
        "tool": {"surface": "mesh", "file": str(tool), "units": "mm"},
        "ply": {"node_spacing_mm": 5.0, "size_mm": [100, 100]},
        "start": {"point_mm": [0, 0]},
        "layup": {
            "plies": [
                {
                    "fabric": "plain-weave-600",
                    "thickness_mm": T_MM,
                    "part_outline_mm": [[-70, -70], [0, -70], [0, 70], [-70, 70]],
                },
                {"fabric": "plain-weave-600", "thickness_mm": T_MM, "orientation_deg": 90},
            ],
            "ply_outputs": ["drape"],
        },
        "outputs": ["layup"],
    }
    stack = preform.layup(scene)
    assert stack.ok, stack.error or stack.reasons
    assert stack.summary["stack_offset_method"] == "vertex normals (mesh)"
    assert stack.plies[1]["offset_mm"] == pytest.approx(T_MM, abs=1e-9)
    nodes = stack.stack.layers[1].result.nodes * 1e3
    nodes = nodes[np.isfinite(nodes[..., 0])]
    # the drop-off's edge is known to a cell of ply 1's net (5 mm) and the offset ramps over a
    # cell of the plate mesh (5 mm): away from both, the offset is exact
    margin = 5.0 + 120.0 / 24
    left, right = nodes[:, 0] < -margin - 1e-9, nodes[:, 0] > margin + 1e-9
    assert left.sum() > 50 and right.sum() > 50
    assert np.allclose(nodes[left, 2], T_MM, atol=1e-9)
    assert np.allclose(nodes[right, 2], 0.0, atol=1e-9)


def test_stack_sections_map_every_ply_onto_the_fe_mesh_tool_side_first(tmp_path: Path) -> None:
    from preform.pipeline.scene import bundled_scene_dir

    skin = bundled_scene_dir().parent / "tools" / "hemisphere_skin.inp"
    scene = {
        **SMALL,
        "export": {"mesh": str(skin), "reference_direction": [1, 0, 0]},
        "outputs": ["layup", "stack_sections"],
    }
    stack = preform.layup(scene, out_dir=tmp_path)
    # the 100 mm plies cover the middle of the 176 mm skin: its bare rest makes the stack
    # partial, as uncovered elements make a single ply's export
    assert stack.status == "partial", stack.error
    (reason,) = stack.reasons
    assert "of 392 elements of hemisphere_skin.inp" in reason and "with no ply" in reason
    sections = stack.products["stack_sections"]
    assert [p.name for p in sections.plies] == [layer.name for layer in stack.stack.layers]
    assert [p.material for p in sections.plies] == [
        "plain-weave-600",
        "plain-weave-600",
        "satin-4hs-crowfoot",
    ]
    first, second = sections.plies[0].mapping, sections.plies[1].mapping
    near_pole = first.covered & second.covered & (np.hypot(*first.centroid_mm[:, :2].T) < 15.0)
    assert near_pole.sum() >= 3
    # the 90° ply's first family is the 0° ply's turned by 90° about the normal (near the
    # pole, where the drape has hardly sheared)
    turn = (second.angle_u_deg - first.angle_u_deg)[near_pole]
    assert np.allclose(np.mod(turn, 360.0), 90.0, atol=2.0)
    assert np.allclose(second.thickness_mm[near_pole], T_MM, atol=1e-9)
    table = np.genfromtxt(stack.case_dir / "stack_elements.csv", delimiter=",", names=True)
    covered = np.sum([p.mapping.covered for p in sections.plies], axis=0)
    assert np.array_equal(table["plies_present"], covered)
    assert np.allclose(table["total_thickness_mm"], covered * T_MM, atol=1e-9)


def test_reading_a_ply_at_points_agrees_with_the_exact_closest_point_rule(
    small: preform.Layup,
) -> None:
    """ply_at's shortcut (the nearest cell's parallelogram) against the exact rule alone
    (closest_on_net for every point), on points scattered over and beyond the plies."""
    from preform.export.fe_mapping import EDGE_TOLERANCE, closest_on_net
    from preform.stack.maps import ply_at

    rng = np.random.default_rng(7)
    plan = rng.uniform(-45.0, 45.0, size=(3000, 2))
    r = np.hypot(plan[:, 0], plan[:, 1])
    lift = rng.uniform(0.0, 1.2, size=len(plan))  # anywhere within the stack's height
    points = np.column_stack([plan, np.sqrt(R_MM**2 - r**2) + lift])
    for layer in small.stack.layers:
        gap = 4.0 + 1.5
        fast = ply_at(layer, points, gap)
        hit = closest_on_net(layer.result, points, layer.region)
        exact = (hit.tangential_mm <= EDGE_TOLERANCE * 4.0) & (hit.gap_mm <= gap)
        # the two may differ only where a cell's bow makes its parallelogram straddle the
        # edge of the exact rule's tolerance: a handful of points on the net's edge
        assert np.count_nonzero(fast.present != exact) <= 0.002 * len(points)
        both = fast.present & exact
        assert np.allclose(fast.thickness_mm[both], T_MM, atol=1e-9)
        assert exact.sum() > 500


def test_the_stations_read_on_their_own_ply_without_a_search_give_the_searched_maps(
    small: preform.Layup,
) -> None:
    """stack_at(..., own=reference) skips the nearest-cell search on the ply whose cell
    centres the stations are; the maps are those of the search, every field, bit for bit."""
    from preform.stack.maps import reference_ply, stack_at, stations

    layers = small.stack.layers
    points, area = stations(layers)
    searched = stack_at(layers, points, area)
    shortcut = stack_at(layers, points, area, own=reference_ply(layers))
    for field in ("present", "thickness_mm", "fibre_volume_fraction", "wrinkles"):
        assert np.array_equal(getattr(searched, field), getattr(shortcut, field), equal_nan=True)
    assert shortcut.present[:, reference_ply(layers)].all()


def test_pipeline_run_runs_a_layup_scene_as_one_case_and_reuses_it(tmp_path: Path) -> None:
    import csv
    import json

    import yaml
    from click.testing import CliRunner

    from preform.cli import cli

    scene = tmp_path / "small.yaml"
    scene.write_text(yaml.safe_dump(SMALL, sort_keys=False))
    out = tmp_path / "results"
    args = ["pipeline", "run", "--scene", str(scene), "--engine", "serial", "--out", str(out)]
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 0, result.output
    (row,) = list(csv.DictReader((out / "results.csv").open()))
    assert row["material"] == "plain-weave-600+satin-4hs-crowfoot"
    assert row["status"] == "ok"
    summary = json.loads((out / "small-stack" / "stack" / "summary.json").read_text())
    assert summary["stack"] == "all 3 plies ok"
    assert [p["name"] for p in summary["plies"]] == [
        "ply-1-plain-weave-600",
        "ply-2-plain-weave-600",
        "ply-3-satin-4hs-crowfoot",
    ]
    again = CliRunner().invoke(cli, args)
    assert again.exit_code == 0, again.output
    assert "skipped" in again.output


def test_a_ply_that_cannot_be_placed_fails_the_stack_naming_it() -> None:
    """A cone has no exact offset: ply 1 drapes on it, ply 2 cannot, and the stack fails
    saying which ply and what to do."""
    scene = {
        **SMALL,
        "tool": {"surface": "cone", "base_radius_mm": 100, "height_mm": 60},
        "start": {"point_mm": [0, 0]},
    }
    stack = preform.layup(scene)
    assert stack.status == "failed"
    assert stack.error is not None
    assert stack.error.startswith(
        "ply 2 of 3 (ply-2-plain-weave-600) cannot be placed: the tool (Cone) has no exact offset"
    ), stack.error
    assert "give the tool as a mesh" in stack.error
    assert [p["status"] for p in stack.plies] == ["ok"]


def test_a_least_energy_ply_searches_its_generator_angle_at_its_own_orientation() -> None:
    scene = {
        **SMALL,
        "search": {"generator_angle_deg": {"min": 60, "max": 120}, "scan_step_deg": 10},
        "layup": {
            "plies": [
                {
                    "fabric": "E-BX-318",
                    "orientation_deg": 30,
                    "generator_angle_deg": "least_energy",
                },
                {"fabric": "plain-weave-600", "orientation_deg": 0, "thickness_mm": T_MM},
            ],
            "ply_outputs": ["drape"],
        },
    }
    stack = preform.layup(scene)
    assert stack.status in ("ok", "partial"), stack.error
    first, second = stack.plies
    # the search ran and chose an angle in its range; the fixed ply kept 90°
    assert 60.0 <= first["generator_angle_deg"] <= 120.0
    assert first["generator_angle_deg"] != pytest.approx(90.0, abs=1e-6)
    assert second["generator_angle_deg"] == pytest.approx(90.0, abs=1e-9)
    assert np.degrees(stack.stack.layers[0].result.orientation) == pytest.approx(30.0, abs=1e-9)


def test_a_layup_scene_writes_the_stacks_composite_sections_for_every_solver(
    tmp_path: Path,
) -> None:
    """The scene outputs ``stack_abaqus``, ``stack_calculix``, ``stack_lsdyna`` and
    ``stack_ansys`` write the composite sections of the mapped stack (the writers themselves
    are run in ccx in tests/export/test_calculix_solver.py): one composite section per element
    with a ply, as many layers as plies present there, every fabric named as a material."""
    import re

    from preform.pipeline.scene import bundled_scene_dir

    skin = bundled_scene_dir().parent / "tools" / "hemisphere_skin.inp"
    decks = ["stack_abaqus", "stack_calculix", "stack_lsdyna", "stack_ansys"]
    scene = {
        **SMALL,
        "export": {"mesh": str(skin), "reference_direction": [1, 0, 0]},
        "outputs": ["layup", "stack_sections", *decks],
    }
    stack = preform.layup(scene, out_dir=tmp_path)
    # the 100 mm plies cover the middle of the 176 mm skin: its bare rest makes the stack
    # partial, as uncovered elements make a single ply's export
    assert stack.status == "partial", stack.error
    (reason,) = stack.reasons
    assert "of 392 elements of hemisphere_skin.inp" in reason and "with no ply" in reason
    written = {p.name for p in stack.case_dir.iterdir()}
    assert {"stack_abaqus.inp", "stack_calculix.inp", "stack_lsdyna.k", "stack_ansys.mac"} <= (
        written
    )
    table = np.genfromtxt(stack.case_dir / "stack_elements.csv", delimiter=",", names=True)
    with_ply = int(np.count_nonzero(table["plies_present"] > 0))
    assert with_ply > 0
    for name in ("stack_abaqus.inp", "stack_calculix.inp"):
        text = (stack.case_dir / name).read_text()
        assert len(re.findall(r"^\*SHELL SECTION, .*COMPOSITE", text, re.M)) == with_ply, name
        for fabric in ("plain-weave-600", "satin-4hs-crowfoot"):
            assert fabric.upper() in text.upper(), (name, fabric)
    counts = stack.summary["stack_sections_summary"]
    assert counts["elements"] == len(table)
    assert counts["elements_bare"] == len(table) - with_ply
