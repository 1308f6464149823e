"""One flat pattern: ``cut_pattern``. The staircase output ``flat_pattern`` it replaced is
refused where it can be named (a scene's outputs, ``preform export``'s targets, the writers in
``preform.export``), each time with a message naming what replaced it."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from preform.cli import build_cli

SCENE = """\
name: small-hemisphere
tool: {surface: hemisphere, radius_mm: 50}
ply: {node_spacing_mm: 10, size_mm: [160, 160]}
start: {point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90}
outputs: [drape, OUTPUT]
"""


def run(*args: str):
    return CliRunner().invoke(build_cli(), list(args), catch_exceptions=False)


def test_a_scene_asking_for_flat_pattern_is_refused_naming_cut_pattern(tmp_path) -> None:
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENE.replace("OUTPUT", "flat_pattern"))
    result = run("pipeline", "run", "--scene", str(scene), "--materials", "plain-weave-150",
                 "--engine", "serial", "--out", str(tmp_path / "out"))  # fmt: skip
    assert result.exit_code == 2, result.output
    assert "'flat_pattern'" in result.stderr and "'cut_pattern'" in result.stderr
    assert "did you mean" not in result.stderr  # the message, not a spelling guess
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").rglob("*.dxf"))


def test_the_replacement_is_planned_where_the_old_name_is_refused(tmp_path) -> None:
    from preform.pipeline.planner import PlanError, plan
    from preform.pipeline.scene import SceneError, load_scene
    from preform.plugin_manager import default_host

    registry = default_host().registry
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENE.replace("OUTPUT", "cut_pattern"))
    loaded, _ = load_scene(scene, registry)
    assert "cut_pattern" in [s.name for s in plan(loaded, registry)]
    assert "flat_pattern" not in registry.providers()
    scene.write_text(SCENE.replace("OUTPUT", "flat_pattern"))
    with pytest.raises((PlanError, SceneError)) as error:
        loaded, _ = load_scene(scene, registry)
        plan(loaded, registry)
    # located at the output, as any scene error
    assert f"{scene}:5:" in str(error.value) and "replaced by 'cut_pattern'" in str(error.value)


def test_the_export_target_flat_pattern_is_refused_naming_cut_pattern(tmp_path) -> None:
    result = run("export", "plain-weave-150", "flat-pattern", "--out", str(tmp_path / "x"))
    assert result.exit_code == 2
    assert "'flat-pattern' is now 'cut-pattern'" in result.stderr
    assert not (tmp_path / "x").exists()
    listed = run("export", "--help").stdout
    assert "cut-pattern" in listed and "flat-pattern" not in listed


@pytest.mark.parametrize("kind", ["csv", "dxf", "svg"])
def test_the_staircase_writers_are_refused_naming_the_cut_pattern_writers(kind) -> None:
    import preform.export

    with pytest.raises(AttributeError, match=f"use write_cut_pattern_{kind}"):
        getattr(preform.export, f"write_flat_pattern_{kind}")
    assert f"write_flat_pattern_{kind}" not in preform.export.__all__
    assert callable(getattr(preform.export, f"write_cut_pattern_{kind}"))
