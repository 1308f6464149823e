"""The LS-DYNA include, read back by a fixed-field parser written here, and checked by hand."""

from __future__ import annotations

import numpy as np
import pytest

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.fe_mapping import map_to_mesh
from preform.export.lsdyna import (
    lsdyna_composite_text,
    write_lsdyna_composite,
    write_lsdyna_include,
)
from preform.export.shell_mesh import shell_mesh
from preform.plugins.surfaces.basic import Hemisphere, Plane


def read_k(text: str) -> dict[str, list[str]]:
    """Data lines under each keyword, comments ($) dropped."""
    out: dict[str, list[str]] = {}
    key = ""
    for line in text.splitlines():
        if line.startswith("$"):
            continue
        if line.startswith("*"):
            key = line.strip().upper()
            out.setdefault(key, [])
        else:
            out[key].append(line)
    return out


def shells_beta(lines: list[str]) -> dict[int, tuple[int, list[int], list[float], float]]:
    out = {}
    for card1, card2 in zip(lines[::2], lines[1::2], strict=True):
        ints = [int(card1[k : k + 8]) for k in range(0, 80, 8)]
        reals = [float(card2[k : k + 16]) for k in range(0, 80, 16)]
        out[ints[0]] = (ints[1], ints[2:6], reals[:4], reals[4])
    return out


def test_hand_checked_beta_thickness_and_uncovered_set(tmp_path) -> None:
    """Flat drape, u at 30° from x, v at 120° (α = 90°, no shear): element 1 (nodes along +x
    first, normal +z) has BETA = 30°; element 2 is the same square with its nodes listed
    the other way round (normal −z, first edge along +y), so BETA = −(30° − 90°) = 60°; the
    triangle 3 has its first edge along x and N4 = N3; element 4 lies beyond the ply."""
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
        orientation_rad=np.radians(30.0),
    )
    pts = np.array(
        [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [400, 0, 0], [410, 0, 0], [410, 10, 0]],
        float,
    )
    mesh = shell_mesh(
        pts,
        [[0, 1, 2, 3], [0, 3, 2, 1], [0, 1, 2], [4, 5, 6]],
        element_ids=np.array([1, 2, 3, 4]),
        node_ids=np.array([11, 12, 13, 14, 15, 16, 17]),
    )
    mapping = map_to_mesh(result, mesh, nominal_thickness_mm=0.25)
    path = tmp_path / "drape.k"
    write_lsdyna_include(mapping, path, part_id=7, uncovered_set_id=42)
    cards = read_k(path.read_text(encoding="ascii"))
    shells = shells_beta(cards["*ELEMENT_SHELL_BETA"])
    assert sorted(shells) == [1, 2, 3]
    pid, nodes, thick, beta = shells[1]
    assert pid == 7 and nodes == [11, 12, 13, 14]
    np.testing.assert_allclose(thick, 0.25, rtol=1e-8)
    np.testing.assert_allclose(beta, 30.0, atol=1e-6)
    assert shells[2][1] == [11, 14, 13, 12]
    np.testing.assert_allclose(shells[2][3], 60.0, atol=1e-6)
    assert shells[3][1] == [11, 12, 13, 13]
    np.testing.assert_allclose(shells[3][3], 30.0, atol=1e-6)
    sid, *members = (
        int(line[k : k + 10]) for line in cards["*SET_SHELL_LIST"] for k in range(0, len(line), 10)
    )
    assert sid == 42 and members == [4]
    assert "*END" in cards


def test_beta_reproduces_the_fibre_direction_on_a_hemisphere(tmp_path) -> None:
    """Read back, rotating each element's N1→N2 edge by BETA about its normal gives the
    mapped u fibre direction."""
    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.3, 0.3)),
    )
    xs = np.arange(-60.0, 60.1, 10.0)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    z = np.sqrt(100.0**2 - x**2 - y**2)
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    mesh = shell_mesh(np.column_stack([x.ravel(), y.ravel(), z.ravel()]), corners)
    mapping = map_to_mesh(result, mesh)
    path = tmp_path / "drape.k"
    write_lsdyna_include(mapping, path)
    shells = shells_beta(read_k(path.read_text(encoding="ascii"))["*ELEMENT_SHELL_BETA"])
    assert len(shells) == mesh.n_elements
    for k, eid in enumerate(mesh.element_ids.tolist()):
        _, _, thick, beta = shells[eid]
        assert thick == [0.0] * 4  # t0 unknown: the section's thickness
        n = mapping.normal[k]
        e = mesh.first_edges()[k]
        e = e - (e @ n) * n
        e /= np.linalg.norm(e)
        b = np.radians(beta)
        rotated = np.cos(b) * e + np.sin(b) * np.cross(n, e)
        np.testing.assert_allclose(rotated, mapping.fibre_u[k], atol=1e-7)


