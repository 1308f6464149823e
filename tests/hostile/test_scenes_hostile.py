"""Hostile scenes and tool meshes (issue 10, items 9 and 10): refused up front, located, bounded.

What scene validation can know before running is refused there with FILE:LINE:COL at the
offending field and the limit a user can raise (``limits.max_nodes``, ``limits.max_mesh_mb``):
a mesh path that is missing, a directory, a device or a FIFO (never opened, so nothing hangs),
a mesh file larger than the limit (judged by ``stat``: a sparse file of gigabytes costs
nothing), a ply of 10¹⁰ nodes (arithmetic, no array), a spacing that leaves no cell, a start
point off the tool or outside the ply. A malformed mesh that only reading can reveal fails its
case at the surface step with the file's own error. The bundled scenes still validate.
"""

from __future__ import annotations

import os
import signal
import struct
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from preform.base.status import CaseFailure
from preform.drape.steps import run_surface
from preform.pipeline.scene import SceneError, bundled_scene_dir, load_scene, validate_scene_data
from preform.plugins.surfaces.mesh import (
    MeshFileError,
    read_obj,
    read_stl,
    tessellate_hemisphere,
    write_stl,
)
from preform.step import CaseContext
from preform.testing import PluginSandbox
from preform.yamlsource import load_yaml

#: CPU seconds of this process (not wall time, which a loaded machine inflates) within which
#: an oversized input must be refused: the guard is against building it first (minutes,
#: gigabytes), not a speed target.
REFUSAL_CPU_S = 2.0

MESH_SCENE = """\
name: hostile-mesh
tool:
  surface: mesh
  file: {file}
ply:
  node_spacing_mm: 10
  size_mm: [360, 360]
start:
  point_mm: [0, 0]
limits:
  max_mesh_mb: {mb}
outputs: [drape]
"""
#: Where MESH_SCENE's fields are (line, column of the key).
TOOL_FILE = (4, 3)

ANALYTIC_SCENE = """\
name: hostile-analytic
tool:
  surface: {surface}
  {dims}
ply:
  node_spacing_mm: {spacing}
  size_mm: [{ply}, {ply}]
  offset_mm: [{offset}, 0]
start:
  point_mm: [{x}, {y}]
limits:
  max_nodes: {max_nodes}
outputs: [drape]
"""
PLY = (5, 1)
SPACING = (6, 3)
OFFSET = (8, 3)
START = (10, 3)
MAX_NODES = (12, 3)


@pytest.fixture
def sandbox(preform_plugins: PluginSandbox) -> PluginSandbox:
    preform_plugins.load_builtins()
    return preform_plugins


@pytest.fixture
def no_hang() -> Iterator[None]:
    """Fail, rather than hang the suite, if anything blocks (a FIFO opened for reading)."""

    def alarm(signum: int, frame: Any) -> None:
        raise TimeoutError("blocked for 10 s: something opened the FIFO")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(10)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def mesh_scene(tmp_path: Path, file: str, mb: float = 512) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text(MESH_SCENE.format(file=file, mb=mb))
    return path


def analytic_scene(
    tmp_path: Path,
    *,
    surface: str = "hemisphere",
    dims: str = "radius_mm: 100",
    spacing: float = 10,
    ply: float = 360,
    offset: float = 0,
    x: float = 0,
    y: float = 0,
    max_nodes: int = 20_000_000,
) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text(
        ANALYTIC_SCENE.format(
            surface=surface,
            dims=dims,
            spacing=spacing,
            ply=ply,
            offset=offset,
            x=x,
            y=y,
            max_nodes=max_nodes,
        )
    )
    return path


def refused(sandbox: PluginSandbox, path: Path) -> list[str]:
    with pytest.raises(SceneError) as info:
        load_scene(path, sandbox.registry)
    return [str(e) for e in info.value.errors]


