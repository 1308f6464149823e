"""The CalculiX include read back without ccx: per covered element its orientation and section."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from preform.export.calculix import calculix_include_text, write_calculix_include
from preform.export.fe_mapping import map_to_mesh
from preform.export.shell_mesh import shell_mesh


def cap_mapping(make_net, lift_mm: float = 50.0):
    """A domed, skewed net (shear of both signs) under a mesh of its own cells, those at one
    corner lifted ``lift_mm`` off the net so they are not covered."""
    net = make_net(10, 12, dome=True)
    nodes = net.nodes.reshape(-1, 3) * 1e3
    idx = np.arange(len(nodes)).reshape(net.nodes.shape[:2])
    corners = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    )
    far = nodes.copy()
    far[idx[:2, :2].ravel(), 2] += lift_mm
    mesh = shell_mesh(far, corners, element_ids=500 + 2 * np.arange(len(corners)))
    return map_to_mesh(net, mesh, nominal_thickness_mm=0.3)


def blocks(text: str) -> list[tuple[str, list[str]]]:
    out: list[tuple[str, list[str]]] = []
    for line in text.splitlines():
        if line.startswith("**"):
            continue
        if line.startswith("*"):
            out.append((line, []))
        else:
            out[-1][1].append(line)
    return out


@pytest.mark.parametrize("form", ["orthotropic", "two-layer"])
def test_each_covered_element_has_its_axes_and_thickness(make_net, form) -> None:
    mapping = cap_mapping(make_net)
    cov = mapping.covered
    assert cov.any() and not cov.all()
    text = calculix_include_text(mapping, form=form, materials=("CU", "CV"), u_fraction=0.6)
    axes = {}
    sections = {}
    for head, data in blocks(text):
        if head.startswith("*ORIENTATION"):
            assert head.endswith("SYSTEM=RECTANGULAR") and data[1] == "3, 0."
            axes[head.split("NAME=")[1].split(",")[0]] = np.array(
                [float(v) for v in data[0].split(",")]
            )
        elif head.startswith("*SHELL SECTION"):
            sections[int(head.split("ELSET=PREFORM_E")[1].split(",")[0])] = (head, data)
    ids = mapping.mesh.element_ids
    assert sorted(sections) == sorted(ids[cov].tolist())
    for k in np.nonzero(cov)[0]:
        label, n, t = int(ids[k]), mapping.normal[k], mapping.thickness_mm[k]
        for family, fibre in (("U", mapping.fibre_u[k]), ("V", mapping.fibre_v[k])):
            if form == "orthotropic" and family == "V":
                assert f"PREFORM_V{label}" not in axes
                continue
            a, b = axes[f"PREFORM_{family}{label}"][:3], axes[f"PREFORM_{family}{label}"][3:]
            assert a == pytest.approx(fibre, abs=1e-9)
            # b in the element's plane, at 90° from a about the normal: local 3 = normal
            assert np.cross(a, b) == pytest.approx(n, abs=1e-9)
        head, data = sections[label]
        if form == "orthotropic":
            assert head.endswith(f"MATERIAL=PREFORM_FABRIC, ORIENTATION=PREFORM_U{label}")
            assert float(data[0]) == pytest.approx(t, rel=1e-9)
        else:
            assert head.endswith("COMPOSITE")
            (tu, _, mu, ou), (tv, _, mv, ov) = ([f.strip() for f in d.split(",")] for d in data)
            assert (mu, ou, mv, ov) == ("CU", f"PREFORM_U{label}", "CV", f"PREFORM_V{label}")
            assert float(tu) == pytest.approx(0.6 * t) and float(tv) == pytest.approx(0.4 * t)


def test_uncovered_elements_are_listed_and_get_nothing(make_net) -> None:
    mapping = cap_mapping(make_net)
    text = calculix_include_text(mapping)
    uncovered = mapping.uncovered_ids.tolist()
    listed = text.split("*ELSET, ELSET=PREFORM_UNCOVERED\n")[1].split("*")[0]
    assert sorted(int(v) for v in listed.replace("\n", ",").split(",") if v.strip()) == uncovered
    for label in uncovered:
        assert f"PREFORM_E{label}," not in text and f"PREFORM_U{label}," not in text
    assert f"uncovered: {len(uncovered)} (ELSET=PREFORM_UNCOVERED)" in text
    # all covered (the mesh of the net's own cells, none lifted): the set is neither written
    # nor named
    text = calculix_include_text(cap_mapping(make_net, lift_mm=0.0))
    assert "PREFORM_UNCOVERED" not in text and "No uncovered element" in text


def test_refused_inputs(make_net, tmp_path) -> None:
    mapping = cap_mapping(make_net)
    with pytest.raises(ValueError, match="nominal thickness t0 is not known"):
        calculix_include_text(dataclasses.replace(mapping, nominal_thickness_mm=None))
    with pytest.raises(ValueError, match="form must be"):
        calculix_include_text(mapping, form="three-layer")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="u_fraction"):
        calculix_include_text(mapping, form="two-layer", u_fraction=1.0)
    with pytest.raises(ValueError, match="not a deck name"):
        calculix_include_text(mapping, material="my fabric")
    with pytest.raises(ValueError, match="prefix"):
        calculix_include_text(mapping, prefix="1X")
    path = tmp_path / "d.inp"
    write_calculix_include(mapping, path, title="γ 12°")
    assert path.read_bytes().isascii() and "gamma 12?" in path.read_text()
