"""Mesh hygiene refuses a surface folded back onto itself (a triangle turned over: windings
agree across its edges, its normal is reversed against its neighbours'), says where, and lets
real creases through: on a flat grid, a creased grid, a closed box, a coarse dome, under rigid
motions and scalings, and through the pipeline."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from preform.cli import cli
from preform.plugins.surfaces.mesh import TriangleMesh, tessellate_hemisphere, write_stl
from preform.plugins.surfaces.mesh_hygiene import FOLD_ANGLE_DEG, MeshRefused, repair

N, STEP = 9, 0.025  # the grid: 9 × 9 vertices 25 mm apart, 200 mm square
#: The vertex pushed through, and which of the triangles around it is turned over.
PUSHED, FAN = 5 * N + 4, 0


def flat_grid(n: int = N, step: float = STEP) -> tuple[np.ndarray, np.ndarray]:
    """A square grid in z = 0 centred on the origin, every triangle wound up (+z)."""
    s = (np.arange(n) - (n - 1) / 2) * step
    x, y = np.meshgrid(s, s, indexing="ij")
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            faces += [[a, a + n, a + n + 1], [a, a + n + 1, a + 1]]
    return vertices, np.array(faces)


def normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    c = vertices[faces]
    n = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def push_through(
    vertices: np.ndarray, faces: np.ndarray, vertex: int, fan: int, past: float = 0.2
) -> tuple[np.ndarray, int]:
    """The mesh with ``vertex`` moved across the opposite edge of the ``fan``-th triangle
    around it, ``past`` × its distance beyond that edge's midpoint; and that triangle."""
    turned = int(np.flatnonzero(np.any(faces == vertex, axis=1))[fan])
    opposite = [k for k in faces[turned] if k != vertex]
    middle = vertices[opposite].mean(axis=0)
    moved = vertices.copy()
    moved[vertex] = middle + past * (middle - vertices[vertex])
    return moved, turned


def edge_midpoints(vertices: np.ndarray, face: np.ndarray) -> np.ndarray:
    return 0.5 * (vertices[face] + vertices[np.roll(face, -1)])


