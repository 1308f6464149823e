"""``preform export [NAME]... TARGET... --scene LAYUP``: a layup scene's stack exported from the
command line, its CalculiX deck run in ccx, and its bad input refused where it is.

The truths: the same stack through ``preform.layup`` (the API's pipeline path) writes the same
decks; in ccx, the 8 x 8 S8R cap of docs/examples/calculix_cap_mesh.inp (square in plan, so
symmetric under a quarter turn about z) pulled at its pole along x with both plies at 0° moves
as it does pulled along y with both at 90° (the drape of a balanced weave turned a quarter
turn), and differently from the 90° stack pulled along x (so ccx applies the orientations).
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import preform
from preform.cli import cli

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
MESH = EXAMPLES / "calculix_cap_mesh.inp"
#: An illustrative orthotropic ply (MPa): E1, E2, E3, ν12, ν13, ν23, G12, G13, G23.
MODULI = (140000.0, 10000.0, 10000.0, 0.3, 0.3, 0.5, 5000.0, 5000.0, 3500.0)


def write_scene(folder: Path, scene: dict) -> Path:
    """The scene as YAML (JSON is YAML) beside a copy of the mesh it names relatively."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(MESH, folder)
    path = folder / "cap-stack.yaml"
    path.write_text(json.dumps(scene))
    return path


