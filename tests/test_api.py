"""The Python API (``preform.drape``, ``least_energy``, ``run``, ``scene``): the pipeline's own
cases, statuses and files, in mm and degrees. The docs' examples run in tests/docs."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

import preform
from preform.cli import cli
from preform.pipeline.scene import SceneError
from preform.plugins.surfaces.mesh import tessellate_hemisphere, write_stl

HAT = {
    "name": "hat",
    "tool": {"surface": "mesh", "file": "hat_mould.obj"},
    "ply": {"node_spacing_mm": 10, "size_mm": [360, 360]},
    "start": {"point_mm": [0, 0], "generator_angle_deg": 90},
    "outputs": ["drape", "cells_csv"],
}


def cli_json(*args: str) -> dict:
    result = CliRunner().invoke(cli, [*args, "--json"])
    assert result.exit_code in (0, 1), result.stderr
    return json.loads(result.stdout)


def test_import_preform_stays_light():
    code = (
        "import sys, preform; "
        "print(sorted(m for m in ('preform.api', 'pandas', 'matplotlib', 'scipy') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_partial_drape_has_the_pipelines_status_reasons_and_fraction(tmp_path):
    scene_file = tmp_path / "hat.yaml"
    import yaml

    scene_file.write_text(yaml.safe_dump({**HAT, "tool": HAT["tool"]}))
    piped = cli_json(
        "pipeline", "run", "--scene", str(scene_file), "--materials", "plain-weave-600",
        "--engine", "serial", "--out", str(tmp_path / "run"),
    )["cases"][0]  # fmt: skip
    d = preform.drape("plain-weave-600", HAT)
    assert piped["status"] == d.status == "partial"
    assert d.reasons == piped["reasons"] and d.reasons
    assert d.summary["covered_fraction"] == pytest.approx(piped["covered_fraction"])
    assert not d.ok
    d.raise_for_status()  # partial is a result: nothing raised


def test_a_failed_drape_is_returned_with_its_error_and_has_no_cells(tmp_path):
    write_stl(tmp_path / "dome.stl", tessellate_hemisphere(0.010, 8))
    scene = preform.scene(
        {
            "name": "no-cells",
            "tool": {"surface": "mesh", "file": str(tmp_path / "dome.stl")},
            "ply": {"node_spacing_mm": 50, "size_mm": [100, 100]},
            "start": {"point_mm": [0, 0]},
            "outputs": ["drape"],
        }
    )
    d = preform.drape("plain-weave-600", scene)
    assert d.status == "failed" and "the drape has no cell" in (d.error or "")
    with pytest.raises(preform.CaseFailure, match="the drape has no cell"):
        d.raise_for_status()
    with pytest.raises(preform.CaseFailure, match="has no drape"):
        d.to_pandas()


def test_drape_results_are_in_mm_and_degrees(tmp_path):
    d = preform.drape(
        "plain-weave-600",
        tool={"surface": "hemisphere", "radius_mm": 50},
        ply_size_mm=(180, 180),
        node_spacing_mm=4,
        generator_angle_deg=70,
    )
    assert d.ok, d.error
    cells = d.to_pandas()
    valid = cells[cells["status"] == "VALID"]
    assert valid["z_mm"].max() <= 50.0 + 1e-6 and valid["z_mm"].max() > 40.0
    assert d.generator_angle_deg == pytest.approx(70.0)
    # the summary's energy is the cells' energy densities times their undeformed area inside
    # the part (share × d²): the net runs on past the rim and is clipped to z ≥ 0
    weighted = (valid["energy_J_per_m2"] * valid["part_share"]).sum() * (4e-3) ** 2
    assert d.total_energy_J == pytest.approx(weighted, rel=1e-9)
    counted = valid[valid["in_part"]]
    assert (counted["part_share"] > 0).all() and counted["part_share"].max() == 1.0
    assert (valid[~valid["in_part"]]["part_share"] == 0).all()
    assert d.max_abs_shear_deg == pytest.approx(counted["shear_deg"].abs().max())
    import meshio

    mesh = meshio.read(d.to_vtu(tmp_path / "d.vtu"))
    assert len(mesh.cells[0].data) == len(valid)
    fig = d.plot()
    assert fig.axes  # a figure, not saved anywhere


def test_scene_keywords_change_the_scene_and_are_validated():
    scene = preform.scene("hemisphere", generator_angle_deg=75, node_spacing_mm=5)
    assert scene.start is not None and scene.start.generator_angle_deg == 75
    assert scene.ply is not None and scene.ply.node_spacing_mm == 5
    with pytest.raises(SceneError, match=r"hemisphere\.yaml:\d+:\d+: ply.node_spacing_mm"):
        preform.scene("hemisphere", node_spacing_mm=-1)
    with pytest.raises(TypeError, match="unknown scene keyword 'radius_mm'"):
        preform.drape("plain-weave-600", radius_mm=3)


def test_least_energy_matches_the_pipeline_case(tmp_path):
    piped = cli_json(
        "pipeline", "run", "--scene", "hemisphere-min-energy", "--materials", "E-BX-318",
        "--fidelity", "draft", "--engine", "serial", "--out", str(tmp_path / "run"),
    )  # fmt: skip
    summary = json.loads(
        (tmp_path / "run" / "hemisphere-min-energy" / "E-BX-318" / "summary.json").read_text()
    )
    best = preform.least_energy("E-BX-318", fidelity="draft")
    assert best.status == piped["cases"][0]["status"] == "ok"
    assert best.optimum_generator_angle_deg == pytest.approx(summary["optimum_generator_angle_deg"])
    table = best.energy_vs_angle
    assert list(table["generator_angle_deg"]) == sorted(a for a, _ in summary["energy_vs_angle"])
    assert np.all(np.diff(table["generator_angle_deg"]) > 0)
    assert best.drape.generator_angle_deg == pytest.approx(best.optimum_generator_angle_deg)


def test_run_is_pipeline_run_and_the_cli_resumes_it(tmp_path):
    out = tmp_path / "results"
    run = preform.run(scenes=["shear"], materials="E-BX*", out_dir=out, engine="serial")
    assert run.counts == {"ok": 2}
    table = run.to_pandas()
    assert set(table["material"]) == {"E-BX-318", "E-BXhd-936"}
    assert (table["status"] == "ok").all()
    assert run.summary["exit_code"] == 0
    # the command line sees the same cases with the same inputs: nothing to redo
    again = cli_json(
        "pipeline", "run", "--scene", "shear", "--materials", "E-BX*", "--engine", "serial",
        "--out", str(out),
    )  # fmt: skip
    assert again["counts"] == {"skipped": 2}


def test_run_with_a_fidelity_records_it(tmp_path):
    run = preform.run(
        scenes=["hemisphere"],
        materials="plain-weave-150",
        out_dir=tmp_path / "r",
        engine="serial",
        fidelity="draft",
    )
    assert run.to_pandas()["fidelity"].tolist() == ["draft"]
