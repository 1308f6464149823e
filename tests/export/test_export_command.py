"""`preform export` and the exporter steps of a scene, end to end."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
from click.testing import CliRunner

from preform.cli import cli
from preform.pipeline.scene import bundled_scene_dir

SKIN = bundled_scene_dir().parent / "tools" / "hemisphere_skin.inp"

SCENE = """\
name: small-cap
tool: {{surface: hemisphere, radius_mm: 100}}
ply: {{node_spacing_mm: 5, size_mm: [100, 100]}}
start: {{point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90}}
export: {{mesh: {mesh}, seam_allowance_mm: 4, thickness_cap_ratio: 1.001}}
outputs: [drape, abaqus_include, lsdyna_include, ansys_macro, element_table, element_vtu,
  cut_pattern]
"""


def write_scene(tmp_path: Path) -> Path:
    path = tmp_path / "small-cap.yaml"
    path.write_text(SCENE.format(mesh=SKIN))
    return path


def elset(text: str, name: str) -> list[int]:
    lines = text.splitlines()
    at = lines.index(f"*ELSET, ELSET={name}")
    out: list[int] = []
    for line in lines[at + 1 :]:
        if line.startswith("*"):
            break
        out += [int(v) for v in line.split(",") if v.strip()]
    return out


def test_export_command_writes_targets_and_reports_uncovered_elements(tmp_path) -> None:
    scene = write_scene(tmp_path)
    out = tmp_path / "out"
    result = CliRunner().invoke(
        cli,
        [
            "export",
            "plain-weave-600",
            "abaqus",
            "table",
            "cut-pattern",
            "--scene",
            str(scene),
            "--out",
            str(out),
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["status"] == "partial"  # a 100 mm ply cannot cover the 176 mm skin
    assert report["written"] == {
        "abaqus": "drape_abaqus.inc",
        "table": "elements.csv",
        "cut-pattern": ["cut_pattern.dxf", "cut_pattern.svg", "cut_pattern.csv"],
    }
    mesh = report["mesh"]
    assert mesh["elements"] == 392 and 0 < mesh["elements_uncovered"] < 392
    table = pd.read_csv(out / "elements.csv")
    assert sorted(table.loc[~table.covered, "element_id"]) == sorted(mesh["uncovered_element_ids"])
    text = (out / "drape_abaqus.inc").read_text()
    assert sorted(elset(text, "PREFORM_UNCOVERED")) == sorted(mesh["uncovered_element_ids"])
    assert report["units"] == {"length": "mm", "angle": "deg"}
    # The plain weave shears at most ~10° on this cap, below its locking angle (39.2°): its
    # sheared unit cell keeps the thickness t0 exactly, so no element passes the 1.001 cap
    # (under the old 1/cos γ every sheared element did).
    assert mesh["thickness_model"] == "sheared unit cell"
    assert mesh["thickness_reference"] == "the sheared unit cell's thickness at zero shear"
    assert mesh["elements_above_thickness_cap"] == 0
    assert not any("compaction cap" in w for w in report["warnings"])
    covered = table[table.covered]
    assert covered.shear_deg.abs().max() > 5.0
    assert (covered.thickness_ratio == 1.0).all()
    assert (covered.thickness_mm == mesh["nominal_thickness_mm"]).all()
    assert "** Thickness model: sheared unit cell; t0 = 0.64 mm" in text
    assert report["cut_pattern_allowance_area_mm2"] > report["cut_pattern_area_mm2"]
    # whole net cells (d = 5 mm) past the fabric's locking angle, drawn in the flat
    cells = report["cut_pattern_past_locking_area_mm2"] / 25.0
    assert abs(cells - round(cells)) < 1e-9


def test_export_command_refusals(tmp_path) -> None:
    scene = write_scene(tmp_path)
    runner = CliRunner()
    bad = runner.invoke(cli, ["export", "nope", "abaqus", "--scene", str(scene)])
    assert bad.exit_code == 2 and "no fabric named 'nope'" in bad.stderr
    no_scene = runner.invoke(cli, ["export", "plain-weave-600", "abaqus", "--scene", "nosuch"])
    assert no_scene.exit_code == 2 and "no bundled scene" in no_scene.stderr
    wrong = runner.invoke(
        cli,
        ["export", "plain-weave-600", "table", "--reference-direction", "0,0,0"],
    )
    assert wrong.exit_code == 2 and "not all zero" in wrong.stderr
    no_mesh = runner.invoke(cli, ["export", "plain-weave-600", "lsdyna"])
    assert no_mesh.exit_code == 2 and "--mesh" in no_mesh.stderr
    missing = runner.invoke(
        cli,
        [
            "export",
            "plain-weave-600",
            "table",
            "--scene",
            str(scene),
            "--mesh",
            str(tmp_path / "absent.inp"),
            "--out",
            str(tmp_path / "o"),
            "--json",
        ],
    )
    # refused before anything is draped, as bad input
    assert missing.exit_code == 2 and missing.stdout == ""
    assert "--mesh" in missing.stderr and "absent.inp: no such file" in missing.stderr


def test_scene_outputs_run_in_the_pipeline_and_mark_the_case_partial(tmp_path) -> None:
    scene = write_scene(tmp_path)
    out = tmp_path / "run"
    result = CliRunner().invoke(
        cli,
        [
            "pipeline",
            "run",
            "--scene",
            str(scene),
            "--materials",
            "plain-weave-600",
            "--out",
            str(out),
            "--engine",
            "serial",
        ],
    )
    assert result.exit_code == 0, result.output
    case = out / "small-cap" / "plain-weave-600"
    summary = json.loads((case / "summary.json").read_text())
    assert summary["status"] == "partial"
    covered = summary["mesh_elements_covered"]
    assert summary["complete"]  # the drape covers its ply; the mesh reaches beyond it
    assert summary["covered_fraction"] == covered / 392
    assert any("uncovered" in reason for reason in summary["reasons"])
    for name in (
        "drape_abaqus.inc",
        "drape_lsdyna.k",
        "elements.csv",
        "elements.vtu",
        "cut_pattern.dxf",
        "cut_pattern.svg",
        "cut_pattern.csv",
    ):
        assert (case / name).is_file(), name


def test_scene_darts_and_cuts_reach_the_cutting_pattern(tmp_path) -> None:
    """A dart into the flat pattern's edge at y = 50 mm (the 100 mm ply, start in its middle)
    and a cut far off it: the dart is on the DARTS layer and removes fabric, the cut is
    reported as missing the pattern."""
    import ezdxf

    scene = tmp_path / "darted.yaml"
    scene.write_text(
        "name: darted\n"
        "tool: {surface: plane, size_mm: [400, 400]}\n"
        "ply: {node_spacing_mm: 10, size_mm: [100, 100]}\n"
        "start: {point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90}\n"
        "export:\n"
        "  darts: [{apex_mm: [0, 20], mouth_mm: [[-10, 60], [10, 60]]}]\n"
        "  cuts: [{from_mm: [500, 0], to_mm: [600, 0]}]\n"
        "outputs: [drape, cut_pattern]\n"
    )
    out = tmp_path / "out"
    result = CliRunner().invoke(
        cli,
        [
            "export",
            "plain-weave-600",
            "cut-pattern",
            "--scene",
            str(scene),
            "--out",
            str(out),
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    # the dart's triangle up to the edge y = 50: similar to the whole one, ½ · 15 · 30; the
    # smoothed outline's side is straight away from the corners to ~1e-5 mm
    assert abs(report["cut_pattern_darts_removed_area_mm2"] - 225.0) < 1e-3
    assert any("cut 0 misses the pattern" in w for w in report["warnings"])
    msp = ezdxf.readfile(out / "cut_pattern.dxf").modelspace()
    assert len([e for e in msp.query("LWPOLYLINE") if e.dxf.layer == "DARTS"]) == 1
    assert len([e for e in msp.query("LINE") if e.dxf.layer == "CUTS"]) == 1


def test_export_command_writes_both_families_for_lsdyna_and_ansys(tmp_path) -> None:
    scene = write_scene(tmp_path)
    out = tmp_path / "out"
    result = CliRunner().invoke(
        cli,
        [
            "export",
            "plain-weave-600",
            "lsdyna",
            "ansys",
            "--scene",
            str(scene),
            "--lsdyna-form",
            "composite",
            "--thickness-mm",
            "0.3",
            "--out",
            str(out),
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    covered = report["mesh"]["elements_covered"]
    k = (out / "drape_lsdyna.k").read_text().splitlines()
    at = k.index("*ELEMENT_SHELL_COMPOSITE")
    cards = [line for line in k[at + 1 : k.index("*SET_SHELL_LIST")] if not line.startswith("$")]
    assert len(cards) == 2 * covered
    mac = (out / "drape_ansys.mac").read_text().splitlines()
    assert sum(line.startswith("SECTYPE,") for line in mac) == covered
    assert sum(line.startswith("SECDATA,") for line in mac) == 2 * covered