def export(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(cli, ["export", *args])
    return result.exit_code, result.stdout, result.stderr


def test_a_layup_scenes_stack_exports_to_every_solver_as_the_api_writes_it(
    tmp_path, cap_layup
) -> None:
    scene = cap_layup([("plain-weave-600", 0), ("satin-4hs-crowfoot", 45)], MESH.name)
    path = write_scene(tmp_path / "scene", scene)
    out = tmp_path / "out"
    code, stdout, stderr = export(
        "abaqus", "calculix", "lsdyna", "ansys", "table", "cut-pattern", "vtu",
        "--scene", str(path), "--out", str(out), "--json",
    )  # fmt: skip
    assert code == 0, stderr
    report = json.loads(stdout)
    assert report["status"] == "ok" and report["material"] == "plain-weave-600+satin-4hs-crowfoot"
    assert report["written"] == {
        "abaqus": "stack_abaqus.inp",
        "calculix": "stack_calculix.inp",
        "lsdyna": "stack_lsdyna.k",
        "ansys": "stack_ansys.mac",
        "table": "stack_elements.csv",
        "cut-pattern": [
            f"{ply}/cut_pattern.{kind}"
            for ply in ("ply-1-plain-weave-600", "ply-2-satin-4hs-crowfoot")
            for kind in ("dxf", "svg", "csv")
        ],
        "vtu": ["ply-1-plain-weave-600/elements.vtu", "ply-2-satin-4hs-crowfoot/elements.vtu"],
    }
    assert [(p["name"], p["offset_mm"]) for p in report["plies"]] == [
        ("ply-1-plain-weave-600", 0.0),
        ("ply-2-satin-4hs-crowfoot", 0.5),
    ]
    mesh = report["mesh"]
    assert mesh["mesh"] == "calculix_cap_mesh.inp"  # the file's name, never its folder
    assert mesh["elements"] == mesh["elements_all_plies"] == 64
    for files in report["written"].values():
        for name in [files] if isinstance(files, str) else files:
            assert (out / name).stat().st_size > 0, name
    # atomic writes leave no temporary behind
    assert not [p for p in out.rglob("*") if ".preform-tmp" in p.name]
    table = pd.read_csv(out / "stack_elements.csv")
    assert (table["plies_present"] == 2).all()
    np.testing.assert_allclose(table["total_thickness_mm"], 1.0, rtol=0.05)
    # the API's pipeline path, with the same scene and the decks as outputs, writes the same
    api_scene = {**scene, "export": {**scene["export"], "mesh": str(MESH)}}
    api_scene["outputs"] = ["layup", "stack_sections"] + [
        f"stack_{t}" for t in ("abaqus", "calculix", "lsdyna", "ansys")
    ]
    stack = preform.layup(api_scene, out_dir=tmp_path / "api")
    assert stack.status == "ok", stack.error
    for target in ("abaqus", "calculix", "lsdyna", "ansys"):
        name = report["written"][target]
        assert (out / name).read_text() == (stack.case_dir / name).read_text(), name


def pulled(tmp_path: Path, ccx, folder: Path, direction: int, tag: str) -> np.ndarray:
    """ccx on the exported stack: the cap held at its rim, pulled at its pole along
    ``direction`` (1 x, 2 y); the pole's displacement [mm]."""
    card = ", ".join(f"{v:.6g}" for v in MODULI[:8]) + f"\n{MODULI[8]:.6g}, 0.\n"
    job = tmp_path / f"ccx-{tag}"
    job.mkdir()
    shutil.copy(MESH, job)
    shutil.copy(folder / "stack_calculix.inp", job)
    (job / "cap.inp").write_text(
        "*INCLUDE, INPUT=calculix_cap_mesh.inp\n"
        f"*MATERIAL, NAME=plain-weave-600\n*ELASTIC, TYPE=ENGINEERING CONSTANTS\n{card}"
        "*INCLUDE, INPUT=stack_calculix.inp\n*BOUNDARY\nRIM, 1, 3\n*STEP\n*STATIC\n"
        f"*CLOAD\nPOLE, {direction}, 1.\n*NODE PRINT, NSET=POLE\nU\n*END STEP\n"
    )
    ccx(job, "cap")
    rows = re.findall(r"^\s*\d+\s+(\S+)\s+(\S+)\s+(\S+)\s*$", (job / "cap.dat").read_text(), re.M)
    assert rows
    return np.array([float(v) for v in rows[-1]])


def test_the_exported_stack_deck_runs_in_calculix_and_its_orientations_take_effect(
    tmp_path, ccx, cap_layup
) -> None:
    folders = {}
    for angle in (0, 90):
        # a NAME per ply replaces the scene's fabrics: both plies the plain weave
        path = write_scene(
            tmp_path / f"scene-{angle}",
            cap_layup([("satin-4hs-crowfoot", angle)] * 2, MESH.name),
        )
        folders[angle] = tmp_path / f"out-{angle}"
        code, _, stderr = export(
            "plain-weave-600", "plain-weave-600", "calculix",
            "--scene", str(path), "--out", str(folders[angle]),
        )  # fmt: skip
        assert code == 0, stderr
        assert "satin" not in (folders[angle] / "stack_calculix.inp").read_text()
    along_x_0 = pulled(tmp_path, ccx, folders[0], 1, "0x")
    along_y_90 = pulled(tmp_path, ccx, folders[90], 2, "90y")
    along_x_90 = pulled(tmp_path, ccx, folders[90], 1, "90x")
    assert abs(along_x_0[0]) > 0
    # a quarter turn: (u_x of the 0° stack pulled along x) = (u_y of the 90° stack along y)
    np.testing.assert_allclose(along_y_90[1], along_x_0[0], rtol=1e-4)
    # and the orientations matter: fibres along the pull against across it
    assert abs(along_x_90[0]) > 1.5 * abs(along_x_0[0])


@pytest.mark.parametrize(
    ("words", "said"),
    [
        (["plain-weave-600", "abaqus"], "the layup has 2 plies: give no NAME"),
        (["plain-weave-600", "plain-weave-60", "abaqus"], "NAME 2 (ply 2): no fabric named"),
        (["abaqus", "plain-weave-600"], "word 2, 'plain-weave-600', follows the target"),
        (["plain-weave-600"], "no target among"),
        (["flat-pattern"], "'flat-pattern' is now 'cut-pattern'"),
        (["lsdyna", "--lsdyna-form", "beta"], "--lsdyna-form: a stack is written as"),
    ],
)
def test_bad_input_for_a_stack_is_refused_where_it_is(tmp_path, cap_layup, words, said) -> None:
    scene = cap_layup([("plain-weave-600", 0), ("plain-weave-600", 90)], MESH.name)
    path = write_scene(tmp_path / "scene", scene)
    code, _, stderr = export(*words, "--scene", str(path), "--out", str(tmp_path / "out"))
    assert code == 2 and said in stderr, stderr
    assert not (tmp_path / "out").exists()  # nothing was run


def test_a_layup_fabric_the_library_lacks_is_located_at_its_ply(tmp_path, cap_layup) -> None:
    scene = cap_layup([("plain-weave-600", 0), ("nosuch", 90)], MESH.name)
    path = write_scene(tmp_path / "scene", scene)
    code, _, stderr = export("abaqus", "--scene", str(path), "--out", str(tmp_path / "out"))
    assert code == 2 and "layup.plies[1].fabric: no fabric named 'nosuch'" in stderr, stderr


def test_a_stack_needs_the_mesh_and_a_single_ply_scene_one_name(tmp_path, cap_layup) -> None:
    scene = cap_layup([("plain-weave-600", 0), ("plain-weave-600", 90)], MESH.name)
    del scene["export"]["mesh"]
    path = write_scene(tmp_path / "scene", scene)
    code, _, stderr = export("calculix", "--scene", str(path), "--out", str(tmp_path / "out"))
    assert code == 2 and "need your mesh: --mesh FILE" in stderr, stderr
    code, _, stderr = export(
        "plain-weave-600", "plain-weave-150", "cut-pattern", "--out", str(tmp_path / "one")
    )
    assert code == 2 and "has no layup, so it drapes one fabric" in stderr, stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "one").exists()


