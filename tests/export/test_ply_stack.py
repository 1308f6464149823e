"""Composite sections of a ply stack: drop-offs, checks, and the four writers read back.

The plate is flat (z = 0, normal +z, every element's first edge along +x), so a ply laid at θ
has its u fibres at θ from x in every element, and the writers' angles can be checked against θ
directly; the second ply (at 45°) is cut along its v fibres through the origin, so it covers only
the elements whose centroid c has c · (cos 45°, sin 45°) ≤ 0 (a drop-off over the rest).
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from preform.export.fe_mapping import MeshMapping, map_to_mesh
from preform.export.ply_stack import PlySection, StackSections
from preform.export.shell_mesh import ShellMesh, shell_mesh
from preform.export.stack_abaqus import stack_sections_text, write_stack_sections
from preform.export.stack_ansys import stack_ansys_text
from preform.export.stack_files import write_stack_files
from preform.export.stack_lsdyna import stack_lsdyna_text

T = 0.25  # mm


def plate(nx: int = 8, ny: int = 4) -> ShellMesh:
    """S4-like plate 100 × 50 mm centred on the origin, labels 101, 102, ..."""
    x, y = np.meshgrid(np.linspace(-50, 50, nx + 1), np.linspace(-25, 25, ny + 1), indexing="ij")
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    return shell_mesh(points, corners, element_ids=101 + np.arange(len(corners)))


def under_half_ply(mesh: ShellMesh, angle: float = 45.0) -> np.ndarray:
    """Elements a half ply at ``angle`` covers: centroid on or behind its edge (a v fibre)."""
    theta = np.radians(angle)
    return np.asarray(mesh.centroids()[:, :2] @ [np.cos(theta), np.sin(theta)] <= 1e-6)


def ply(make_net, turned_net, mesh: ShellMesh, angle: float, half: bool = False) -> MeshMapping:
    # the half net spans u in [-150, 0] mm: cut along the v fibre through the origin
    net = (
        make_net(31, 61, spacing=0.005, start=(30, 30))
        if half
        else make_net(61, 61, spacing=0.005, start=(30, 30))
    )
    return map_to_mesh(turned_net(net, angle), mesh, nominal_thickness_mm=T)


@pytest.fixture
def stack(make_net, turned_net) -> StackSections:
    mesh = plate()
    return StackSections(
        (
            PlySection("ply-1", "CARBON_UD", ply(make_net, turned_net, mesh, 0.0)),
            PlySection("ply-2", "GLASS_NCF", ply(make_net, turned_net, mesh, 45.0, half=True)),
            PlySection("ply-3", "CARBON_UD", ply(make_net, turned_net, mesh, 90.0)),
        )
    )


def test_a_ply_absent_from_an_element_is_left_out_and_counted(stack) -> None:
    under = under_half_ply(stack.mesh)
    assert 0 < under.sum() < len(under)
    present = stack.present()
    assert np.array_equal(present[:, 1], under)  # the drop-off, exactly
    assert present[:, [0, 2]].all()
    summary = stack.summary()
    absent = int(np.count_nonzero(~under))
    assert summary["ply_absent_elements"] == {"ply-1": 0, "ply-2": absent, "ply-3": 0}
    assert summary["elements_bare"] == 0
    assert summary["elements_all_plies"] == len(under) - absent
    assert summary["materials"] == ["CARBON_UD", "GLASS_NCF"]
    assert np.allclose(stack.total_thickness_mm(), np.where(under, 3 * T, 2 * T))


def sections(text: str) -> dict[int, list[list[str]]]:
    """Element label -> its composite layer lines (fields), from the Abaqus/CalculiX text."""
    out: dict[int, list[list[str]]] = {}
    current = None
    for line in text.splitlines():
        m = re.match(r"\*SHELL SECTION, ELSET=PREFORM_E(\d+), COMPOSITE", line)
        if m:
            current = out.setdefault(int(m.group(1)), [])
        elif line.startswith("*"):
            current = None
        elif current is not None:
            current.append([f.strip() for f in line.split(",")])
    return out


def orientations(text: str) -> dict[str, np.ndarray]:
    lines = text.splitlines()
    return {
        line.split("NAME=")[1].split(",")[0]: np.array([float(v) for v in lines[k + 1].split(",")])
        for k, line in enumerate(lines)
        if line.startswith("*ORIENTATION")
    }


@pytest.mark.parametrize("flavour", ["abaqus", "calculix"])
def test_abaqus_and_calculix_sections_layer_by_layer(stack, flavour) -> None:
    text = stack_sections_text(stack, flavour=flavour)
    per_element = sections(text)
    axes = orientations(text)
    under = dict(zip(stack.mesh.element_ids.tolist(), under_half_ply(stack.mesh), strict=True))
    assert sorted(per_element) == sorted(under)
    for label, layers in per_element.items():
        expected = [("CARBON_UD", 0.0), ("GLASS_NCF", 45.0), ("CARBON_UD", 90.0)]
        if not under[label]:
            del expected[1]  # dropped off: no layer, no default angle
        assert [layer[2] for layer in layers] == [m for m, _ in expected]
        for layer, (_, angle) in zip(layers, expected, strict=True):
            assert float(layer[0]) == pytest.approx(T)
            a, b = axes[layer[3]][:3], axes[layer[3]][3:]
            theta = np.radians(angle)
            assert a == pytest.approx([np.cos(theta), np.sin(theta), 0.0], abs=1e-9)
            # b = n x a: in the plane, 90° on from a, so axis 3 is the normal +z
            assert b == pytest.approx([-np.sin(theta), np.cos(theta), 0.0], abs=1e-9)
            if flavour == "abaqus":
                assert layer[1] == "3" and layer[4].startswith("ply-")
            else:
                assert layer[1] == "" and len(layer) == 4


def test_lsdyna_integration_points_per_ply(stack) -> None:
    text = stack_lsdyna_text(stack, material_ids={"CARBON_UD": 7, "GLASS_NCF": 9})
    lines = text.splitlines()
    start = lines.index("*ELEMENT_SHELL_COMPOSITE")
    cards = [ln for ln in lines[start + 1 :] if not ln.startswith("$")]
    cards = cards[: next(k for k, ln in enumerate(cards) if ln.startswith("*"))]
    under = dict(zip(stack.mesh.element_ids.tolist(), under_half_ply(stack.mesh), strict=True))
    k, seen = 0, 0
    while k < len(cards):
        label = int(cards[k][:8])
        n_points = 3 if under[label] else 2
        points = []
        for card in cards[k + 1 : k + 1 + (n_points + 1) // 2]:
            for half in (card[:40], card[40:80]):
                if half.strip():
                    points.append((int(half[:10]), float(half[10:20]), float(half[20:30])))
        expected = [(7, T, 0.0), (9, T, 45.0), (7, T, 90.0)]
        if n_points == 2:
            del expected[1]
        assert points == [pytest.approx(p) for p in expected]
        k += 1 + (n_points + 1) // 2
        seen += 1
    assert seen == stack.mesh.n_elements
    assert "CARBON_UD = 7" in text and "GLASS_NCF = 9" in text


def test_ansys_layers_per_element(stack) -> None:
    text = stack_ansys_text(stack)
    assert "PREFORM_M1 = 1  ! CARBON_UD" in text and "PREFORM_M2 = 2  ! GLASS_NCF" in text
    blocks = re.findall(r"SECTYPE,\d+,SHELL\n((?:SECDATA.*\n)+)EMODIF,(\d+),SECNUM", text)
    assert len(blocks) == stack.mesh.n_elements
    under = dict(zip(stack.mesh.element_ids.tolist(), under_half_ply(stack.mesh), strict=True))
    for body, label in blocks:
        layers = [line.split(",")[1:] for line in body.strip().splitlines()]
        expected = [["PREFORM_M1", 0.0], ["PREFORM_M2", 45.0], ["PREFORM_M1", 90.0]]
        if not under[int(label)]:
            del expected[1]
        assert [[lay[1], float(lay[2])] for lay in layers] == [
            [m, pytest.approx(a, abs=1e-7)] for m, a in expected
        ]
        assert all(float(lay[0]) == pytest.approx(T) for lay in layers)


def test_bare_elements_get_no_section(make_net, turned_net) -> None:
    mesh = plate()
    half = ply(make_net, turned_net, mesh, 0.0, half=True)
    stack = StackSections((PlySection("ply-1", "UD", half),))
    text = stack_sections_text(stack, flavour="calculix")
    bare = [int(v) for v in text.split("*ELSET, ELSET=PREFORM_BARE\n")[1].split("*")[0].split(",")]
    assert sorted(bare) == sorted(mesh.element_ids[~half.covered].tolist())
    assert sorted(sections(text)) == sorted(mesh.element_ids[half.covered].tolist())
    assert (
        stack.summary()["elements_bare"] == len(bare) == np.count_nonzero(~under_half_ply(mesh, 0))
    )
    assert "*SET_SHELL_LIST" in stack_lsdyna_text(stack) and "PREFORM_BARE" in stack_ansys_text(
        stack
    )


def test_bad_stacks_are_refused(make_net, turned_net) -> None:
    mesh = plate()
    good = ply(make_net, turned_net, mesh, 0.0)
    with pytest.raises(ValueError, match="at least one ply"):
        StackSections(())
    with pytest.raises(ValueError, match="repeated: ply-1"):
        StackSections((PlySection("ply-1", "UD", good), PlySection("ply-1", "UD", good)))
    other = ply(make_net, turned_net, plate(4, 2), 0.0)
    with pytest.raises(ValueError, match="another mesh"):
        StackSections((PlySection("ply-1", "UD", good), PlySection("ply-2", "UD", other)))
    with pytest.raises(ValueError, match="not a deck name"):
        PlySection("ply 1", "UD", good)
    with pytest.raises(ValueError, match="not a deck name"):
        PlySection("ply-1", "U,D", good)
    with pytest.raises(ValueError, match="thickness is not known"):
        PlySection("ply-1", "UD", dataclasses.replace(good, nominal_thickness_mm=None))
    stack = StackSections((PlySection("ply-1", "UD", good),))
    with pytest.raises(ValueError, match="no material id for: UD"):
        stack_lsdyna_text(stack, material_ids={"OTHER": 1})
    with pytest.raises(ValueError, match="flavour"):
        stack_sections_text(stack, flavour="nastran")  # type: ignore[arg-type]


# the fixtures only hand out pure builder functions: sharing them across examples is safe
@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    angles=st.lists(st.floats(-179.0, 179.0), min_size=1, max_size=5),
    dropped=st.lists(st.booleans(), min_size=5, max_size=5),
)
def test_every_present_ply_is_one_layer_at_its_angle(make_net, turned_net, angles, dropped):
    """Any stack: each element's layers are its present plies in order, at their angles."""
    mesh = plate(4, 2)
    plies = tuple(
        PlySection(f"p{k}", "UD", ply(make_net, turned_net, mesh, a, half=dropped[k] and k > 0))
        for k, a in enumerate(angles)
    )
    stack = StackSections(plies)
    text = stack_sections_text(stack, flavour="calculix")
    axes = orientations(text)
    present = stack.present()
    for e, label in enumerate(mesh.element_ids.tolist()):
        layers = sections(text).get(label, [])
        wanted = [a for k, a in enumerate(angles) if present[e, k]]
        assert len(layers) == len(wanted)
        for layer, angle in zip(layers, wanted, strict=True):
            a = axes[layer[3]][:3]
            assert np.degrees(np.arctan2(a[1], a[0])) == pytest.approx(angle, abs=1e-6)


