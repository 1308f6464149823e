"""The pipeline at its edges: a scene whose drape leaves no valid cell, and a fabric whose shear
law cannot be built, in one run with healthy cases.

Why: a library run covers many fabrics; one impossible case must be recorded as failed with
its error while every other case completes, and a drape with nothing on the tool must come out
as an honest, empty result (strict JSON, zero energy), not a crash or a NaN in the table.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from preform.pipeline.runner import make_cases, run_cases
from preform.pipeline.scene import load_scene
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
- name: law-raises
  architecture: woven
  source: test
  note: "as-woven tow fraction above the packing cap: the law refuses to build"
  tow_types:
    t: {fibre: glass, linear_density_tex: 600, width_mm: 3.0, height_mm: 0.2}
  warp: {tow_spacing_mm: 4.0, tow_type: t}
  weft: {tow_spacing_mm: 4.0, tow_type: t}
  weave: {pattern: plain}
  shear_law: {law: friction_compaction, pretension_N: 50, fabric_thickness_mm: 1.0e-6}
"""

#: d larger than the tool's diameter: only the start node is placed, no cell is valid.
EMPTY_DRAPE = """
name: no-cells
tool: {surface: hemisphere, radius_mm: 10}
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


def test_failed_cases_are_recorded_and_the_rest_complete(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    lib_path = tmp_path / "fabrics.yaml"
    lib_path.write_text(FABRICS)
    lib = sandbox.library([lib_path])
    scenes = []
    for name, text in (("no-cells", EMPTY_DRAPE), ("small", SMALL_DRAPE)):
        path = tmp_path / f"{name}.yaml"
        path.write_text(text)
        scenes.append(load_scene(path, sandbox.registry))
    out = tmp_path / "run"
    cases = make_cases(lib, scenes, out, sandbox.host, discover=False)
    report = run_cases(cases, out, sandbox.host, engine="serial")
    by_id = {r.case_id: r for r in report.results}
    assert set(by_id) == {f"{s}/{m}" for s in ("no-cells", "small") for m in lib.names()}

    for scene in ("no-cells", "small"):
        failed = by_id[f"{scene}/law-raises"]
        assert failed.status == "failed"
        assert failed.error and "ValueError" in failed.error and "packing cap" in failed.error

    empty = by_id["no-cells/good-weave"]
    assert empty.status == "ok", empty.error
    assert empty.results["cells_valid"] == 0 and empty.results["nodes_placed"] == 1
    assert empty.results["total_energy_J"] == 0.0 and empty.results["complete"] is False
    assert by_id["small/good-weave"].status == "ok"
    assert by_id["small/good-weave"].results["cells_valid"] > 0

    manifest = json.loads((out / "manifest.json").read_text())
    for case_id, result in by_id.items():
        assert manifest["cases"][case_id]["status"] == result.status

    def refuse(constant: str) -> None:
        pytest.fail(f"non-strict JSON constant {constant}")

    for summary in out.rglob("summary.json"):
        # Strict JSON: Python's json accepts NaN unless told not to.
        json.loads(summary.read_text(), parse_constant=refuse)
    assert (out / "results.csv").exists()
