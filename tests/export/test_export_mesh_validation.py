"""A scene's ``export.mesh`` is checked at validation, like a tool mesh file: missing,
unreadable, empty, not a regular file, too large or of no known format is refused there,
located at the key (FILE:LINE:COL: export.mesh: message), before anything is draped."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from preform.pipeline.scene import SceneError, bundled_scene_dir, load_scene
from preform.plugin_manager import default_host

SKIN = bundled_scene_dir().parent / "tools" / "hemisphere_skin.inp"

SCENE = """\
name: mesh-check
tool: {{surface: hemisphere, radius_mm: 100}}
ply: {{node_spacing_mm: 10, size_mm: [100, 100]}}
start: {{point_mm: [0, 0]}}
limits: {{max_mesh_mb: {mb}}}
export:
  seam_allowance_mm: 2
  mesh: {mesh}
outputs: [drape, element_table]
"""
#: Line and column of the ``mesh`` key in SCENE.
MESH_KEY = (8, 3)


def scene_file(tmp_path: Path, mesh: str | Path, mb: float = 512) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE.format(mesh=mesh, mb=mb))
    return path


def refusal(path: Path) -> str:
    """The single located error of a refused scene, checked to be at the mesh key."""
    with pytest.raises(SceneError) as info:
        load_scene(path, default_host().registry)
    (error,) = (str(e) for e in info.value.errors)
    prefix = f"{path}:{MESH_KEY[0]}:{MESH_KEY[1]}: export.mesh: "
    assert error.startswith(prefix), error
    return error[len(prefix) :]


def test_a_readable_mesh_passes(tmp_path) -> None:
    scene, _ = load_scene(scene_file(tmp_path, SKIN), default_host().registry)
    assert scene.export is not None and scene.export.mesh == str(SKIN)


def test_missing_mesh_relative_to_the_scene(tmp_path) -> None:
    assert refusal(scene_file(tmp_path, "nothere.inp")).endswith("nothere.inp: no such file")


def test_a_directory_an_empty_file_and_an_unknown_format(tmp_path) -> None:
    (tmp_path / "dir.inp").mkdir()
    assert "is a directory" in refusal(scene_file(tmp_path, "dir.inp"))
    (tmp_path / "empty.inp").write_text("")
    assert "is empty" in refusal(scene_file(tmp_path, "empty.inp"))
    (tmp_path / "mesh.xyz").write_text("1 2 3\n")
    assert "no reader for '.xyz' files" in refusal(scene_file(tmp_path, "mesh.xyz"))


def test_a_fifo_is_refused_without_opening_it(tmp_path) -> None:
    os.mkfifo(tmp_path / "pipe.inp")
    assert "not a regular file" in refusal(scene_file(tmp_path, "pipe.inp"))


def test_a_mesh_larger_than_the_limit(tmp_path) -> None:
    (tmp_path / "big.inp").write_text("*NODE\n" + "1, 0, 0, 0\n" * 200)
    message = refusal(scene_file(tmp_path, "big.inp", mb=0.001))
    assert "larger than the limit of 0.001 MB (limits.max_mesh_mb)" in message


@pytest.mark.skipif(os.geteuid() == 0, reason="root opens any file")
def test_an_unreadable_mesh(tmp_path) -> None:
    path = tmp_path / "locked.inp"
    path.write_text(SKIN.read_text())
    path.chmod(0)
    try:
        assert "cannot be opened: Permission denied" in refusal(scene_file(tmp_path, "locked.inp"))
    finally:
        path.chmod(0o644)