def one_error(sandbox: PluginSandbox, path: Path, at: tuple[int, int], field: str) -> str:
    """The single located error of a refused scene, checked to be at ``at`` on ``field``."""
    (error,) = refused(sandbox, path)
    prefix = f"{path}:{at[0]}:{at[1]}: {field}: "
    assert error.startswith(prefix), error
    return error[len(prefix) :]


# --------------------------------------------------------------------------------------------
# Mesh paths refused at validation, without reading (or opening) them


def test_a_missing_mesh_is_located(sandbox: PluginSandbox, tmp_path: Path) -> None:
    message = one_error(sandbox, mesh_scene(tmp_path, "nothere.stl"), TOOL_FILE, "tool.file")
    assert message == (
        f"tool mesh 'nothere.stl' not found next to the scene ({tmp_path}) nor among the "
        "bundled tools"
    )


def test_a_directory_is_not_a_mesh(sandbox: PluginSandbox, tmp_path: Path) -> None:
    (tmp_path / "tool.stl").mkdir()
    message = one_error(sandbox, mesh_scene(tmp_path, "tool.stl"), TOOL_FILE, "tool.file")
    assert message.endswith(
        "tool.stl: is a directory, not a regular file; a tool mesh must be an STL or OBJ file"
    )


@pytest.mark.parametrize("link", [False, True])
def test_dev_zero_is_refused_not_read(
    sandbox: PluginSandbox, tmp_path: Path, no_hang: None, link: bool
) -> None:
    target = "/dev/zero"
    if link:
        (tmp_path / "zero.stl").symlink_to("/dev/zero")
        target = "zero.stl"
    message = one_error(sandbox, mesh_scene(tmp_path, target), TOOL_FILE, "tool.file")
    assert "is a character device, not a regular file" in message


def test_a_fifo_is_refused_without_blocking(
    sandbox: PluginSandbox, tmp_path: Path, no_hang: None
) -> None:
    os.mkfifo(tmp_path / "pipe.stl")
    message = one_error(sandbox, mesh_scene(tmp_path, "pipe.stl"), TOOL_FILE, "tool.file")
    assert "is a FIFO (named pipe), not a regular file" in message


@pytest.mark.parametrize(
    "file, words",
    [
        ("empty.stl", "empty.stl: is empty (0 bytes); a tool mesh must be an STL or OBJ file"),
        ("/proc/self/status", "/proc/self/status: is empty (0 bytes)"),
        ("x" * 5000 + ".stl", "...' cannot be looked up: File name too long"),
        ('"a\\0b.stl"', "tool mesh 'a\\x00b.stl' not found next to the scene"),
    ],
    ids=["empty", "proc", "long-name", "nul-byte"],
)
def test_unreadable_mesh_names_are_located(
    sandbox: PluginSandbox, tmp_path: Path, no_hang: None, file: str, words: str
) -> None:
    (tmp_path / "empty.stl").write_bytes(b"")
    message = one_error(sandbox, mesh_scene(tmp_path, file), TOOL_FILE, "tool.file")
    assert words in message


def test_an_oversized_mesh_is_refused_by_its_size(sandbox: PluginSandbox, tmp_path: Path) -> None:
    big = tmp_path / "huge.stl"
    with open(big, "wb") as f:
        f.truncate(3_000_000)  # sparse: no disk, no reading
    started = time.process_time()
    message = one_error(sandbox, mesh_scene(tmp_path, "huge.stl", mb=1), TOOL_FILE, "tool.file")
    assert time.process_time() - started < 5
    assert message.endswith(
        "huge.stl: 3.0 MB, larger than the limit of 1 MB (limits.max_mesh_mb); decimate the "
        "mesh or raise limits.max_mesh_mb in the scene"
    )