def test_written_file_is_ascii(tmp_path, stack) -> None:
    path = tmp_path / "stack.inp"
    write_stack_sections(stack, path, flavour="calculix", title="γ-test")
    assert path.read_bytes().isascii()
    assert "gamma-test" in path.read_text()


def test_layers_run_from_the_normal_s_negative_side(make_net, turned_net) -> None:
    """Elements listed the other way round (normal −z, into the tool under a ply whose outward
    normal u × v is +z) list their layers outermost first in every writer."""
    mesh = plate(4, 2)
    flipped = np.zeros(mesh.n_elements, dtype=bool)
    flipped[::3] = True
    corners = np.where(flipped[:, None], mesh.corners[:, ::-1], mesh.corners)
    mesh = shell_mesh(mesh.points, corners, element_ids=mesh.element_ids)
    stack = StackSections(
        tuple(
            PlySection(f"ply-{k + 1}", f"M{k + 1}", ply(make_net, turned_net, mesh, a))
            for k, a in enumerate([0.0, 30.0, 90.0])
        )
    )
    assert np.array_equal(stack.normal_into_tool(), flipped)
    assert stack.summary()["elements_normal_into_tool"] == int(flipped.sum())
    ids = mesh.element_ids.tolist()
    for label, layers in sections(stack_sections_text(stack)).items():
        wanted = ["M1", "M2", "M3"][:: -1 if flipped[ids.index(label)] else 1]
        assert [layer[2] for layer in layers] == wanted
    ansys = stack_ansys_text(stack)
    blocks = re.findall(r"SECTYPE,\d+,SHELL\n((?:SECDATA.*\n)+)EMODIF,(\d+),SECNUM", ansys)
    for body, label in blocks:
        mats = [line.split(",")[2] for line in body.strip().splitlines()]
        wanted = ["PREFORM_M1", "PREFORM_M2", "PREFORM_M3"]
        assert mats == wanted[:: -1 if flipped[ids.index(int(label))] else 1]
    lsdyna = stack_lsdyna_text(stack).splitlines()
    at = lsdyna.index("*ELEMENT_SHELL_COMPOSITE") + 3
    for k in range(mesh.n_elements):
        label = int(lsdyna[at + 3 * k][:8])
        mids = [int(lsdyna[at + 3 * k + 1][:10]), int(lsdyna[at + 3 * k + 1][40:50])]
        mids.append(int(lsdyna[at + 3 * k + 2][:10]))
        assert mids == [1, 2, 3][:: -1 if flipped[ids.index(label)] else 1]


