"""`preform export NAME calculix`: one section per covered element, the uncovered listed."""

from __future__ import annotations

import json
import re

from click.testing import CliRunner

from preform.cli import cli
from preform.pipeline.scene import bundled_scene_dir

SKIN = bundled_scene_dir().parent / "tools" / "hemisphere_skin.inp"

SCENE = f"""\
name: small-cap
tool: {{surface: hemisphere, radius_mm: 100}}
ply: {{node_spacing_mm: 5, size_mm: [100, 100]}}
start: {{point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90}}
export: {{mesh: {SKIN}, prefix: CAP}}
outputs: [drape]
"""


def test_export_command_writes_the_calculix_include(tmp_path) -> None:
    scene = tmp_path / "small-cap.yaml"
    scene.write_text(SCENE)
    out = tmp_path / "out"
    args = ["export", "plain-weave-600", "calculix", "--scene", str(scene), "--out", str(out)]
    result = CliRunner().invoke(cli, [*args, "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["written"] == {"calculix": "drape_calculix.inp"}
    mesh = report["mesh"]
    assert 0 < mesh["elements_uncovered"] < mesh["elements"]  # a 100 mm ply, a 176 mm skin
    text = (out / "drape_calculix.inp").read_text()
    sections = re.findall(r"^\*SHELL SECTION, ELSET=CAP_E(\d+), MATERIAL=CAP_FABRIC", text, re.M)
    orientations = re.findall(r"^\*ORIENTATION, NAME=CAP_U(\d+), SYSTEM=RECTANGULAR$", text, re.M)
    assert len(sections) == mesh["elements_covered"] and sections == orientations
    assert not set(map(int, sections)) & set(mesh["uncovered_element_ids"])
    assert "DISTRIBUTION" not in text  # nothing ccx would ignore
    assert f"uncovered: {mesh['elements_uncovered']} (ELSET=CAP_UNCOVERED" in text


def test_calculix_needs_a_mesh(tmp_path) -> None:
    scene = tmp_path / "s.yaml"
    scene.write_text(SCENE.replace(f"mesh: {SKIN}, ", ""))
    result = CliRunner().invoke(
        cli, ["export", "plain-weave-600", "calculix", "--scene", str(scene)]
    )
    assert result.exit_code == 2
    assert "calculix" in result.output and "--mesh FILE" in result.output
