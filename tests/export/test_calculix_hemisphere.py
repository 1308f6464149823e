"""A draped hemisphere cap, exported for CalculiX and run in ccx: the answer follows the fibres.

One ply of a strongly orthotropic (illustrative) material, draped from the pole of a sphere of
radius 100 mm with its generators at +45° and +135° to x, mapped onto an S8R cap mesh (|x|, |y|
≤ 40 mm) held at its rim, and pushed at the pole along x. An orthotropic shell moves off the
line of the load towards its compliant axis: with axis 1 along the u fibres (+45°) the pole
moves to −y, with axis 1 along v (+135°, the mirror image y → −y of the u run) to +y by as
much, and on global axes (orientations ignored: axis 1 along x, the load's line) it hardly
leaves it.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.calculix import calculix_include_text
from preform.export.fe_mapping import MeshMapping, map_to_mesh
from preform.export.shell_mesh import read_shell_mesh
from preform.plugins.surfaces.basic import Hemisphere

R = 100.0  # mm
HALF, N = 40.0, 8  # cap half-width [mm], elements a side
MATERIAL = """*MATERIAL, NAME=FABRIC
*ELASTIC, TYPE=ENGINEERING CONSTANTS
140000., 10000., 10000., 0.3, 0.3, 0.5, 5000., 5000.
3500., 0.
"""


def cap_mesh(folder: Path, grid) -> dict[str, list[int]]:
    """Write ``mesh.inp``: S8R elements on the sphere (mid-side nodes on it too)."""
    step = HALF / N

    def place(i: int, j: int) -> tuple[float, float, float]:
        x, y = -HALF + step * i, -HALF + step * j
        return (x, y, float(np.sqrt(R**2 - x**2 - y**2)))

    lines, nid = grid(N, N, place, "CAP")
    (folder / "mesh.inp").write_text("\n".join(lines) + "\n")
    rim = [
        nid(i, j)
        for j in range(2 * N + 1)
        for i in range(2 * N + 1)
        if i in (0, 2 * N) or j in (0, 2 * N)
    ]
    return {"RIM": rim, "POLE": [nid(N, N)]}


def pole_displacement(folder: Path, ccx, grid, sections: str) -> np.ndarray:
    """Displacement (x, y, z) [mm] of the pole under 1 N along x, with ``sections``."""
    sets = cap_mesh(folder, grid)
    (folder / "sections.inp").write_text(sections)
    lines = ["*INCLUDE, INPUT=mesh.inp", MATERIAL.strip(), "*INCLUDE, INPUT=sections.inp"]
    for name, members in sets.items():
        lines += [f"*NSET, NSET={name}", *[str(n) for n in members]]
    lines += [
        "*BOUNDARY",
        "RIM, 1, 3",
        "*STEP",
        "*STATIC",
        "*CLOAD",
        "POLE, 1, 1.",
        "*NODE PRINT, NSET=POLE",
        "U",
        "*END STEP",
    ]
    (folder / "cap.inp").write_text("\n".join(lines) + "\n")
    ccx(folder, "cap")
    block = (folder / "cap.dat").read_text().split("displacements")[-1]
    rows = re.findall(r"^\s*(\d+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$", block, re.M)
    assert [int(r[0]) for r in rows] == sets["POLE"]
    return np.array([float(v) for v in rows[0][1:]])


@pytest.fixture(scope="module")
def cap_mapping(tmp_path_factory, quadratic_shells) -> MeshMapping:
    folder = tmp_path_factory.mktemp("cap")
    cap_mesh(folder, quadratic_shells)
    result = drape(
        Hemisphere(R / 1e3),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.16, 0.16)),
        generator_angle_rad=np.pi / 2,
        orientation_rad=np.pi / 4,
    )
    mapping = map_to_mesh(result, read_shell_mesh(folder / "mesh.inp"), nominal_thickness_mm=0.5)
    assert mapping.covered.all()
    # draped, not flat: the fibres shear away from the generators
    assert np.nanmax(np.abs(mapping.shear_deg)) > 3.0
    return mapping


def test_the_cap_deflects_as_the_mapped_fibres_say(
    tmp_path, ccx, quadratic_shells, cap_mapping
) -> None:
    pole = int(np.argmin(np.linalg.norm(cap_mapping.centroid_mm[:, :2], axis=1)))
    # the mapped angle of the u fibres near the pole is the drape's +45°
    assert cap_mapping.angle_u_deg[pole] == pytest.approx(45.0, abs=2.0)
    along_u = pole_displacement(
        tmp_path, ccx, quadratic_shells, calculix_include_text(cap_mapping, material="FABRIC")
    )
    swapped = dataclasses.replace(cap_mapping, fibre_u=cap_mapping.fibre_v)
    along_v = pole_displacement(
        tmp_path, ccx, quadratic_shells, calculix_include_text(swapped, material="FABRIC")
    )
    plain = pole_displacement(
        tmp_path, ccx, quadratic_shells, "*SHELL SECTION, ELSET=CAP, MATERIAL=FABRIC\n0.5\n"
    )
    # off the load's line towards the compliant axis (n x u, at 135°): to -y
    assert along_u[0] > 0 and along_u[1] < -0.1 * along_u[0]
    # the mirror image: axis 1 along v moves the pole to +y by as much
    assert along_v[0] == pytest.approx(along_u[0], rel=0.02)
    assert along_v[1] == pytest.approx(-along_u[1], rel=0.02)
    # global axes, symmetric about the load's line: the pole stays on it
    assert abs(plain[1]) < 0.02 * abs(along_u[1])