def shells_composite(
    lines: list[str],
) -> dict[int, tuple[list[int], list[tuple[int, float, float]]]]:
    """Element -> (nodes, [(MID, THICK, B) per integration point]), read in the fixed
    10-character fields of card 2: MID1, THICK1, B1, (blank), MID2, THICK2, B2."""
    out = {}
    for card1, card2 in zip(lines[::2], lines[1::2], strict=True):
        ints = [int(card1[k : k + 8]) for k in range(0, 80, 8)]
        card2 = card2.ljust(80)
        points = [
            (int(card2[k : k + 10]), float(card2[k + 10 : k + 20]), float(card2[k + 20 : k + 30]))
            for k in (0, 40)
        ]
        assert card2[30:40].strip() == "" and card2[70:80].strip() == ""
        out[ints[0]] = (ints[2:6], points)
    return out


def sheared_plate_mapping(**kwargs):
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
        orientation_rad=np.radians(30.0),
        generator_angle_rad=np.radians(60.0),
    )
    pts = np.array(
        [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [400, 0, 0], [410, 0, 0], [410, 10, 0]],
        float,
    )
    mesh = shell_mesh(
        pts,
        [[0, 1, 2, 3], [0, 3, 2, 1], [4, 5, 6]],
        element_ids=np.array([1, 2, 4]),
        node_ids=np.array([11, 12, 13, 14, 15, 16, 17]),
    )
    return map_to_mesh(result, mesh, **kwargs)


def test_hand_checked_composite_both_families(tmp_path) -> None:
    """Plate sheared by γ = 30°: u at 30°, v at 30° + 60° = 90° from x. Element 1 (first edge
    +x, normal +z): B1 = 30°, B2 = 90°. Element 2 (nodes the other way: first edge +y,
    normal −z): B1 = −(30° − 90°) = 60°, B2 = 0°. t = 0.25/cos 30° = 0.288675 mm, split
    0.7/0.3; element 4 lies beyond the ply and is only in the set."""
    mapping = sheared_plate_mapping(nominal_thickness_mm=0.25)
    path = tmp_path / "drape.k"
    write_lsdyna_composite(mapping, path, materials=(5, 6), u_fraction=0.7, uncovered_set_id=9)
    cards = read_k(path.read_text(encoding="ascii"))
    shells = shells_composite(cards["*ELEMENT_SHELL_COMPOSITE"])
    assert sorted(shells) == [1, 2]
    t = 0.25 / np.cos(np.radians(30.0))
    nodes, ((m1, t1, b1), (m2, t2, b2)) = shells[1]
    assert nodes == [11, 12, 13, 14] and (m1, m2) == (5, 6)
    assert t1 == pytest.approx(0.7 * t, rel=1e-6) and t2 == pytest.approx(0.3 * t, rel=1e-6)
    assert b1 == pytest.approx(30.0, abs=1e-5) and b2 == pytest.approx(90.0, abs=1e-5)
    nodes, ((_, _, b1), (_, _, b2)) = shells[2]
    assert nodes == [11, 14, 13, 12]
    assert b1 == pytest.approx(60.0, abs=1e-5) and b2 == pytest.approx(0.0, abs=1e-5)
    assert [int(v) for v in cards["*SET_SHELL_LIST"][0].split()] == [9]
    assert [int(v) for v in cards["*SET_SHELL_LIST"][1].split()] == [4]


def test_composite_refuses_without_thickness() -> None:
    with pytest.raises(ValueError, match="t0"):
        lsdyna_composite_text(sheared_plate_mapping())


def test_composite_angles_rebuild_both_families_on_a_hemisphere(tmp_path) -> None:
    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.3, 0.3)),
    )
    xs = np.arange(-60.0, 60.1, 10.0)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    z = np.sqrt(100.0**2 - x**2 - y**2)
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    mesh = shell_mesh(np.column_stack([x.ravel(), y.ravel(), z.ravel()]), corners)
    mapping = map_to_mesh(result, mesh, nominal_thickness_mm=0.3)
    path = tmp_path / "drape.k"
    write_lsdyna_composite(mapping, path)
    shells = shells_composite(read_k(path.read_text(encoding="ascii"))["*ELEMENT_SHELL_COMPOSITE"])
    assert len(shells) == mesh.n_elements
    for k, eid in enumerate(mesh.element_ids.tolist()):
        _, ((_, t1, b1), (_, t2, b2)) = shells[eid]
        assert t1 + t2 == pytest.approx(mapping.thickness_mm[k], rel=1e-6)
        n = mapping.normal[k]
        e = mesh.first_edges()[k]
        e = e - (e @ n) * n
        e /= np.linalg.norm(e)
        for beta, fibre in ((b1, mapping.fibre_u[k]), (b2, mapping.fibre_v[k])):
            b = np.radians(beta)
            rotated = np.cos(b) * e + np.sin(b) * np.cross(n, e)
            # 10-character fields keep about 7 digits of the angle
            np.testing.assert_allclose(rotated, fibre, atol=1e-6)
