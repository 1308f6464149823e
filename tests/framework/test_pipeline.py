"""The pipeline: lazy planning, failure isolation, identical engines, resumable runs."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pandas as pd
import pytest

from preform.base.atomic import is_temporary_name
from preform.pipeline.planner import PlanError, plan
from preform.pipeline.runner import make_cases, run_cases
from preform.pipeline.scene import SceneError, load_scene

LIBRARY = """\
- {name: felt-a, architecture: toy, source: s, note: n, areal_density_g_m2: 100}
- {name: felt-b, architecture: toy, source: s, note: n, areal_density_g_m2: 200}
- {name: explodes, architecture: toy, source: s, note: n, areal_density_g_m2: 300}
- {name: felt-c, architecture: toy, source: s, note: n, areal_density_g_m2: 400}
"""


@pytest.fixture
def toy(preform_plugins, third_party_site, tmp_path, monkeypatch):
    import toyplug

    preform_plugins.register(toyplug, "toy")
    log = tmp_path / "steps.log"
    monkeypatch.setenv("TOY_STEP_LOG", str(log))
    lib_path = tmp_path / "lib.yaml"
    lib_path.write_text(LIBRARY)
    return preform_plugins, lib_path, log


def scene_file(tmp_path: Path, outputs: list[str], name: str = "toy-scene") -> Path:
    p = tmp_path / f"{name}.yaml"
    p.write_text(f"name: {name}\noutputs: {json.dumps(outputs)}\n")
    return p


def calls(log: Path) -> list[str]:
    return log.read_text().split() if log.exists() else []


def test_planner_runs_only_what_outputs_need(toy, tmp_path):
    sandbox, lib_path, log = toy
    lib = sandbox.library([lib_path])
    scene = load_scene(scene_file(tmp_path, ["mass_txt"]), sandbox.registry)
    assert [s.name for s in plan(scene[0], sandbox.registry)] == ["mass", "mass_txt"]
    report = run_cases(
        make_cases(lib, [scene], tmp_path / "out", sandbox.host),
        tmp_path / "out",
        sandbox.host,
        engine="serial",
    )
    # four fabrics: mass ran four times, mass_txt three (explodes fails first), heavy never
    assert sorted(calls(log)) == sorted(["mass"] * 4 + ["mass_txt"] * 3)
    assert [r.status for r in report.results] == ["ok", "ok", "failed", "ok"]
    assert "RuntimeError: this fabric always fails" in report.results[2].error


def test_unknown_output_is_a_located_scene_error(toy, tmp_path):
    sandbox, _, _ = toy
    p = scene_file(tmp_path, ["mass_txt", "hevy"])
    with pytest.raises(SceneError) as info:
        load_scene(p, sandbox.registry)
    (err,) = info.value.errors
    assert str(err).startswith(f"{p}:2:")
    assert "unknown output 'hevy'" in str(err) and "did you mean 'heavy'" in str(err)


def test_plan_error_lists_available_outputs(toy, tmp_path):
    sandbox, _, _ = toy
    scene, _ = load_scene(scene_file(tmp_path, ["heavy"]), sandbox.registry)
    bad = scene.model_copy(update={"outputs": ["nothing"]})
    with pytest.raises(PlanError) as info:
        plan(bad, sandbox.registry)
    assert "available outputs:" in str(info.value) and "mass_txt" in str(info.value)


def read_results(out: Path) -> pd.DataFrame:
    df = pd.read_csv(out / "results.csv")
    timing = ("wall_time_s", "finished")
    return df.drop(columns=[c for c in df.columns if c.startswith("time_") or c in timing])


@pytest.mark.parametrize("engine", ["process", "dask"])
def test_engines_give_identical_results(toy, tmp_path, engine, monkeypatch):
    sandbox, lib_path, _ = toy
    # workers discover plugins through entry points: let them find the toy distribution
    monkeypatch.setenv("PREFORM_LOAD_PLUGINS", "toy")
    lib = sandbox.library([lib_path])
    scene = load_scene(scene_file(tmp_path, ["mass_txt", "heavy"]), sandbox.registry)
    serial_out, other_out = tmp_path / "serial", tmp_path / engine
    run_cases(
        make_cases(lib, [scene], serial_out, sandbox.host),
        serial_out,
        sandbox.host,
        engine="serial",
    )
    run_cases(
        make_cases(lib, [scene], other_out, sandbox.host),
        other_out,
        sandbox.host,
        engine=engine,
        workers=2,
    )
    pd.testing.assert_frame_equal(read_results(serial_out), read_results(other_out))
    for case in ("felt-a", "felt-b", "felt-c"):
        a = (serial_out / "toy-scene" / case / "mass.txt").read_text()
        b = (other_out / "toy-scene" / case / "mass.txt").read_text()
        assert a == b
    status = json.loads((other_out / "manifest.json").read_text())["cases"]
    assert status["toy-scene/explodes"]["status"] == "failed"


def test_interrupted_run_resumes_without_redoing_or_corrupting(toy, tmp_path):
    _, lib_path, log = toy
    scene = scene_file(tmp_path, ["mass_txt", "crash"])
    out = tmp_path / "out"
    env = {**os.environ, "PREFORM_LOAD_PLUGINS": "core,toy", "TOY_CRASH_ON": "felt-c"}
    cmd = [
        sys.executable,
        "-m",
        "preform",
        "pipeline",
        "run",
        str(lib_path),
        "--no-bundled",  # LIBRARY adds to the bundled library
        "--scene",
        str(scene),
        "--out",
        str(out),
        "--engine",
        "serial",
    ]
    first = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert first.returncode == 3  # the process died inside the felt-c case
    done_first = calls(log).count("mass_txt")
    # felt-a, felt-b finished; felt-c died in its crash step (planned before mass_txt: the
    # planner orders independent steps by name), so its folder has no summary: not done
    assert done_first == 2
    assert not (out / "toy-scene" / "felt-c" / "mass.txt").exists()
    assert not (out / "toy-scene" / "felt-c" / "summary.json").exists()
    # nothing half-written: every JSON parses, no temporary files are left to be mistaken
    for f in out.rglob("*.json"):
        json.loads(f.read_text())
    # what finished before the crash is recorded, and the tables are current
    manifest = json.loads((out / "manifest.json").read_text())
    assert {k: v["status"] for k, v in manifest["cases"].items()} == {
        "toy-scene/felt-a": "ok",
        "toy-scene/felt-b": "ok",
        "toy-scene/explodes": "failed",
        "toy-scene/felt-c": "pending",
    }
    assert list(pd.read_csv(out / "results.csv")["material"]) == ["explodes", "felt-a", "felt-b"]
    log.unlink()
    env.pop("TOY_CRASH_ON")
    second = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert second.returncode == 1, second.stderr  # explodes still fails, and says so
    # the resumed run redid only the unfinished cases: felt-c and the failed one
    assert sorted(calls(log)) == sorted(["mass", "mass", "mass_txt", "crash"])
    manifest = json.loads((out / "manifest.json").read_text())
    statuses = {k: v["status"] for k, v in manifest["cases"].items()}
    assert statuses == {
        "toy-scene/felt-a": "ok",
        "toy-scene/felt-b": "ok",
        "toy-scene/explodes": "failed",
        "toy-scene/felt-c": "ok",
    }
    assert manifest["runs"][-1]["counts"] == {"skipped": 2, "failed": 1, "ok": 1}
    assert "2 skipped" in second.stdout
    assert not [f for f in out.rglob("*") if is_temporary_name(f.name)]
    table = pd.read_csv(out / "results.csv")
    assert list(table["material"]) == ["explodes", "felt-a", "felt-b", "felt-c"]
    assert list(table["mass_g"].fillna(-1)) == [-1, 200.0, 400.0, 800.0]
    # --force redoes everything
    log.unlink()
    subprocess.run([*cmd, "--force"], env=env, capture_output=True, text=True, timeout=120)
    assert calls(log).count("mass") == 4


def test_manifest_records_inputs_and_versions(toy, tmp_path):
    _, lib_path, _ = toy
    scene = scene_file(tmp_path, ["mass"])
    out = tmp_path / "out"
    env = {**os.environ, "PREFORM_LOAD_PLUGINS": "core,toy"}
    subprocess.run(
        [
            sys.executable,
            "-m",
            "preform",
            "pipeline",
            "run",
            str(lib_path),
            "--no-bundled",  # LIBRARY adds to the bundled library
            "--scene",
            str(scene),
            "--out",
            str(out),
            "--engine",
            "serial",
            "--materials",
            "felt-*",
        ],
        env=env,
        check=True,
        capture_output=True,
    )
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["preform_version"]
    assert {p["name"] for p in manifest["plugins"]} == {"core", "toy"}
    (lib_rec,) = manifest["inputs"]["libraries"]
    import hashlib

    assert lib_rec["sha256"] == hashlib.sha256(lib_path.read_bytes()).hexdigest()
    assert sorted(manifest["cases"]) == ["toy-scene/felt-a", "toy-scene/felt-b", "toy-scene/felt-c"]


def test_explain_prints_plan_without_running(toy, tmp_path):
    _, lib_path, log = toy
    scene = scene_file(tmp_path, ["heavy"])
    env = {**os.environ, "PREFORM_LOAD_PLUGINS": "core,toy"}
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "preform",
            "pipeline",
            "run",
            str(lib_path),
            "--no-bundled",  # LIBRARY adds to the bundled library
            "--scene",
            str(scene),
            "--explain",
        ],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    assert "mass (v1)" in res.stdout and "heavy (v1): needs mass" in res.stdout
    assert calls(log) == []
    assert textwrap.dedent(res.stdout).count("->") == 2