def test_stack_files_for_the_named_targets(tmp_path, stack) -> None:
    written = write_stack_files(stack, tmp_path, ["calculix", "ansys", "calculix"], prefix="LAY")
    assert written == {"calculix": "stack_calculix.inp", "ansys": "stack_ansys.mac"}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(written.values())
    assert (tmp_path / "stack_calculix.inp").read_text() == stack_sections_text(
        stack, prefix="LAY", flavour="calculix"
    )
    assert "LAY_M1 = 1" in (tmp_path / "stack_ansys.mac").read_text()
    with pytest.raises(ValueError, match="no stack target nastran; known: abaqus"):
        write_stack_files(stack, tmp_path, ["nastran"])


@pytest.mark.parametrize("half", [False, True], ids=["no bare element", "bare elements"])
def test_headers_name_the_mesh_file_only_and_the_sets_written(
    tmp_path, make_net, turned_net, half
) -> None:
    """As the single-ply decks: nothing of the machine (the mesh by its file name), LS-DYNA
    within 80 columns, and the set of elements with no ply named exactly when written."""
    from preform.export.shell_mesh import read_shell_mesh

    deep = tmp_path / "home" / "someone" / "projects"
    deep.mkdir(parents=True)
    name = "left_hand_door_inner_panel_revision_C_shell_mesh_of_the_tool_surface_coarse.inp"
    mesh = plate(4, 2)
    lines = ["*NODE"] + [f"{k + 1}, {x}, {y}, {z}" for k, (x, y, z) in enumerate(mesh.points)]
    lines.append("*ELEMENT, TYPE=S4R, ELSET=SKIN")
    lines += [
        ", ".join(map(str, [e, *(c + 1)]))
        for e, c in zip(mesh.element_ids, mesh.corners, strict=True)
    ]
    (deep / name).write_text("\n".join(lines) + "\n")
    mesh = read_shell_mesh(deep / name)
    plies = (
        PlySection("ply-1", "UD", ply(make_net, turned_net, mesh, 0.0, half=half)),
        PlySection(
            "a-ply-with-a-name-long-enough-to-wrap",
            "UD",
            ply(make_net, turned_net, mesh, 90.0, half=half),
        ),
    )
    stack = StackSections(plies)
    title = "E-BX-318 over the door panel, least-energy generator angle, ply 3 of 8, " * 2
    texts = {
        "abaqus": stack_sections_text(stack, title=title),
        "calculix": stack_sections_text(stack, flavour="calculix", title=title),
        "lsdyna": stack_lsdyna_text(stack, title=title, bare_set_id=7),
        "ansys": stack_ansys_text(stack),
    }
    for kind, text in texts.items():
        assert str(tmp_path) not in text and "someone" not in text, kind
        assert name[:40] in text.replace("\n$   ", "").replace("\n**   ", ""), kind
        bare_named = {"lsdyna": "*SET_SHELL_LIST 7", "ansys": "component PREFORM_BARE"}.get(
            kind, "ELSET=PREFORM_BARE"
        )
        assert (bare_named in text) == half, kind
        written = {"lsdyna": "\n*SET_SHELL_LIST\n", "ansys": "CM,PREFORM_BARE,ELEM"}.get(
            kind, "*ELSET, ELSET=PREFORM_BARE\n"
        )
        assert (written in text) == half, kind
    assert all(len(line) <= 80 for line in texts["lsdyna"].splitlines())
    comments = " ".join(
        ln[1:].strip() for ln in texts["lsdyna"].splitlines() if ln.startswith("$ ")
    )
    assert "ply 3 of 8" in comments
