"""The ANSYS APDL input: the LOCAL angles rebuild each element's frame by the documented
rotation sequence (Z, then new X, then new Y), read back from the file."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.ansys import ansys_macro_text, local_angles_deg, write_ansys_macro
from preform.export.fe_mapping import map_to_mesh
from preform.export.shell_mesh import shell_mesh
from preform.plugins.surfaces.basic import Hemisphere, Plane


def rot(axis: int, deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]  # X: Y toward Z; Y: Z toward X; Z: X toward Y
    m = np.eye(3)
    m[i, i] = m[j, j] = c
    m[j, i], m[i, j] = s, -s
    return m


def frame_from_local(thxy: float, thyz: float, thzx: float) -> np.ndarray:
    """Columns: the local axes after rotating about Z, then the new X, then the new Y."""
    return rot(2, thxy) @ rot(0, thyz) @ rot(1, thzx)


@settings(max_examples=60, deadline=None)
@given(
    q=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
        lambda v: sum(x * x for x in v) > 1e-3
    )
)
def test_angles_rebuild_any_frame(q) -> None:
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    frame = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    a, b, c = local_angles_deg(frame[None])[0]
    np.testing.assert_allclose(frame_from_local(a, b, c), frame, atol=1e-7)


def test_gimbal_frame_local_y_vertical() -> None:
    frame = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # y along +Z
    a, b, c = local_angles_deg(frame[None])[0]
    assert abs(b - 90.0) < 1e-9
    np.testing.assert_allclose(frame_from_local(a, b, c), frame, atol=1e-9)


def test_hand_checked_flat_element() -> None:
    """u at 30° on a flat element with normal +z: LOCAL angles (30, 0, 0); a second element
    beyond the ply is only in the uncovered component."""
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
        orientation_rad=np.radians(30.0),
    )
    pts = np.array(
        [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [300, 0, 0], [310, 0, 0], [310, 10, 0]],
        float,
    )
    mesh = shell_mesh(pts, [[0, 1, 2, 3], [4, 5, 6]], element_ids=np.array([3, 4]))
    text = ansys_macro_text(map_to_mesh(result, mesh))
    lines = text.splitlines()
    local = next(line for line in lines if line.startswith("LOCAL,"))
    values = [float(v) for v in local.split(",")[1:]]
    assert values[:2] == [1001, 0]
    np.testing.assert_allclose(values[2:5], [5, 5, 0], atol=1e-9)
    np.testing.assert_allclose(values[5:], [30, 0, 0], atol=1e-7)
    assert "EMODIF,3,ESYS,1001" in lines
    assert not any(line.startswith("EMODIF,4,") for line in lines)
    at = lines.index("CM,PREFORM_UNCOVERED,ELEM")
    assert lines[at - 1] == "ESEL,A,ELEM,,4" and lines[at - 2] == "ESEL,NONE"


def test_read_back_on_a_hemisphere(tmp_path) -> None:
    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.3, 0.3)),
    )
    xs = np.arange(-60.0, 60.1, 12.0)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    mesh = shell_mesh(
        np.column_stack(
            [x.ravel(), y.ravel(), np.sqrt(100.0**2 - x.ravel() ** 2 - y.ravel() ** 2)]
        ),
        corners,
    )
    mapping = map_to_mesh(result, mesh)
    path = tmp_path / "drape.mac"
    write_ansys_macro(mapping, path)
    lines = path.read_text(encoding="ascii").splitlines()
    systems = {}
    for line in lines:
        if line.startswith("LOCAL,"):
            v = [float(t) for t in line.split(",")[1:]]
            systems[int(v[0])] = frame_from_local(*v[5:8])
    assigned = {
        int(line.split(",")[1]): int(line.split(",")[3])
        for line in lines
        if line.startswith("EMODIF,")
    }
    assert sorted(assigned) == sorted(mesh.element_ids.tolist())
    for k, eid in enumerate(mesh.element_ids.tolist()):
        frame = systems[assigned[eid]]
        np.testing.assert_allclose(frame[:, 0], mapping.fibre_u[k], atol=1e-7)
        np.testing.assert_allclose(frame[:, 2], mapping.normal[k], atol=1e-7)


def sections_of(lines: list[str]) -> dict[int, tuple[int, list[tuple[float, str, float]]]]:
    """Element -> (its section number, the section's layers (TK, MAT, THETA)), read back from
    SECTYPE / SECDATA / EMODIF SECNUM lines."""
    layers: dict[int, list[tuple[float, str, float]]] = {}
    current = None
    owner = {}
    for line in lines:
        fields = line.split(",")
        if fields[0] == "SECTYPE":
            assert fields[2] == "SHELL"
            current = int(fields[1])
            layers[current] = []
        elif fields[0] == "SECDATA":
            assert current is not None and fields[4] == "3"
            layers[current].append((float(fields[1]), fields[2], float(fields[3])))
        elif fields[0] == "EMODIF" and fields[2] == "SECNUM":
            owner[int(fields[1])] = int(fields[3])
    return {e: (s, layers[s]) for e, s in owner.items()}


def test_hand_checked_sections_on_a_sheared_plate() -> None:
    """u at 30°, v at 30° + 60° = 90° (shear γ = 30°): the v layer's THETA is 60°; t0 = 0.25 mm
    thickens to 0.25/cos 30° = 0.288675 mm, 0.144338 mm per layer; the element beyond the ply
    gets no section."""
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
        orientation_rad=np.radians(30.0),
        generator_angle_rad=np.radians(60.0),
    )
    pts = np.array(
        [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [300, 0, 0], [310, 0, 0], [310, 10, 0]],
        float,
    )
    mesh = shell_mesh(pts, [[0, 1, 2, 3], [4, 5, 6]], element_ids=np.array([3, 4]))
    text = ansys_macro_text(
        map_to_mesh(result, mesh, nominal_thickness_mm=0.25), materials=(7, 8), first_section=50
    )
    lines = text.splitlines()
    assert "PREFORM_MAT_U = 7" in lines and "PREFORM_MAT_V = 8" in lines
    sections = sections_of(lines)
    assert list(sections) == [3]
    number, ((tk_u, mat_u, th_u), (tk_v, mat_v, th_v)) = sections[3]
    assert number == 50 and (mat_u, mat_v) == ("PREFORM_MAT_U", "PREFORM_MAT_V")
    assert tk_u == pytest.approx(0.144337567, rel=1e-8)
    assert tk_v == pytest.approx(0.144337567, rel=1e-8)
    assert th_u == 0.0 and th_v == pytest.approx(60.0, abs=1e-7)


def test_no_thickness_no_sections() -> None:
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
    )
    mesh = shell_mesh(np.array([[0, 0, 0], [10, 0, 0], [10, 10, 0]], float), [[0, 1, 2]])
    text = ansys_macro_text(map_to_mesh(result, mesh))
    assert "SECTYPE" not in text and "SECNUM" not in text and "t0 unknown" in text
    with pytest.raises(ValueError, match="u_fraction"):
        ansys_macro_text(map_to_mesh(result, mesh), u_fraction=1.0)


def test_sections_read_back_on_a_hemisphere(tmp_path) -> None:
    """Read back: the layers sum to the mapped thickness, and turning each element's system
    x axis (the u fibres) by the v layer's THETA about its z axis gives the mapped v fibres."""
    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.3, 0.3)),
    )
    xs = np.arange(-60.0, 60.1, 12.0)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    mesh = shell_mesh(
        np.column_stack(
            [x.ravel(), y.ravel(), np.sqrt(100.0**2 - x.ravel() ** 2 - y.ravel() ** 2)]
        ),
        corners,
    )
    mapping = map_to_mesh(result, mesh, nominal_thickness_mm=0.3)
    path = tmp_path / "drape.mac"
    write_ansys_macro(mapping, path, u_fraction=0.6)
    lines = path.read_text(encoding="ascii").splitlines()
    systems = {}
    for line in lines:
        if line.startswith("LOCAL,"):
            v = [float(t) for t in line.split(",")[1:]]
            systems[int(v[0])] = frame_from_local(*v[5:8])
    esys = {
        int(line.split(",")[1]): int(line.split(",")[3])
        for line in lines
        if line.startswith("EMODIF,") and ",ESYS," in line
    }
    sections = sections_of(lines)
    assert sorted(sections) == sorted(mesh.element_ids.tolist())
    assert len({s for s, _ in sections.values()}) == mesh.n_elements
    shears = []
    for k, eid in enumerate(mesh.element_ids.tolist()):
        _, ((tk_u, _, th_u), (tk_v, _, th_v)) = sections[eid]
        assert tk_u + tk_v == pytest.approx(mapping.thickness_mm[k], rel=1e-8)
        assert tk_u == pytest.approx(0.6 * mapping.thickness_mm[k], rel=1e-8)
        assert th_u == 0.0
        frame = systems[esys[eid]]
        b = np.radians(th_v)
        v = np.cos(b) * frame[:, 0] + np.sin(b) * frame[:, 1]
        np.testing.assert_allclose(v, mapping.fibre_v[k], atol=1e-7)
        shears.append(abs(90.0 - th_v))
    assert max(shears) > 5.0  # the hemisphere shears the fabric: THETA is not just 90°
