"""The pipeline at its edges: a drape that leaves no valid cell, in one run with a healthy case.

Why: a library run covers many fabrics and scenes; a case whose drape has nothing on the tool
must be recorded ``failed`` with the reason in words (not reported ``ok`` with one node and no
cell), while every other case completes, and every summary stays strict JSON.

The scene with no cell uses a mesh tool: its size is unknown until the mesh is read, so scene
validation cannot refuse the spacing and the drape step must (an analytic tool's spacing is
refused at validation: ``tests/hostile/test_scenes_hostile.py``).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from preform.pipeline.runner import make_cases, run_cases
from preform.pipeline.scene import load_scene
from preform.plugins.surfaces.mesh import tessellate_hemisphere, write_stl
from preform.testing import PluginSandbox

FABRICS = """
- name: good-weave
  architecture: woven
  source: test
  note: test
  tow_types:
    t: {fibre: glass, linear_density_tex: 600, width_mm: 3.0, height_mm: 0.2}
  warp: {tow_spacing_mm: 4.0, tow_type: t}
  weft: {tow_spacing_mm: 4.0, tow_type: t}
  weave: {pattern: plain}
  shear_law: {law: friction_compaction, pretension_N: 50, fabric_thickness_mm: 1.0}
"""

#: d larger than the tool's diameter: only the start node is placed, no cell is valid.
EMPTY_DRAPE = """
name: no-cells
tool: {surface: mesh, file: dome.stl}
ply: {node_spacing_mm: 50, size_mm: [100, 100]}
start: {point_mm: [0, 0], generator_angle_deg: 90}
outputs: [drape, cells_csv]
"""

SMALL_DRAPE = """
name: small
tool: {surface: hemisphere, radius_mm: 100}
ply: {node_spacing_mm: 20, size_mm: [200, 200]}
start: {point_mm: [0, 0], generator_angle_deg: 80}
outputs: [drape]
"""


@pytest.fixture
def sandbox(preform_plugins: PluginSandbox) -> PluginSandbox:
    preform_plugins.load_builtins()
    return preform_plugins


def test_a_drape_without_cells_fails_and_the_rest_complete(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    lib_path = tmp_path / "fabrics.yaml"
    lib_path.write_text(FABRICS)
    lib = sandbox.library([lib_path])
    write_stl(tmp_path / "dome.stl", tessellate_hemisphere(0.010, 8))
    scenes = []
    for name, text in (("no-cells", EMPTY_DRAPE), ("small", SMALL_DRAPE)):
        path = tmp_path / f"{name}.yaml"
        path.write_text(text)
        scenes.append(load_scene(path, sandbox.registry))
    out = tmp_path / "run"
    cases = make_cases(lib, scenes, out, sandbox.host, discover=False)
    report = run_cases(cases, out, sandbox.host, engine="serial")
    by_id = {r.case_id: r for r in report.results}
    assert set(by_id) == {"no-cells/good-weave", "small/good-weave"}

    empty = by_id["no-cells/good-weave"]
    assert empty.status == "failed"
    assert empty.error is not None and "the drape has no cell" in empty.error
    assert "node spacing 50 mm" in empty.error
    assert not (out / "no-cells" / "good-weave" / "cells.csv").exists()
    assert by_id["small/good-weave"].status == "ok", by_id["small/good-weave"].error
    assert by_id["small/good-weave"].results["cells_valid"] > 0

    def refuse(constant: str) -> None:
        pytest.fail(f"non-strict JSON constant {constant}")

    for summary in out.rglob("summary.json"):
        # Strict JSON: Python's json accepts NaN unless told not to.
        json.loads(summary.read_text(), parse_constant=refuse)


HAT_SCENE = """
name: hat
tool: {surface: mesh, file: hat_mould.obj}
ply: {node_spacing_mm: 10, size_mm: [360, 360]}
start: {point_mm: [0, 0], generator_angle_deg: 90}
outputs: [drape, cells_csv]
"""


def test_a_run_records_partial_and_warnings_in_words(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    """Through the runner: the hat mould is partial with its covered fraction and why; the
    hemisphere is ok, with its cells past locking said in words; summary.json carries both."""
    lib_path = tmp_path / "fabrics.yaml"
    lib_path.write_text(FABRICS)
    lib = sandbox.library([lib_path])
    scenes = []
    for name, text in (("hat", HAT_SCENE), ("small", SMALL_DRAPE)):
        path = tmp_path / f"{name}.yaml"
        path.write_text(text)
        scenes.append(load_scene(path, sandbox.registry))
    out = tmp_path / "run"
    cases = make_cases(lib, scenes, out, sandbox.host, discover=False)
    report = run_cases(cases, out, sandbox.host, engine="serial")
    by_id = {r.case_id: r for r in report.results}

    hat = by_id["hat/good-weave"]
    assert hat.status == "partial", hat.error
    (reason,) = hat.reasons
    fraction = hat.results["covered_fraction"]
    # the band over the block and down its walls is placed, the block corners' shadows fold
    assert 0.3 < fraction < 0.8
    assert reason.startswith(f"the net covers {100 * fraction:.1f} % of the ply's fabric area")
    written = json.loads((out / "hat" / "good-weave" / "summary.json").read_text())
    assert written["status"] == "partial" and written["reasons"] == [reason]
    assert written["covered_fraction"] == fraction and written["complete"] is False

    dome = by_id["small/good-weave"]
    assert dome.status == "ok" and dome.reasons == []
    assert dome.results["covered_fraction"] == 1.0
    locking = [w for w in dome.warnings if "past the locking angle" in w]
    assert len(locking) == (1 if dome.results["cells_past_locking"] else 0)