def test_reports_and_summaries_name_the_users_mesh_by_its_file_name(tmp_path) -> None:
    """Issue 26: a report goes to other machines, where the folder the mesh was read from
    means nothing; the decks already named the file only."""
    folder = tmp_path / "somewhere" / "deep"
    folder.mkdir(parents=True)
    shutil.copy(MESH, folder / "my_cap.inp")
    scene = tmp_path / "small.yaml"
    scene.write_text(
        "name: small\ntool: {surface: hemisphere, radius_mm: 100}\n"
        "ply: {node_spacing_mm: 10, size_mm: [60, 60]}\n"
        "start: {point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90}\n"
        f"export: {{mesh: {folder / 'my_cap.inp'}}}\noutputs: [drape, abaqus_include]\n"
    )
    code, stdout, stderr = export(
        "plain-weave-600", "abaqus", "--scene", str(scene), "--out", str(tmp_path / "e"), "--json"
    )
    assert code == 0, stderr
    report = json.loads(stdout)
    assert report["status"] == "partial"  # a 60 mm ply leaves the 80 mm cap's rim bare
    assert report["mesh"]["mesh"] == "my_cap.inp"
    assert "my_cap.inp" in report["reasons"][0]
    assert "somewhere" not in stdout + stderr
    result = CliRunner().invoke(
        cli,
        ["pipeline", "run", "--scene", str(scene), "--materials", "plain-weave-600",
         "--engine", "serial", "--out", str(tmp_path / "run")],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    (summary,) = (tmp_path / "run").glob("*/*/summary.json")
    text = summary.read_text()
    assert "my_cap.inp" in text and "somewhere" not in text


def test_a_mesh_no_ply_covers_fails_and_writes_no_deck(tmp_path, cap_layup) -> None:
    """The cap read in metres as mm lies 82 m from the drape: every section would be
    missing, so the export fails (exit 1) saying how far apart they are, and writes no deck."""
    scene = cap_layup([("plain-weave-600", 0), ("plain-weave-600", 90)], MESH.name)
    path = write_scene(tmp_path / "scene", scene)
    out = tmp_path / "out"
    code, stdout, stderr = export(
        "calculix", "table", "--scene", str(path), "--mesh-unit-mm", "1000",
        "--out", str(out), "--json",
    )  # fmt: skip
    assert code == 1, stderr
    report = json.loads(stdout)
    assert report["status"] == "failed" and report["written"] == {}
    assert "no ply covers any element" in report["error"] and "mm apart" in report["error"]
    assert not list(out.glob("stack_*"))
