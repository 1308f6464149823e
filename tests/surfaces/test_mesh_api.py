"""The Python paths to a drapable mesh check it as a scene's tool is checked: ``read_stl`` and
``read_obj`` repair through the scene's own function and return a ``ToolMesh`` carrying its
hygiene report; ``TriangleMesh(vertices, faces)`` refuses fins, one-sided surfaces and folds.
Truths: the place of a fold is an edge of the triangle whose corner the test moved; a plate's
area is its side squared; a crease's turn is the angle it was bent by; a fin's edge is the
edge the test stood it on."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.plugins.surfaces import mesh as mesh_module
from preform.plugins.surfaces.mesh import TriangleMesh, read_obj, read_stl, write_stl
from preform.plugins.surfaces.mesh_hygiene import FOLD_ANGLE_DEG, MeshRefused
from preform.plugins.surfaces.tool_mesh import ToolMesh
from preform.plugins.surfaces.tools import MeshTool, build_mesh

N, STEP = 7, 0.02  # the plate: 7 × 7 vertices 20 mm apart, 120 mm square
SIDE = (N - 1) * STEP
TOOLS = Path(mesh_module.__file__).resolve().parents[2] / "materials" / "tools"


def plate(n: int = N, step: float = STEP) -> tuple[np.ndarray, np.ndarray]:
    """A square plate in z = 0 centred on the origin, every triangle wound up (+z)."""
    s = (np.arange(n) - (n - 1) / 2) * step
    x, y = np.meshgrid(s, s, indexing="ij")
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            faces += [[a, a + n, a + n + 1], [a, a + n + 1, a + 1]]
    return vertices, np.array(faces)


def turn_over(
    vertices: np.ndarray, faces: np.ndarray, vertex: int, fan: int
) -> tuple[np.ndarray, int]:
    """The plate with ``vertex`` moved across the opposite edge of the ``fan``-th triangle
    around it (a fifth of its distance beyond that edge's midpoint), and that triangle."""
    turned = int(np.flatnonzero(np.any(faces == vertex, axis=1))[fan])
    middle = vertices[[k for k in faces[turned] if k != vertex]].mean(axis=0)
    moved = vertices.copy()
    moved[vertex] = middle + 0.2 * (middle - vertices[vertex])
    return moved, turned


def crease(turn_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """The plate bent down about the y axis along x = 0 by ``turn_deg``: the normals of the
    triangles on the crease turn by exactly that."""
    vertices, faces = plate()
    t = np.radians(turn_deg)
    flank = vertices[:, 0] > 0.0
    x = vertices[flank, 0].copy()
    vertices[flank, 0], vertices[flank, 2] = x * np.cos(t), -x * np.sin(t)
    return vertices, faces


def write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """An OBJ file in millimetres, written here from the arrays (not by preform)."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in (vertices / 1e-3).tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces.tolist()]
    path.write_text("\n".join(lines) + "\n")


def write_ascii_stl(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """An ASCII STL in millimetres, triangle by triangle, written here from the arrays."""
    lines = ["solid test"]
    for corners in (vertices[faces] / 1e-3).tolist():
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {x!r} {y!r} {z!r}" for x, y, z in corners]
        lines += ["endloop", "endfacet"]
    path.write_text("\n".join([*lines, "endsolid test"]) + "\n")


def write_binary_stl(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """A binary STL in millimetres (float32 corners), written here from the arrays."""
    record = np.dtype([("n", "<f4", (3,)), ("c", "<f4", (3, 3)), ("a", "<u2")])
    records = np.zeros(faces.shape[0], dtype=record)
    records["c"] = vertices[faces] / 1e-3
    path.write_bytes(b" " * 80 + np.uint32(faces.shape[0]).tobytes() + records.tobytes())


WRITERS = {
    "arrays": None,
    "ascii.stl": write_ascii_stl,
    "binary.stl": write_binary_stl,
    "mesh.obj": write_obj,
}


def build(path_kind: str, tmp_path: Path, vertices, faces, **options) -> TriangleMesh:
    """The mesh through one Python path: the constructor, read_stl or read_obj."""
    writer = WRITERS[path_kind]
    if writer is None:
        return TriangleMesh(vertices, faces, **options)
    path = tmp_path / path_kind
    writer(path, vertices, faces)
    reader = read_obj if path.suffix == ".obj" else read_stl
    return reader(path, **options)


def area_of(mesh: TriangleMesh) -> float:
    c = mesh.vertices[mesh.faces]
    return 0.5 * float(np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum())


@pytest.mark.parametrize("path_kind", list(WRITERS))
def test_a_triangle_turned_over_is_refused_where_the_moved_vertex_is(path_kind, tmp_path):
    vertices, faces = plate()
    centre = (N // 2) * N + N // 2
    moved, turned = turn_over(vertices, faces, centre, 0)
    # the fixture is what it says: exactly that triangle faces down
    c = moved[faces]
    up = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])[:, 2]
    assert np.flatnonzero(up < 0.0).tolist() == [turned]
    with pytest.raises(MeshRefused) as caught:
        build(path_kind, tmp_path, moved, faces)
    message = str(caught.value)
    if path_kind != "arrays":
        assert message.startswith(f"{tmp_path / path_kind}: 3 fold edge(s)")
    assert f"input triangle {turned + 1} is folded across 3 of its edges" in message
    where = caught.value.where_m
    assert where is not None
    # the place is the midpoint of an edge of the turned triangle (float32 in a binary STL)
    corners = moved[faces[turned]]
    midpoints = 0.5 * (corners + np.roll(corners, -1, axis=0))
    tolerance = 1e-6 if path_kind == "binary.stl" else 1e-12
    assert np.linalg.norm(midpoints - where, axis=1).min() < tolerance
    # and so within an edge of the vertex moved, never further than the triangle reaches
    assert (
        np.linalg.norm(where - moved[centre])
        <= np.linalg.norm(corners - moved[centre], axis=1).max()
    )


@pytest.mark.parametrize("path_kind", list(WRITERS))
def test_the_plate_unfolded_is_accepted_unchanged_and_silent(path_kind, tmp_path):
    vertices, faces = plate()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = build(path_kind, tmp_path, vertices, faces)
    assert mesh.n_triangles == faces.shape[0]
    assert area_of(mesh) == pytest.approx(SIDE**2, rel=1e-12)
    assert np.all(mesh.face_normals[:, 2] > 1.0 - 1e-12)
    if path_kind != "arrays":
        assert isinstance(mesh, ToolMesh)
        assert mesh.hygiene.repairs() == [] and mesh.hygiene.cautions() == []
        assert mesh.hygiene.triangles == faces.shape[0] and mesh.hygiene.pieces == 1


@pytest.mark.parametrize("path_kind", list(WRITERS))
def test_a_165_degree_crease_is_refused_by_default_and_let_through_at_170_with_a_word(
    path_kind, tmp_path
):
    vertices, faces = crease(165.0)
    with pytest.raises(MeshRefused, match=r"the sharpest, 165°") as caught:
        build(path_kind, tmp_path, vertices, faces)
    assert caught.value.where_m is not None
    assert abs(caught.value.where_m[0]) < 1e-7 and abs(caught.value.where_m[2]) < 1e-7
    with pytest.warns(UserWarning, match=r"more than 160° \(the sharpest 165°") as said:
        mesh = build(path_kind, tmp_path, vertices, faces, fold_angle_deg=170.0)
    assert "fold angle of 170°" in str(said[0].message)
    # the surface is kept: the plate's area, bent or not
    assert area_of(mesh) == pytest.approx(SIDE**2, rel=1e-6)
    if path_kind == "arrays":
        (caution,) = mesh.cautions
    else:
        report = mesh.hygiene
        # the crease line holds N - 1 grid edges, each between two triangles turning by 165°
        assert report.folds_allowed == N - 1 and report.fold_angle_deg == 170.0
        assert report.sharpest_fold_deg == pytest.approx(165.0, abs=1e-4)
        (caution,) = report.cautions()
        assert mesh.summary()["mesh_folds_allowed"] == N - 1
    assert f"{N - 1} edge(s)" in caution


@pytest.mark.parametrize("path_kind", list(WRITERS))
def test_a_fin_is_refused_on_the_edge_it_stands_on(path_kind, tmp_path):
    vertices, faces = plate()
    # a triangle standing up on the interior edge a-b shared by two plate triangles
    a, b = int(faces[20, 0]), int(faces[20, 2])
    top = 0.5 * (vertices[a] + vertices[b]) + np.array([0.0, 0.0, STEP])
    finned = np.vstack([vertices, top])
    fin = np.vstack([faces, [[a, b, len(vertices)]]])
    with pytest.raises(MeshRefused, match=r"1 non-manifold edge\(s\)") as caught:
        build(path_kind, tmp_path, finned, fin)
    assert "shared by 3 triangles" in str(caught.value)
    assert caught.value.where_m is not None
    tolerance = 1e-6 if path_kind == "binary.stl" else 1e-12
    np.testing.assert_allclose(
        caught.value.where_m, 0.5 * (vertices[a] + vertices[b]), atol=tolerance
    )


def test_a_one_sided_surface_is_refused():
    """A Möbius band: a strip of 12 quads around a circle, turned half a turn, its ends
    joined with the sides exchanged."""
    k = 12
    theta = 2 * np.pi * np.arange(k) / k
    ring = []
    for t in theta:
        for w in (-0.02, 0.02):
            r = 0.1 + w * np.cos(t / 2)
            ring.append((r * np.cos(t), r * np.sin(t), w * np.sin(t / 2)))
    faces = []
    for i in range(k):
        a, b = 2 * i, 2 * i + 1
        c, d = (2 * (i + 1), 2 * (i + 1) + 1) if i < k - 1 else (1, 0)
        faces += [[a, c, d], [a, d, b]]
    with pytest.raises(MeshRefused, match="cannot be wound consistently"):
        TriangleMesh(np.array(ring), np.array(faces))


def test_triangles_wound_against_their_plate_are_re_wound_with_a_word(tmp_path):
    vertices, faces = plate()
    mixed = faces.copy()
    mixed[::7] = mixed[::7, ::-1]
    n_wrong = len(range(0, faces.shape[0], 7))
    with pytest.warns(UserWarning, match=rf"re-wound {n_wrong} triangles"):
        mesh = TriangleMesh(vertices, mixed)
    assert mesh.rewound_triangles == n_wrong
    assert np.all(mesh.face_normals[:, 2] > 0.0)
    write_ascii_stl(tmp_path / "mixed.stl", vertices, mixed)
    with pytest.warns(UserWarning, match=rf"mixed\.stl: re-wound {n_wrong} triangles"):
        read = read_stl(tmp_path / "mixed.stl")
    assert read.hygiene.flipped_triangles == n_wrong
    assert np.all(read.face_normals[:, 2] > 0.0)
    # The caller's winding says which side is out: a plate wound down stays down (a file
    # tool is turned up, as a scene's is).
    down = TriangleMesh(vertices, faces[:, ::-1])
    assert np.all(down.face_normals[:, 2] < 0.0)
    write_ascii_stl(tmp_path / "down.stl", vertices, faces[:, ::-1])
    with pytest.warns(UserWarning, match=r"turned 1 piece\(s\) over"):
        assert np.all(read_stl(tmp_path / "down.stl").face_normals[:, 2] > 0.0)


def test_the_readers_knobs_are_the_scenes(tmp_path):
    """A crack 0.01 mm wide between two halves of the plate stays open at the default weld
    tolerance (1e-6 of the diagonal: 0.17 µm) and closes at 0.02 mm; a largest edge splits
    triangles and keeps the area."""
    vertices, faces = plate()
    right = vertices[:, 0] > 1e-9
    # the right half gets its own copies of the middle column's vertices, 0.01 mm away
    middle = np.flatnonzero(np.abs(vertices[:, 0]) < 1e-9)
    copies = vertices[middle] + np.array([1e-5, 0.0, 0.0])
    index = {int(v): len(vertices) + k for k, v in enumerate(middle)}
    cracked = np.vstack([vertices, copies])
    cracked_faces = faces.copy()
    on_right = np.any(right[faces], axis=1)
    for row in np.flatnonzero(on_right):
        cracked_faces[row] = [index.get(int(v), int(v)) for v in faces[row]]
    write_ascii_stl(tmp_path / "cracked.stl", cracked, cracked_faces)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        apart = read_stl(tmp_path / "cracked.stl")
    assert apart.hygiene.pieces == 2 and apart.hygiene.cracks_welded == 0
    with pytest.warns(UserWarning, match=rf"welded {N} vertices"):
        welded = read_stl(tmp_path / "cracked.stl", weld_tolerance_m=2e-5)
    assert welded.hygiene.pieces == 1 and welded.hygiene.cracks_welded == N
    with pytest.warns(UserWarning, match="welded"):
        split = read_stl(tmp_path / "cracked.stl", weld_tolerance_m=2e-5, max_edge_m=0.01)
    c = split.vertices[split.faces]
    assert np.linalg.norm(np.roll(c, -1, axis=1) - c, axis=2).max() <= 0.01
    assert area_of(split) == pytest.approx(area_of(welded), rel=1e-12)
    assert split.hygiene.max_edge_m == 0.01
    assert read_stl(tmp_path / "cracked.stl", feature_angle_deg=20.0).feature_angle_deg == 20.0


@pytest.mark.parametrize(
    ("name", "units"), [("hemisphere_r100.stl", "mm"), ("hat_mould.obj", "mm")]
)
def test_the_bundled_tools_read_the_same_in_python_as_in_a_scene(name, units):
    reader = read_obj if name.endswith(".obj") else read_stl
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read = reader(TOOLS / name)
    scene = build_mesh(MeshTool(surface="mesh", file=name, units=units), ".")
    np.testing.assert_array_equal(read.vertices, scene.vertices)
    np.testing.assert_array_equal(read.faces, scene.faces)
    np.testing.assert_array_equal(read.face_label, scene.face_label)
    assert read.hygiene == scene.hygiene
    assert read.source.format == scene.source.format and read.source.unit == "mm"


def test_a_tool_mesh_is_not_checked_twice(monkeypatch, tmp_path):
    """repair has run the checks on a ToolMesh's arrays: its construction does not call them
    again, while a TriangleMesh's does, once."""
    calls = []
    checked = mesh_module.check_surface

    def counting(*args, **kwargs):
        calls.append(1)
        return checked(*args, **kwargs)

    monkeypatch.setattr(mesh_module, "check_surface", counting)
    vertices, faces = plate()
    write_ascii_stl(tmp_path / "plate.stl", vertices, faces)
    read_stl(tmp_path / "plate.stl")
    assert calls == []
    TriangleMesh(vertices, faces)
    assert calls == [1]


@settings(max_examples=25, deadline=None)
@given(
    vertex=st.sampled_from([i * N + j for i in range(1, N - 1) for j in range(1, N - 1)]),
    fan=st.integers(0, 5),
    angle=st.floats(0.0, 2 * np.pi),
    scale=st.sampled_from([1e-3, 1.0, 50.0]),
)
def test_any_triangle_turned_over_anywhere_under_any_rotation_and_scale_is_refused_there(
    vertex, fan, angle, scale
):
    """Every interior vertex has six triangles around it on this plate; whichever is turned
    over (those next to the rim too), wherever the plate is turned about z and tilted, at any
    size, the constructor refuses it at one of its edges."""
    vertices, faces = plate()
    moved, turned = turn_over(vertices, faces, vertex, fan)
    c, s = np.cos(angle), np.sin(angle)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, np.cos(0.4), -np.sin(0.4)], [0.0, np.sin(0.4), np.cos(0.4)]]
    )
    placed = scale * moved @ rotation.T
    with pytest.raises(MeshRefused) as caught:
        TriangleMesh(placed, faces)
    # folded across each of its edges another triangle shares (an edge on the rim has none)
    shared = sum(
        int(np.count_nonzero(np.sum(np.isin(faces, pair), axis=1) == 2) == 2)
        for pair in ([faces[turned, k], faces[turned, (k + 1) % 3]] for k in range(3))
    )
    said = f"input triangle {turned + 1} is folded across {shared} of its edges"
    assert said in str(caught.value)
    corners = placed[faces[turned]]
    midpoints = 0.5 * (corners + np.roll(corners, -1, axis=0))
    assert np.linalg.norm(midpoints - caught.value.where_m, axis=1).min() < 1e-12 * scale


def test_fold_angle_is_checked_by_the_constructor():
    vertices, faces = plate()
    with pytest.raises(ValueError, match=r"fold angle must be in \(0, 180\] degrees"):
        TriangleMesh(vertices, faces, fold_angle_deg=200.0)
    assert FOLD_ANGLE_DEG == 160.0  # the default the docs and messages quote


def test_write_then_read_keeps_a_checked_mesh(tmp_path):
    """write_stl writes what a TriangleMesh holds; reading it back repairs nothing."""
    vertices, faces = crease(90.0)
    write_stl(tmp_path / "bent.stl", TriangleMesh(vertices, faces))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = read_stl(tmp_path / "bent.stl")
    assert back.n_triangles == faces.shape[0]
    assert area_of(back) == pytest.approx(SIDE**2, rel=1e-6)
