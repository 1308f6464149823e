"""The Abaqus include, read back with a parser written here, and a hand-checked example."""

from __future__ import annotations

import numpy as np
import pytest

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.abaqus import abaqus_include_text, write_abaqus_include
from preform.export.fe_mapping import map_to_mesh
from preform.export.shell_mesh import shell_mesh
from preform.plugins.surfaces.basic import Hemisphere, Plane


def parse_inp(text: str) -> list[tuple[str, dict[str, str], list[list[str]]]]:
    """Keyword blocks: (KEYWORD, {PARAM: value}, data lines split at commas); comments out."""
    blocks: list[tuple[str, dict[str, str], list[list[str]]]] = []
    for raw in text.splitlines():
        line = raw.rstrip()
        assert len(line) <= 256  # Abaqus's line limit
        if line.startswith("**") or not line:
            continue
        if line.startswith("*"):
            parts = [p.strip() for p in line[1:].split(",")]
            params = dict([*p.split("=", 1), ""][:2] for p in parts[1:])
            blocks.append((parts[0].upper(), {k.upper(): v for k, v in params.items()}, []))
        else:
            blocks[-1][2].append([f.strip() for f in line.split(",")])
    return blocks


def hemisphere_case():
    result = drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.12, 0.12)),
        generator_angle_rad=np.radians(80.0),
    )
    xs = np.arange(-80.0, 80.1, 8.0)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    z = np.sqrt(np.maximum(100.0**2 - x**2 - y**2, 0.0))
    idx = np.arange(x.size).reshape(x.shape)
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    mesh = shell_mesh(
        np.column_stack([x.ravel(), y.ravel(), z.ravel()]),
        corners,
        element_ids=1000 + 3 * np.arange(len(corners)),
    )
    return map_to_mesh(result, mesh, nominal_thickness_mm=0.4)


def test_read_back_one_unit_in_plane_orientation_per_covered_element(tmp_path) -> None:
    mapping = hemisphere_case()
    cov = mapping.covered
    assert cov.any() and not cov.all()  # the ply covers the top only
    path = tmp_path / "drape.inc"
    write_abaqus_include(mapping, path, title="E-BX 318 γ")
    text = path.read_text(encoding="ascii")
    blocks = parse_inp(text)
    sets = {
        p["ELSET"]: [int(v) for row in data for v in row if v]
        for k, p, data in blocks
        if k == "ELSET"
    }
    ids = mapping.mesh.element_ids
    assert sorted(sets["PREFORM_UNCOVERED"]) == sorted(ids[~cov].tolist())
    assert sorted(sets["PREFORM_COVERED"]) == sorted(ids[cov].tolist())
    tables = {p["NAME"]: data for k, p, data in blocks if k == "DISTRIBUTION TABLE"}
    assert tables["PREFORM_COORD_TABLE"] == [["COORD3D", "COORD3D"]]
    assert tables["PREFORM_LENGTH_TABLE"] == [["LENGTH"]]
    dists = {p["NAME"]: (p, data) for k, p, data in blocks if k == "DISTRIBUTION"}
    orients = {p["NAME"]: (p, data) for k, p, data in blocks if k == "ORIENTATION"}
    normal = dict(zip(ids.tolist(), mapping.normal, strict=True))
    for family in ("U", "V"):
        params, data = orients[f"PREFORM_{family}"]
        assert data[0] == [f"PREFORM_DIR_{family}"] and data[1] == ["3", "0."]
        params, rows = dists[f"PREFORM_DIR_{family}"]
        assert params["LOCATION"] == "ELEMENT" and params["TABLE"] == "PREFORM_COORD_TABLE"
        assert rows[0][0] == ""  # the default line Abaqus requires
        labels = [int(r[0]) for r in rows[1:]]
        assert sorted(labels) == sorted(ids[cov].tolist())  # one per covered element, once
        assert len(set(labels)) == len(labels)
        for r in rows[1:]:
            a, b = np.array(r[1:4], float), np.array(r[4:7], float)
            n = normal[int(r[0])]
            assert abs(np.linalg.norm(a) - 1) < 1e-9 and abs(np.linalg.norm(b) - 1) < 1e-9
            assert abs(a @ n) < 1e-9 and abs(b @ n) < 1e-9 and abs(a @ b) < 1e-9
    params, rows = dists["PREFORM_THICKNESS"]
    assert rows[0] == ["", "0.4"]
    t = {int(r[0]): float(r[1]) for r in rows[1:]}
    assert sorted(t) == sorted(ids[cov].tolist())
    assert all(v >= 0.4 for v in t.values())
    assert "gamma" in text  # ASCII only


def test_hand_checked_two_elements() -> None:
    """A flat drape with u along x at 0°, v at 60° (γ = −30°) on two 10 mm squares, one of them
    beyond the ply. By hand: a = (1, 0, 0), b = n × a = (0, 1, 0) for u; a = (cos 60°,
    sin 60°, 0), b = (−sin 60°, cos 60°, 0) for v; t = 0.5 / cos 30° = 0.5773502692 mm."""
    result = drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
        generator_angle_rad=np.radians(60.0),
    )
    pts = np.array(
        [
            [0, 0, 0],
            [10, 0, 0],
            [10, 10, 0],
            [0, 10, 0],
            [500, 0, 0],
            [510, 0, 0],
            [510, 10, 0],
            [500, 10, 0],
        ],
        float,
    )
    mesh = shell_mesh(pts, [[0, 1, 2, 3], [4, 5, 6, 7]], element_ids=np.array([5, 8]))
    text = abaqus_include_text(map_to_mesh(result, mesh, nominal_thickness_mm=0.5))
    lines = text.splitlines()
    assert lines[lines.index("*ELSET, ELSET=PREFORM_COVERED") + 1] == "5"
    assert lines[lines.index("*ELSET, ELSET=PREFORM_UNCOVERED") + 1] == "8"
    u_at = lines.index(
        "*DISTRIBUTION, NAME=PREFORM_DIR_U, LOCATION=ELEMENT, TABLE=PREFORM_COORD_TABLE"
    )
    assert lines[u_at + 1] == ", 1., 0., 0., 0., 1., 0."
    got = np.array(lines[u_at + 2].split(",")[1:], float)
    np.testing.assert_allclose(got, [1, 0, 0, 0, 1, 0], atol=1e-10)
    assert lines[u_at + 3].startswith("*ORIENTATION, NAME=PREFORM_U")
    v_at = lines.index(
        "*DISTRIBUTION, NAME=PREFORM_DIR_V, LOCATION=ELEMENT, TABLE=PREFORM_COORD_TABLE"
    )
    c, s = np.cos(np.pi / 3), np.sin(np.pi / 3)
    np.testing.assert_allclose(
        np.array(lines[v_at + 2].split(",")[1:], float), [c, s, 0, -s, c, 0], atol=1e-10
    )
    t_at = lines.index(
        "*DISTRIBUTION, NAME=PREFORM_THICKNESS, LOCATION=ELEMENT, TABLE=PREFORM_LENGTH_TABLE"
    )
    assert lines[t_at + 1] == ", 0.5"
    assert lines[t_at + 2] == "5, 0.5773502692"
    assert not any(line.startswith("8,") for line in lines)  # never defaulted


def test_prefix_is_checked() -> None:
    mapping = hemisphere_case()
    with pytest.raises(ValueError, match="prefix"):
        abaqus_include_text(mapping, prefix="1 bad")
    assert "*ORIENTATION, NAME=PLY_2_U" in abaqus_include_text(mapping, prefix="ply_2")