def creased_grid(turn_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """The flat grid bent along the grid line x = 0: x ≤ 0 stays flat, x > 0 turns down about
    the y axis by ``turn_deg``, so the normals turn by exactly that across the crease."""
    vertices, faces = flat_grid()
    t = np.radians(turn_deg)
    x = vertices[:, 0].copy()
    flank = x > 0.0
    vertices[flank, 0] = x[flank] * np.cos(t)
    vertices[flank, 2] = -x[flank] * np.sin(t)
    return vertices, faces


def write_folded_stl(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """An ASCII STL (mm) of a folded mesh: TriangleMesh refuses a fold unless told to let it
    through, which it then says."""
    with pytest.warns(UserWarning, match="let through by a fold angle of 180°"):
        write_stl(path, TriangleMesh(vertices, faces, fold_angle_deg=180.0), binary=False)


def refusal(vertices: np.ndarray, faces: np.ndarray, **options: float) -> MeshRefused:
    with pytest.raises(MeshRefused) as caught:
        repair(vertices, faces, **options)
    return caught.value


def said_where_mm(message: str) -> np.ndarray:
    """The place a refusal names, as written: '(x, y, z) mm'."""
    found = re.search(r"edge at \(([^)]*)\) mm", message)
    assert found is not None, message
    return np.array([float(c) for c in found.group(1).split(",")])


def test_a_vertex_pushed_through_a_flat_grid_is_refused_at_the_triangle_it_turned_over():
    vertices, faces = flat_grid()
    moved, turned = push_through(vertices, faces, PUSHED, FAN)
    # The fixture does what it says: exactly that triangle faces down, the rest up.
    assert np.flatnonzero(normals(moved, faces)[:, 2] < 0.0).tolist() == [turned]
    error = refusal(moved, faces)
    message = str(error)
    # In a plane the turned-over triangle folds through 180° against all three neighbours.
    assert message.startswith("3 fold edge(s): ")
    assert "the sharpest, 180°" in message
    assert f"input triangle {turned + 1} is folded across 3 of its edges" in message
    # Where: the midpoint of one of its edges (all three fold through 180°, so which one is
    # the sharpest is rounding), in metres and in the millimetres written.
    assert error.where_m is not None
    near = np.linalg.norm(edge_midpoints(moved, faces[turned]) - error.where_m, axis=1)
    assert near.min() < 1e-12
    np.testing.assert_allclose(said_where_mm(message), error.where_m * 1e3, atol=1e-3)
    # The names of the edge's triangles include the turned-over one.
    pair = re.search(r"between input triangles (\d+) and (\d+)", message)
    assert pair is not None and str(turned + 1) in pair.groups()
    # It is the fold check that refuses: with it off the mesh passes untouched.
    kept = repair(moved, faces, fold_angle_deg=180.0)
    assert kept.faces.shape == faces.shape and kept.report.repairs() == []


def test_a_mis_wound_fold_is_refused_too():
    """Winding is repaired first: a turned-over triangle stored with the opposite winding is
    re-wound to agree with its neighbours, and then folds as before."""
    vertices, faces = flat_grid()
    moved, turned = push_through(vertices, faces, PUSHED, FAN)
    faces = faces.copy()
    faces[turned] = faces[turned, ::-1]
    assert np.all(normals(moved, faces)[:, 2] > 0.0)  # every normal up: no fold by normals
    assert "3 fold edge(s)" in str(refusal(moved, faces))


@pytest.mark.parametrize("turn_deg", [0.0, 30.0, 90.0, 120.0, 150.0, 159.0])
def test_real_creases_pass_unchanged(turn_deg):
    vertices, faces = creased_grid(turn_deg)
    fixed = repair(vertices, faces)
    assert fixed.report.repairs() == [] and fixed.report.pieces == 1
    np.testing.assert_array_equal(fixed.vertices[fixed.faces], vertices[faces])


@pytest.mark.parametrize("turn_deg", [165.0, 175.0])
def test_a_crease_sharper_than_the_fold_angle_is_refused_on_the_crease(turn_deg):
    vertices, faces = creased_grid(turn_deg)
    error = refusal(vertices, faces)
    # Every crease edge folds: the 8 grid edges along x = 0.
    assert str(error).startswith("8 fold edge(s): ")
    assert f"the sharpest, {turn_deg:.4g}°" in str(error)
    assert error.where_m is not None
    assert abs(error.where_m[0]) < 1e-15 and abs(error.where_m[2]) < 1e-15
    # The threshold is a parameter: a user who means a knife edge can raise it.
    repair(vertices, faces, fold_angle_deg=180.0)


def box(size: tuple[float, float, float], n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed box (side lengths ``size`` [m]), each side an n × n grid with its own copies
    of the shared corners (welded by repair), triangles wound at random."""
    rng = np.random.default_rng(seed)
    grid_v, grid_f = flat_grid(n, 1.0 / (n - 1))
    unit = grid_v[:, :2] + 0.5  # [0, 1]²
    parts, faces = [], []
    for axis in range(3):
        for side in (0.0, 1.0):
            p = np.empty((unit.shape[0], 3))
            others = [a for a in range(3) if a != axis]
            p[:, others[0]], p[:, others[1]] = unit[:, 0], unit[:, 1]
            p[:, axis] = side
            faces.append(grid_f + sum(len(q) for q in parts))
            parts.append(p * np.array(size))
    faces_all = np.vstack(faces)
    flip = rng.random(faces_all.shape[0]) < 0.5
    faces_all[flip] = faces_all[flip, ::-1]
    return np.vstack(parts), faces_all


@pytest.mark.parametrize("size", [(1.0, 1.0, 1.0), (0.4, 0.2, 0.002), (0.01, 0.3, 0.3)])
def test_a_closed_box_has_no_fold(size):
    vertices, faces = box(size, 5, seed=3)
    fixed = repair(vertices, faces)
    assert fixed.report.open_edges == 0 and fixed.report.pieces == 1
    corners = fixed.vertices[fixed.faces]
    volume = np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum()
    assert volume / 6 == pytest.approx(np.prod(size))  # wound outward, nothing lost


def test_every_triangle_turned_over_on_a_coarse_dome_is_refused():
    """A dome tessellated coarsely (neighbouring facets turn by up to 18°, more than the CAD
    tessellation angle of 15°): every interior vertex pushed past the opposite edge of each
    triangle around it, back onto the sphere, turns a triangle over (checked: its normal
    points into the sphere) and is refused."""
    dome = tessellate_hemisphere(0.1, 4)
    vertices, faces = dome.vertices, dome.faces
    n = normals(vertices, faces)
    sides: dict[tuple[int, int], list[int]] = {}
    for t, face in enumerate(faces.tolist()):
        for k in range(3):
            sides.setdefault(tuple(sorted((face[k], face[k - 1]))), []).append(t)
    pairs = [pair for pair in sides.values() if len(pair) == 2]
    facet_turn = [np.degrees(np.arccos(n[a] @ n[b])) for a, b in pairs]
    assert 15.0 < max(facet_turn) < 20.0
    rim = np.flatnonzero(np.abs(vertices[:, 2]) < 1e-12)
    sharpest_turns = []
    for vertex in np.setdiff1d(np.arange(len(vertices)), rim):
        for fan in range(np.count_nonzero(np.any(faces == vertex, axis=1))):
            moved, _ = push_through(vertices, faces, vertex, fan)
            moved[vertex] *= 0.1 / np.linalg.norm(moved[vertex])
            c = moved[faces].mean(axis=1)
            assert np.any(np.einsum("ij,ij->i", normals(moved, faces), c) < 0.0)
            sharpest = re.search(r"the sharpest, ([\d.]+)°", str(refusal(moved, faces)))
            assert sharpest is not None
            sharpest_turns.append(float(sharpest.group(1)))
    assert len(sharpest_turns) > 100
    # The margin docs/tools.md quotes for the fold angle.
    assert min(sharpest_turns) == pytest.approx(163.6, abs=0.05)
    assert min(sharpest_turns) > FOLD_ANGLE_DEG


def rotation(q: tuple[float, float, float, float]) -> np.ndarray:
    w, x, y, z = np.array(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


unit_interval = st.floats(-1.0, 1.0)


@settings(max_examples=30, deadline=None)
@given(
    q=st.tuples(unit_interval, unit_interval, unit_interval, unit_interval),
    log_scale=st.floats(-3.0, 3.0),
    shift=st.tuples(*[st.floats(-10.0, 10.0)] * 3),
)
def test_detection_is_invariant_under_rigid_motions_and_scaling(q, log_scale, shift):
    assume(np.linalg.norm(q) > 0.1)
    r, scale, t = rotation(q), 10.0**log_scale, np.array(shift)

    def moved(v: np.ndarray) -> np.ndarray:
        return scale * v @ r.T + t

    vertices, faces = flat_grid()
    pushed, turned = push_through(vertices, faces, PUSHED, FAN)
    error = refusal(moved(pushed), faces)
    assert str(error).startswith("3 fold edge(s): ")
    assert f"input triangle {turned + 1} is folded across 3" in str(error)
    assert error.where_m is not None
    near = np.linalg.norm(moved(edge_midpoints(pushed, faces[turned])) - error.where_m, axis=1)
    assert near.min() < 1e-9 * max(scale, np.abs(t).max())
    for turn_deg in (90.0, 150.0):
        repair(moved(creased_grid(turn_deg)[0]), faces)
    assert "8 fold edge(s)" in str(refusal(moved(creased_grid(170.0)[0]), faces))


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**16),
    in_plane=st.floats(0.0, 0.16),
    height=st.floats(0.0, 0.8),
    q=st.tuples(unit_interval, unit_interval, unit_interval, unit_interval),
)
def test_jitter_that_keeps_every_normal_within_60_degrees_is_never_a_fold(
    seed, in_plane, height, q
):
    """Two normals each within 60° of one direction are within 120° of each other (the
    triangle inequality on the sphere), below the fold angle: such a mesh is never refused,
    however bumpy."""
    assume(np.linalg.norm(q) > 0.1)
    rng = np.random.default_rng(seed)
    vertices, faces = flat_grid()
    vertices[:, :2] += rng.uniform(-in_plane, in_plane, (len(vertices), 2)) * STEP
    vertices[:, 2] += rng.uniform(-height, height, len(vertices)) * STEP
    assume(np.all(normals(vertices, faces)[:, 2] >= 0.5))
    r = rotation(q)
    fixed = repair(vertices @ r.T, faces)
    assert fixed.faces.shape == faces.shape


def test_a_folded_tool_fails_its_case_saying_where(tmp_path: Path):
    """Through the pipeline: the case fails with the refusal (file, place, what to do) in its
    summary and on the console; no drape is reported."""
    vertices, faces = flat_grid()
    pushed, turned = push_through(vertices, faces, PUSHED, FAN)
    write_folded_stl(tmp_path / "folded.stl", pushed, faces)
    scene = {
        "name": "folded-tool",
        "tool": {"surface": "mesh", "file": "folded.stl"},
        "ply": {"node_spacing_mm": 10.0, "size_mm": [150, 150]},
        "start": {"point_mm": [3.1, 1.7], "generator_angle_deg": 80},
        "outputs": ["cells_csv"],
    }
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(scene))
    out = tmp_path / "out"
    args = ["pipeline", "run", "--scene", str(tmp_path / "scene.yaml"), "--materials"]
    result = CliRunner().invoke(cli, [*args, "E-BX-318", "--engine", "serial", "--out", str(out)])
    assert result.exit_code != 0
    summary = json.loads(next(out.glob("*/*/summary.json")).read_text())
    assert summary["status"] == "failed"
    error = summary["error"]
    assert "folded.stl: 3 fold edge(s)" in error and "move the vertex back" in error
    # The place is written in the scene's millimetres (write_stl wrote mm, the default unit).
    where = said_where_mm(error)
    assert np.linalg.norm(edge_midpoints(pushed, faces[turned]) * 1e3 - where, axis=1).min() < 1e-3
    assert "3 fold edge(s)" in result.output


def test_a_tool_file_refused_for_a_fold_keeps_the_place(tmp_path: Path):
    """Read from a file, the refusal names the file and still carries the place [m]."""
    from preform.plugins.surfaces.tools import MeshTool, build_mesh

    vertices, faces = flat_grid()
    pushed, turned = push_through(vertices, faces, PUSHED, FAN)
    write_folded_stl(tmp_path / "folded.stl", pushed, faces)
    tool = MeshTool(surface="mesh", file="folded.stl")
    with pytest.raises(MeshRefused, match=r"folded\.stl: 3 fold edge") as caught:
        build_mesh(tool, str(tmp_path))
    assert caught.value.where_m is not None
    # the file holds millimetres (write_stl's default unit): the place comes back in metres
    near = np.linalg.norm(edge_midpoints(pushed, faces[turned]) - caught.value.where_m, axis=1)
    assert near.min() < 1e-6


@pytest.mark.parametrize("turn_deg", [165.0, 175.0])
def test_a_raised_fold_angle_lets_a_sharp_crease_through_and_says_so(turn_deg):
    """A real edge sharper than the default (a thin wedge) passes when the caller raises the
    fold angle past it, and the report counts every crease edge it let through and says where
    the sharpest is; a crease the default allows is never counted."""
    vertices, faces = creased_grid(turn_deg)
    fixed = repair(vertices, faces, fold_angle_deg=176.0)
    report = fixed.report
    # the crease line x = 0 holds N - 1 grid edges, each between two triangles turning by
    # exactly turn_deg (the diagonals do not cross it)
    assert report.folds_allowed == N - 1
    assert report.sharpest_fold_deg == pytest.approx(turn_deg, abs=1e-9)
    assert report.sharpest_fold_at_m is not None and abs(report.sharpest_fold_at_m[0]) < 1e-12
    (caution,) = report.cautions()
    assert f"{N - 1} edge(s)" in caution and "fold angle of 176°" in caution
    summary = report.summary()
    assert summary["mesh_fold_angle_deg"] == 176.0 and summary["mesh_folds_allowed"] == N - 1
    gentle = repair(*creased_grid(150.0), fold_angle_deg=176.0).report
    assert gentle.folds_allowed == 0 and gentle.cautions() == []


def test_a_scene_can_raise_the_fold_angle_and_the_case_warns(tmp_path: Path):
    """tool.fold_angle_deg lets a folded tool through the pipeline; the case then carries the
    caution in its warnings (console and summary) and the fold angle in its summary."""
    vertices, faces = creased_grid(170.0)
    write_folded_stl(tmp_path / "wedge.stl", vertices, faces)
    scene = {
        "name": "wedge-tool",
        "tool": {"surface": "mesh", "file": "wedge.stl", "fold_angle_deg": 175},
        "ply": {"node_spacing_mm": 10.0, "size_mm": [60, 60]},
        "start": {"point_mm": [-40, 1.7], "generator_angle_deg": 80},
        "outputs": ["cells_csv"],
    }
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(scene))
    out = tmp_path / "out"
    args = ["pipeline", "run", "--scene", str(tmp_path / "scene.yaml"), "--materials"]
    result = CliRunner().invoke(cli, [*args, "E-BX-318", "--engine", "serial", "--out", str(out)])
    summary = json.loads(next(out.glob("*/*/summary.json")).read_text())
    assert summary["mesh_fold_angle_deg"] == 175.0
    assert summary["mesh_folds_allowed"] == N - 1
    said = [w for w in summary["warnings"] if "turns back by more than 160°" in w]
    assert len(said) == 1 and "fold angle of 175°" in said[0]
    assert "turns back by more than 160°" in result.output


@pytest.mark.parametrize("angle", [0.0, -10.0, 180.5, float("nan")])
def test_a_fold_angle_outside_0_to_180_degrees_is_refused(angle):
    vertices, faces = flat_grid()
    with pytest.raises(ValueError, match=r"fold angle must be in \(0, 180\] degrees"):
        repair(vertices, faces, fold_angle_deg=angle)