def test_a_raised_mesh_limit_lets_a_gigabyte_file_validate_without_reading_it(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    big = tmp_path / "huge.stl"
    with open(big, "wb") as f:
        f.truncate(2_000_000_000)
    started = time.process_time()
    scene, _ = load_scene(mesh_scene(tmp_path, "huge.stl", mb=3000), sandbox.registry)
    assert time.process_time() - started < 5
    assert scene.limits.max_mesh_mb == 3000
    # The default limit refuses the same file.
    assert (
        "larger than the limit of 512 MB" in refused(sandbox, mesh_scene(tmp_path, "huge.stl"))[0]
    )


@pytest.mark.parametrize("bad", ["max_mesh_mb: 0", "max_mesh_mb: -5", "max_nodes: 0"])
def test_limits_must_be_positive(sandbox: PluginSandbox, tmp_path: Path, bad: str) -> None:
    path = mesh_scene(tmp_path, "hat_mould.obj").with_name("l.yaml")
    path.write_text(MESH_SCENE.format(file="hat_mould.obj", mb=1).replace("max_mesh_mb: 1", bad))
    (error,) = refused(sandbox, path)
    assert error.startswith(f"{path}:11:") and f"limits.{bad.split(':')[0]}" in error


# --------------------------------------------------------------------------------------------
# Reading itself is bounded too (a library caller, or a file swapped after validation)


def test_the_readers_refuse_devices_fifos_and_size(tmp_path: Path, no_hang: None) -> None:
    with pytest.raises(MeshFileError, match="is a character device"):
        read_stl("/dev/zero")
    os.mkfifo(tmp_path / "p.obj")
    with pytest.raises(MeshFileError, match="is a FIFO"):
        read_obj(tmp_path / "p.obj")
    write_stl(tmp_path / "dome.stl", tessellate_hemisphere(0.1, 12))
    with pytest.raises(MeshFileError, match=r"larger than the limit of 0\.001 MB"):
        read_stl(tmp_path / "dome.stl", max_bytes=1000)
    assert read_stl(tmp_path / "dome.stl", max_bytes=10**6).n_triangles == 4 * 12 * 12


def test_the_surface_step_applies_the_scenes_mesh_limit(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    write_stl(tmp_path / "dome.stl", tessellate_hemisphere(0.1, 40))  # 320 kB
    scene, _ = load_scene(mesh_scene(tmp_path, "dome.stl", mb=1), sandbox.registry)
    lib = sandbox.library(bundled=True)
    ctx = CaseContext(lib.fabric("plain-weave-150"), scene, sandbox.registry, tmp_path)
    assert run_surface(ctx)["surface"].n_triangles == 6400
    # The file grows past the limit after validation: the step refuses it before reading.
    with open(tmp_path / "dome.stl", "r+b") as f:
        f.truncate(2_000_000)
    with pytest.raises(CaseFailure, match=r"^tool: .*2\.0 MB, larger than the limit of 1 MB"):
        run_surface(ctx)


# --------------------------------------------------------------------------------------------
# Malformed meshes: validation cannot see inside; the surface step fails with the file's error


def _binary_stl(tmp_path: Path) -> bytes:
    write_stl(tmp_path / "ok.stl", tessellate_hemisphere(0.1, 4))
    return (tmp_path / "ok.stl").read_bytes()


def _nan_vertex(data: bytes) -> bytes:
    # Record 5's first corner x: header 84, record 50 bytes, normal 12.
    at = 84 + 5 * 50 + 12
    return data[:at] + struct.pack("<f", float("nan")) + data[at + 4 :]


ASCII_ONE = """solid t
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 1 0 0
vertex 0 1 {z}
endloop
endfacet
{end}"""

MALFORMED: dict[str, tuple[str, Any, str]] = {
    "truncated binary STL": (
        "t.stl",
        lambda b: b[:-20],
        "not a valid binary STL: the header declares 64 triangles, which needs 3284 bytes, but "
        "the file has 3264",
    ),
    "triangle count disagrees with size": (
        "t.stl",
        lambda b: b[:80] + struct.pack("<I", 65) + b[84:],
        "the header declares 65 triangles, which needs 3334 bytes, but the file has 3284",
    ),
    "binary STL with a NaN vertex": (
        "t.stl",
        _nan_vertex,
        "triangle 5 has a non-finite coordinate",
    ),
    "binary STL without triangles": (
        "t.stl",
        lambda b: b[:80] + struct.pack("<I", 0),
        "binary STL with no triangles",
    ),
    "file shorter than a header": (
        "t.stl",
        lambda b: b[:50],
        "not an STL file: 50 bytes, shorter than a binary header",
    ),
    "ASCII STL with a NaN vertex": (
        "t.stl",
        lambda b: ASCII_ONE.format(z="nan", end="endsolid t").encode(),
        ":6: vertex: non-finite value in '0 1 nan'",
    ),
    "ASCII STL cut short": (
        "t.stl",
        lambda b: ASCII_ONE.format(z="0", end="").encode(),
        "file ends inside a solid (missing 'endsolid')",
    ),
    "OBJ index out of range": (
        "t.obj",
        lambda b: b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n",
        ":5: face refers to a vertex beyond the 3 the file defines",
    ),
    "OBJ index zero": (
        "t.obj",
        lambda b: b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        ":4: face corner '0': OBJ indices start at 1, not 0",
    ),
    "OBJ with a NaN vertex": (
        "t.obj",
        lambda b: b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
        ":2: vertex: non-finite value in '1 nan 0'",
    ),
    "OBJ without faces": (
        "t.obj",
        lambda b: b"v 0 0 0\nv 1 0 0\nv 0 1 0\n",
        "OBJ file with no faces",
    ),
    "OBJ of garbage": ("t.obj", lambda b: b"\x00\x01\x02 7\n", ":1: not an OBJ statement"),
    "OBJ whose triangles have no area": (
        "t.obj",
        lambda b: b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
        "the mesh has no triangle of non-zero area",
    ),
    "OBJ whose vertices coincide": (
        "t.obj",
        lambda b: b"v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n",
        "the mesh has no extent: all its vertices coincide",
    ),
}


@pytest.mark.filterwarnings("ignore:TriangleMesh. dropped")
@pytest.mark.parametrize("case", list(MALFORMED))
def test_a_malformed_mesh_fails_its_case_with_the_files_error(
    sandbox: PluginSandbox, tmp_path: Path, case: str
) -> None:
    name, damage, expected = MALFORMED[case]
    (tmp_path / name).write_bytes(damage(_binary_stl(tmp_path)))
    scene, _ = load_scene(mesh_scene(tmp_path, name), sandbox.registry)  # validation passes
    lib = sandbox.library(bundled=True)
    ctx = CaseContext(lib.fabric("plain-weave-150"), scene, sandbox.registry, tmp_path)
    with pytest.raises(CaseFailure) as info:
        run_surface(ctx)
    message = str(info.value)
    assert message.startswith(f"tool: {tmp_path / name}")
    assert expected in message


# --------------------------------------------------------------------------------------------
# Nets too large for the machine: refused by arithmetic, in milliseconds, at the field


def test_a_ply_of_ten_to_the_twelve_nodes_is_refused_in_milliseconds(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    path = analytic_scene(tmp_path, spacing=0.1, ply=1e5)
    (doc,) = load_yaml(path)
    started = time.process_time()
    with pytest.raises(SceneError) as info:
        validate_scene_data(doc, doc.data, sandbox.registry)
    assert time.process_time() - started < REFUSAL_CPU_S
    (error,) = info.value.errors
    assert (error.line, error.column, error.path) == (*SPACING, "ply.node_spacing_mm")
    assert error.message.startswith(
        "the ply needs 1,000,001 × 1,000,001 = 1e+12 net nodes at node spacing 0.1 mm, more "
        "than limits.max_nodes = 20,000,000 (about 130 TB of memory)"
    )
    assert "raise limits.max_nodes in the scene" in error.message


@pytest.mark.parametrize("max_nodes, accepted", [(500_000, False), (2_000_000, True)])
def test_the_node_limit_is_the_users_to_raise(
    sandbox: PluginSandbox, tmp_path: Path, max_nodes: int, accepted: bool
) -> None:
    # 1000 mm at 1 mm: 1001 × 1001 = 1,002,001 nodes (the tool is irrelevant to the count).
    path = analytic_scene(
        tmp_path,
        surface="plane",
        dims="size_mm: [2000, 2000]",
        spacing=1,
        ply=1000,
        max_nodes=max_nodes,
    )
    if accepted:
        assert load_scene(path, sandbox.registry)[0].limits.max_nodes == max_nodes
    else:
        message = one_error(sandbox, path, SPACING, "ply.node_spacing_mm")
        assert "1,001 × 1,001 = 1e+06 net nodes" in message
        assert f"more than limits.max_nodes = {max_nodes:,}" in message


def test_a_preset_spacing_over_the_limit_is_located_at_the_ply(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    text = analytic_scene(tmp_path, ply=1e5).read_text().replace("  node_spacing_mm: 10\n", "")
    path = tmp_path / "preset.yaml"
    path.write_text(text)
    message = one_error(sandbox, path, PLY, "ply")
    # standard preset: d = R/40 = 2.5 mm
    assert message.startswith(
        "the ply needs 40,001 × 40,001 = 1.6e+09 net nodes at node spacing 2.5 mm"
    )


def test_a_polygon_ply_is_counted_by_its_extent(sandbox: PluginSandbox, tmp_path: Path) -> None:
    path = tmp_path / "poly.yaml"
    path.write_text(
        "name: poly\ntool: {surface: plane}\nply:\n  node_spacing_mm: 0.5\n"
        "  outline_mm: [[-5000, -5000], [5000, -5000], [0, 5000]]\nstart: {point_mm: [0, 0]}\n"
        "outputs: [drape]\n"
    )
    (error,) = refused(sandbox, path)
    assert error.startswith(f"{path}:4:3: ply.node_spacing_mm: the ply needs 20,001 × 20,001")


# --------------------------------------------------------------------------------------------
# Spacing that leaves no cell, start points that cannot be placed


@pytest.mark.parametrize(
    "surface, dims, spacing, size",
    [
        ("hemisphere", "radius_mm: 100", 150, "100"),
        ("plane", "size_mm: [100, 100]", 200, "141.4"),
        ("cylinder", "radius_mm: 50\n  length_mm: 100", 200, "141.4"),
    ],
)
def test_a_spacing_larger_than_the_tool_is_refused(
    sandbox: PluginSandbox, tmp_path: Path, surface: str, dims: str, spacing: float, size: str
) -> None:
    path = analytic_scene(tmp_path, surface=surface, dims=dims, spacing=spacing, ply=1000)
    if surface == "cylinder":
        spacing_at = (SPACING[0] + 1, SPACING[1])
    else:
        spacing_at = SPACING
    message = one_error(sandbox, path, spacing_at, "ply.node_spacing_mm")
    assert message.startswith(
        f"the node spacing {spacing:g} mm is larger than the tool (its typical length is "
        f"{size} mm), so the net has no cell on it"
    )


def test_a_spacing_larger_than_the_ply_is_refused(sandbox: PluginSandbox, tmp_path: Path) -> None:
    message = one_error(
        sandbox, analytic_scene(tmp_path, spacing=60, ply=100), SPACING, "ply.node_spacing_mm"
    )
    assert message.startswith(
        "the node spacing 60 mm leaves the ply (100 × 100 mm) with 1 × 1 node(s), so the net "
        "has no cell"
    )


@pytest.mark.parametrize(
    "surface, dims, x, y, extent",
    [
        ("hemisphere", "radius_mm: 100", 300, 0, "x -100 … 100 mm, y -100 … 100 mm"),
        ("plane", "size_mm: [1000, 600]", 0, 400, "x -500 … 500 mm, y -300 … 300 mm"),
        ("paraboloid", "radius_mm: 100\n  height_mm: 80", 75, 75, "x -100 … 100 mm"),
    ],
)
def test_a_start_off_the_tool_is_located(
    sandbox: PluginSandbox,
    tmp_path: Path,
    surface: str,
    dims: str,
    x: float,
    y: float,
    extent: str,
) -> None:
    path = analytic_scene(tmp_path, surface=surface, dims=dims, x=x, y=y)
    start_at = (START[0] + dims.count("\n"), START[1])
    message = one_error(sandbox, path, start_at, "start.point_mm")
    assert message.startswith(f"the start point (x, y) = ({x:g}, {y:g}) mm is not over the tool")
    assert extent in message and message.endswith("move start.point_mm onto it")


def test_a_start_outside_the_ply_is_located(sandbox: PluginSandbox, tmp_path: Path) -> None:
    message = one_error(
        sandbox, analytic_scene(tmp_path, ply=100, offset=80), OFFSET, "ply.offset_mm"
    )
    assert message.startswith("the start point (the flat origin) lies outside the ply")


def test_every_problem_is_reported_at_once(sandbox: PluginSandbox, tmp_path: Path) -> None:
    errors = refused(sandbox, analytic_scene(tmp_path, spacing=150, ply=1000, x=300))
    assert [e.split(": ")[1] for e in errors] == ["ply.node_spacing_mm", "start.point_mm"]


@pytest.mark.parametrize("x, y", [(0, 0), (99, 0), (-70, 70)])
def test_a_start_on_the_tool_validates(
    sandbox: PluginSandbox, tmp_path: Path, x: float, y: float
) -> None:
    scene, _ = load_scene(analytic_scene(tmp_path, x=x, y=y), sandbox.registry)
    assert scene.start is not None and scene.start.point_mm == (x, y)


@pytest.mark.parametrize("path", sorted(bundled_scene_dir().glob("*.yaml")), ids=lambda p: p.stem)
def test_the_bundled_scenes_still_validate(sandbox: PluginSandbox, path: Path) -> None:
    scene, _ = load_scene(path, sandbox.registry)
    assert scene.name == path.stem


@pytest.mark.parametrize(
    "surface, dims, words",
    [
        (
            "hemisphere",
            "radius_mm: 100\n  flange_half_width_mm: 150",
            "a flange needs a fillet: fillet_radius_mm must lie in (0, radius_mm = 100) mm, got 0",
        ),
        (
            "hemisphere",
            "radius_mm: 100\n  flange_half_width_mm: 105\n  fillet_radius_mm: 10",
            "flange_half_width_mm = 105 mm must exceed the fillet's foot radius √(R² + 2Rρ) = "
            "109.5 mm",
        ),
        (
            "cone",
            "base_radius_mm: 100\n  height_mm: 50\n  top_radius_mm: 150",
            "top_radius_mm = 150 mm must be below base_radius_mm = 100 mm",
        ),
    ],
)
def test_a_tool_that_cannot_be_built_is_refused_in_millimetres(
    sandbox: PluginSandbox, tmp_path: Path, surface: str, dims: str, words: str
) -> None:
    (error,) = refused(sandbox, analytic_scene(tmp_path, surface=surface, dims=dims))
    assert error.startswith(f"{tmp_path / 'scene.yaml'}:3:3: tool: ")
    assert error.endswith(words)


@pytest.mark.parametrize("spacing", ["1e-300", "5e-324"])
def test_a_vanishing_spacing_is_refused_not_overflowed(
    sandbox: PluginSandbox, tmp_path: Path, spacing: str
) -> None:
    path = analytic_scene(tmp_path, ply=1e5)
    path.write_text(path.read_text().replace("node_spacing_mm: 10", f"node_spacing_mm: {spacing}"))
    message = one_error(sandbox, path, SPACING, "ply.node_spacing_mm")
    assert message.startswith("the ply needs more than 1e+18 net nodes at node spacing ")
    assert "(more memory than any machine has)" in message


SECTIONS = """\
name: sections
tool: {{surface: hemisphere, radius_mm: 100}}
ply: {{node_spacing_mm: 10, size_mm: [360, 360]}}
start: {{point_mm: [0, 0]{start}}}
{extra}
outputs: [drape]
"""

SECTION_CASES = {
    "scan step of 1e-12°": (
        "",
        "search: {generator_angle_deg: {min: 30, max: 150}, scan_step_deg: 1e-12}",
        (5, 52, "search.scan_step_deg"),
        "a scan of [30°, 150°] every 1e-12° needs 120,000,000,000,003 drapes, more than the "
        "budget max_drapes = 60",
    ),
    "scan step of 1e-300°": (
        "",
        "search: {generator_angle_deg: {min: 30, max: 150, step: 1e-300}}",
        (5, 51, "search.generator_angle_deg.step"),
        "every 1e-300° needs too many drapes",
    ),
    "reversed search range": (
        "",
        "search: {generator_angle_deg: {min: 150, max: 30}}",
        (5, 10, "search.generator_angle_deg"),
        "the generator-angle range must satisfy 0 < min < max < 180°, got [150°, 30°]",
    ),
    "search range past 180°": (
        "",
        "search: {generator_angle_deg: {min: 30, max: 200}}",
        (5, 10, "search.generator_angle_deg"),
        "got [30°, 200°]",
    ),
    "wrinkle area share above one": (
        "",
        "search: {max_wrinkle_area_share: 1.5}",
        (5, 34, "search.max_wrinkle_area_share"),
        "less than or equal to 1",
    ),
    "wrinkle area share as a word": (
        "",
        "search: {max_wrinkle_area_share: some}",
        (5, 34, "search.max_wrinkle_area_share"),
        "number",
    ),
    "shear step of 1e-9°": (
        "",
        "shear: {angles_deg: {min: 0, max: 60, step: 1e-9}}",
        (5, 39, "shear.angles_deg.step"),
        "a step of 1e-09° over [0°, 60°] gives 6e+10 angles, more than 100,000",
    ),
    "reversed shear range": (
        "",
        "shear: {angles_deg: {min: 60, max: 0}}",
        (5, 9, "shear.angles_deg"),
        "min (60°) must not exceed max (0°)",
    ),
    "polyline without polylines": (
        ", generators: polyline",
        "",
        (4, 27, "start.generators"),
        "generators: polyline needs start.generator_polylines_mm",
    ),
    "polyline with a search": (
        ", generators: polyline, generator_polylines_mm: [[[0, 0], [50, 0]], [[0, 0], [0, 50]]]",
        "search: {}",
        (4, 27, "start.generators"),
        "the generator-angle search needs geodesic or plan generators",
    ),
    "one-point polyline": (
        ", generators: polyline, generator_polylines_mm: [[[0, 0]], [[0, 0], [0, 50]]]",
        "",
        (4, 74, "start.generator_polylines_mm[0]"),
        "a generator polyline needs 2 to 10,000 vertices, got 1",
    ),
}


@pytest.mark.parametrize("case", list(SECTION_CASES))
def test_section_problems_are_refused_before_running(
    sandbox: PluginSandbox, tmp_path: Path, case: str
) -> None:
    start, extra, (line, column, field), words = SECTION_CASES[case]
    path = tmp_path / "sections.yaml"
    path.write_text(SECTIONS.format(start=start, extra=extra))
    started = time.process_time()
    errors = refused(sandbox, path)
    assert time.process_time() - started < 5
    assert errors[0].startswith(f"{path}:{line}:{column}: {field}: "), errors
    assert words in errors[0]


def test_a_ply_outline_of_too_many_vertices_is_refused(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    import math

    ring = [
        [round(100 * math.cos(t), 3), round(100 * math.sin(t), 3)]
        for t in (2 * math.pi * k / 20_001 for k in range(20_001))
    ]
    path = tmp_path / "outline.yaml"
    path.write_text(
        "name: outline\ntool: {surface: plane}\nply:\n  node_spacing_mm: 10\n"
        f"  outline_mm: {ring}\nstart: {{point_mm: [0, 0]}}\noutputs: [drape]\n"
    )
    (error,) = refused(sandbox, path)
    assert error == (
        f"{path}:5:15: ply.outline_mm: List should have at most 10000 items after validation, "
        "not 20001"
    )
