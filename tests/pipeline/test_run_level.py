"""The run-level figure (Fig. 10) drawn on a worker of the run's engine (issue 15) is the one
the ``preform`` process draws itself, byte for byte."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

from preform.pipeline.runner import make_cases, run_cases
from preform.pipeline.scene import load_scene

SCENE = """\
name: small-study
tool: {surface: hemisphere, radius_mm: 100}
ply: {node_spacing_mm: 10, size_mm: [200, 200]}
start: {point_mm: [0, 0], orientation_deg: 0}
search: {generator_angle_deg: {min: 30, max: 150}, scan_step_deg: 20}
outputs: [optimum, library_energy_png]
"""


@pytest.fixture
def sandbox(preform_plugins):
    preform_plugins.load_builtins()
    return preform_plugins


def _run(sandbox: Any, tmp_path: Path, out: Path, engine: str, outputs: list[str]) -> Any:
    path = tmp_path / "scene.yaml"
    data = yaml.safe_load(SCENE)
    data["outputs"] = outputs
    path.write_text(yaml.safe_dump(data))
    scene = load_scene(path, sandbox.registry)
    cases = make_cases(
        sandbox.library(bundled=True), [scene], out, sandbox.host, materials_glob="plain-weave-*"
    )
    report = run_cases(cases, out, sandbox.host, engine=engine, workers=2)
    assert [r.status for r in report.results] == ["ok", "ok"], [r.error for r in report.results]
    return json.loads((out / "manifest.json").read_text())["aggregates"]


def test_the_run_level_figure_from_a_worker_is_the_one_drawn_here(sandbox, tmp_path):
    outputs = ["optimum", "library_energy_png"]
    here = _run(sandbox, tmp_path, tmp_path / "serial", "serial", outputs)
    worker = _run(sandbox, tmp_path, tmp_path / "process", "process", outputs)
    assert here == worker == {"small-study": {"library_energy_png": ["energy_vs_angle.png"]}}
    figure = Path("small-study/energy_vs_angle.png")
    assert (tmp_path / "serial" / figure).read_bytes() == (
        tmp_path / "process" / figure
    ).read_bytes()
