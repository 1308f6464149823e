"""The exported CalculiX decks run in CalculiX (ccx), and ccx applies their orientations.

A flat plate 100 × 50 mm of S8R shells is pulled along x (the loaded edge moved by δ, the other
held, every node kept in its plane with its rotations held so the plate cannot bend: the
membrane stiffness alone) and its stiffness Nx/εx = (F/W)/(δ/L) [N/mm] is compared with
classical laminate theory written here: Nx/εx = 1/a11, a = A⁻¹, A = Σ Q̄(θ)·t over the plies
(Jones, *Mechanics of Composite Materials*, 2nd ed., §4.2; Q̄ from the plane-stress reduced
stiffnesses rotated by θ). The material is an illustrative carbon/epoxy ply, not a datasheet.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from preform.export.abaqus import abaqus_include_text
from preform.export.calculix import calculix_include_text
from preform.export.fe_mapping import MeshMapping, map_to_mesh
from preform.export.ply_stack import PlySection, StackSections
from preform.export.shell_mesh import read_shell_mesh
from preform.export.stack_abaqus import stack_sections_text

# Illustrative unidirectional carbon/epoxy ply [MPa]: E1, E2, nu12, G12 (plane stress), and the
# out-of-plane constants ccx's 3-D expansion of the shell also needs.
E1, E2, NU12, G12 = 140_000.0, 10_000.0, 0.3, 5_000.0
MATERIAL = [
    "*MATERIAL, NAME={name}",
    "*ELASTIC, TYPE=ENGINEERING CONSTANTS",
    f"{E1}, {E2}, {E2}, {NU12}, {NU12}, 0.5, {G12}, {G12}",
    "3500., 0.",
]
T_PLY = 0.25  # mm
L, W = 100.0, 50.0  # mm
STRETCH = 0.1  # mm: δ, εx = 1e-3


def clt_stiffness(angles_deg: list[float], t: float = T_PLY) -> float:
    """Nx/εx [N/mm] of a laminate free to contract and shear in its plane (Ny = Nxy = 0)."""
    nu21 = NU12 * E2 / E1
    q11, q22 = E1 / (1 - NU12 * nu21), E2 / (1 - NU12 * nu21)
    q12, q66 = NU12 * E2 / (1 - NU12 * nu21), G12
    a = np.zeros((3, 3))
    for theta in np.radians(angles_deg):
        m, n = np.cos(theta), np.sin(theta)
        b11 = q11 * m**4 + 2 * (q12 + 2 * q66) * m**2 * n**2 + q22 * n**4
        b22 = q11 * n**4 + 2 * (q12 + 2 * q66) * m**2 * n**2 + q22 * m**4
        b12 = (q11 + q22 - 4 * q66) * m**2 * n**2 + q12 * (m**4 + n**4)
        b66 = (q11 + q22 - 2 * q12 - 2 * q66) * m**2 * n**2 + q66 * (m**4 + n**4)
        b16 = (q11 - q12 - 2 * q66) * m**3 * n + (q12 - q22 + 2 * q66) * m * n**3
        b26 = (q11 - q12 - 2 * q66) * m * n**3 + (q12 - q22 + 2 * q66) * m**3 * n
        a += t * np.array([[b11, b12, b16], [b12, b22, b26], [b16, b26, b66]])
    return float(1.0 / np.linalg.inv(a)[0, 0])


def plate_mesh(folder: Path, grid, nx: int = 8, ny: int = 4) -> dict[str, list[int]]:
    """Write ``mesh.inp`` (S8R plate centred on the origin, normal +z); return node sets."""
    lines, nid = grid(
        nx, ny, lambda i, j: (L * i / (2 * nx) - L / 2, W * j / (2 * ny) - W / 2, 0.0), "PLATE"
    )
    (folder / "mesh.inp").write_text("\n".join(lines) + "\n")
    nodes = [(i, j) for j in range(2 * ny + 1) for i in range(2 * nx + 1) if not (i % 2 and j % 2)]
    return {
        "LEFT": [nid(i, j) for i, j in nodes if i == 0],
        "RIGHT": [nid(i, j) for i, j in nodes if i == 2 * nx],
        "ALL": [nid(i, j) for i, j in nodes],
    }


def run_plate(folder: Path, ccx, grid, sections: str, materials: list[str]) -> float:
    """Pull the plate with ``sections`` (an include's text); return Nx/εx [N/mm]."""
    sets = plate_mesh(folder, grid)
    (folder / "sections.inp").write_text(sections)
    lines = ["*INCLUDE, INPUT=mesh.inp"]
    for name in materials:
        lines += [line.format(name=name) for line in MATERIAL]
    lines.append("*INCLUDE, INPUT=sections.inp")
    for name, members in sets.items():
        lines += [f"*NSET, NSET={name}", *[str(n) for n in members]]
    lines += [
        "*BOUNDARY",
        "LEFT, 1, 1",
        f"{sets['LEFT'][0]}, 2, 2",
        "ALL, 3, 6",  # in-plane only: no bending, so the membrane (A) stiffness is measured
        "*STEP",
        "*STATIC",
        "*BOUNDARY",
        f"RIGHT, 1, 1, {STRETCH}",
        "*NODE PRINT, NSET=LEFT, TOTALS=ONLY",
        "RF",
        "*END STEP",
    ]
    (folder / "plate.inp").write_text("\n".join(lines) + "\n")
    output = ccx(folder, "plate")
    assert "WARNING" not in output.upper(), output[-2000:]  # ccx says what it ignores
    dat = (folder / "plate.dat").read_text()
    totals = re.findall(r"total force.*?\n\s*\n\s*(\S+)", dat)
    force = -float(totals[-1])
    return (force / W) / (STRETCH / L)


def flat_net_mapping(make_net, turned_net, grid, folder: Path, angle_deg: float) -> MeshMapping:
    """A flat unsheared ply with its u fibres at ``angle_deg`` from x, mapped onto the plate."""
    net = turned_net(make_net(41, 41, spacing=0.005, start=(20, 20)), angle_deg)
    plate_mesh(folder, grid)
    mapping = map_to_mesh(net, read_shell_mesh(folder / "mesh.inp"), nominal_thickness_mm=T_PLY)
    assert mapping.covered.all()
    return mapping


@pytest.mark.parametrize("angles", [[0.0, 45.0, -45.0, 90.0], [0.0, 90.0]])
@pytest.mark.parametrize("flavour", ["calculix", "abaqus"])
def test_exported_stack_has_the_laminate_theory_stiffness(
    tmp_path, make_net, turned_net, quadratic_shells, ccx, angles, flavour
) -> None:
    plies = tuple(
        PlySection(
            f"ply-{k + 1}",
            "UD",
            flat_net_mapping(make_net, turned_net, quadratic_shells, tmp_path, a),
        )
        for k, a in enumerate(angles)
    )
    text = stack_sections_text(StackSections(plies), flavour=flavour)
    stiffness = run_plate(tmp_path, ccx, quadratic_shells, text, ["UD"])
    assert stiffness == pytest.approx(clt_stiffness(angles), rel=0.01)
    # and not what the plies would give all along x (orientations ignored)
    assert abs(stiffness / clt_stiffness([0.0] * len(angles)) - 1) > 0.2


def test_single_ply_orientation_takes_effect(
    tmp_path, make_net, turned_net, quadratic_shells, ccx
) -> None:
    stiffness = {}
    for angle in (0.0, 90.0, 30.0):
        text = calculix_include_text(
            flat_net_mapping(make_net, turned_net, quadratic_shells, tmp_path, angle), material="UD"
        )
        stiffness[angle] = run_plate(tmp_path, ccx, quadratic_shells, text, ["UD"])
        assert stiffness[angle] == pytest.approx(clt_stiffness([angle], T_PLY), rel=0.01)
    # the same section on global axes: what ccx computes when it ignores an orientation
    plain = run_plate(
        tmp_path,
        ccx,
        quadratic_shells,
        f"*SHELL SECTION, ELSET=PLATE, MATERIAL=UD\n{T_PLY}\n",
        ["UD"],
    )
    assert plain == pytest.approx(clt_stiffness([0.0], T_PLY), rel=0.01)
    for angle in (90.0, 30.0):
        assert abs(stiffness[angle] / plain - 1) > 0.5, "ccx ignored the orientations"
    assert stiffness[0.0] / stiffness[90.0] == pytest.approx(E1 / E2, rel=0.01)


def test_two_layer_form_is_both_fibre_families(
    tmp_path, make_net, turned_net, quadratic_shells, ccx
) -> None:
    """An unsheared fabric (u along x, v along y) in two layers of t/2: a [0/90] laminate."""
    mapping = flat_net_mapping(make_net, turned_net, quadratic_shells, tmp_path, 0.0)
    text = calculix_include_text(mapping, form="two-layer", materials=("UD", "UD"), u_fraction=0.5)
    stiffness = run_plate(tmp_path, ccx, quadratic_shells, text, ["UD"])
    assert stiffness == pytest.approx(clt_stiffness([0.0, 90.0], T_PLY / 2), rel=0.01)


def test_the_abaqus_include_is_not_what_ccx_applies(
    tmp_path, make_net, turned_net, quadratic_shells, ccx
) -> None:
    """Why the CalculiX flavour exists: ccx runs the Abaqus include (fibres at 90°) with a
    warning and computes the global-axes (0°) stiffness. A ccx that applies it is no defect of
    preform's: the test then skips, saying docs/exports.md's CalculiX section is out of date."""
    mapping = flat_net_mapping(make_net, turned_net, quadratic_shells, tmp_path, 90.0)
    text = abaqus_include_text(mapping) + (
        f"*SHELL SECTION, ELSET=PREFORM_COVERED, MATERIAL=UD, ORIENTATION=PREFORM_U\n{T_PLY}\n"
    )
    try:
        stiffness = run_plate(tmp_path, ccx, quadratic_shells, text, ["UD"])
    except AssertionError as error:
        assert "WARNING" in str(error)  # it ran, and said what it ignored
        dat = (tmp_path / "plate.dat").read_text()
        force = -float(re.findall(r"total force.*?\n\s*\n\s*(\S+)", dat)[-1])
        stiffness = (force / W) / (STRETCH / L)
    if stiffness == pytest.approx(clt_stiffness([90.0]), rel=0.01):
        pytest.skip("this ccx applies the Abaqus include: docs/exports.md says it does not")
    assert stiffness == pytest.approx(clt_stiffness([0.0]), rel=0.01)


def test_a_dropped_ply_is_absent_where_ccx_computes(
    tmp_path, make_net, quadratic_shells, ccx
) -> None:
    """[0/90] on the half x < 0, [0] on the rest (the 90° ply dropped off): pulled along x the
    halves are in series, Nx/εx = 2 / (a11[0/90] + a11[0]) (Nx the same in both), to the
    constraint their different Poisson contractions put on each other at the joint."""
    plate_mesh(tmp_path, quadratic_shells)
    mesh = read_shell_mesh(tmp_path / "mesh.inp")
    full = map_to_mesh(
        make_net(41, 41, spacing=0.005, start=(20, 20)), mesh, nominal_thickness_mm=T_PLY
    )
    half_net = make_net(21, 41, spacing=0.005, start=(20, 20))  # u in [-100, 0] mm
    half = map_to_mesh(
        dataclasses.replace(half_net, fibre_u=half_net.fibre_v, fibre_v=-half_net.fibre_u),
        mesh,
        nominal_thickness_mm=T_PLY,
    )
    assert np.array_equal(half.covered, mesh.centroids()[:, 0] < 0)
    stack = StackSections((PlySection("ply-1", "UD", full), PlySection("ply-2", "UD", half)))
    stiffness = run_plate(
        tmp_path, ccx, quadratic_shells, stack_sections_text(stack, flavour="calculix"), ["UD"]
    )
    series = 2.0 / (1.0 / clt_stiffness([0.0, 90.0]) + 1.0 / clt_stiffness([0.0]))
    assert stiffness == pytest.approx(series, rel=0.01)
