"""The LS-DYNA and ANSYS stack files read back by readers that are not ours.

**LS-DYNA**: ``ansys-dyna-core`` (PyPI; its keyword deck reader runs offline, no solver or
server) loads ``stack_lsdyna.k``. Its ``*ELEMENT_SHELL_COMPOSITE`` class holds one element and
its first two integration points per keyword and ignores the cards after them without a
warning, so each element is handed to it as a keyword of its own, once per card of integration
points (LS-DYNA's card layout, as its field schema says: EID, PID, N1-N8 in 8 columns; MID,
THICK, B, unused in 10). What it reads is compared with the stack's sections and the mesh file,
read here as text. Its ``*SET_SHELL_LIST`` reads the bare elements.

**ANSYS**: no reader of an APDL command file is installable: ``ansys-mapdl-core`` drives a
licensed MAPDL process (not on PyPI or Debian), ``ansys-mapdl-reader`` and ``mapdl-archive``
read binary results and CDB archives, not command streams. So the reader is written here from
the command reference (Mechanical APDL Command Reference: LOCAL, SECTYPE, SECDATA for SHELL,
EMODIF, CM, ESEL; a command line holds at most 640 characters, a parameter name at most 32
characters starting with a letter), and the fibre direction is rebuilt from LOCAL's three
successive rotations (THXY about local Z, THYZ about the new X, THZX about the new Y) and
THETA about the element's Z, never from our matrix formulas.

The stack: three plies on the 8 x 8 S8R cap of docs/examples/calculix_cap_mesh.inp, the part
cut to |x|, |y| <= 30 mm (an outer ring of bare elements), the middle ply cut to 20 mm (a
drop-off), so elements carry 3 (an odd count: a half card), 2 or no plies.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np
import pytest

import preform
from preform.export.stack_ansys import stack_ansys_text
from preform.export.stack_lsdyna import stack_lsdyna_text

MESH = Path(__file__).resolve().parents[2] / "docs" / "examples" / "calculix_cap_mesh.inp"


@pytest.fixture(scope="module")
def stack():
    scene = {
        "name": "cap-drop",
        "tool": {"surface": "hemisphere", "radius_mm": 100},
        "ply": {"node_spacing_mm": 5, "size_mm": [160, 160]},
        "start": {"point_mm": [0, 0]},
        "part": {"plan_outline_mm": [[-30, -30], [30, -30], [30, 30], [-30, 30]]},
        "layup": {
            "plies": [
                {"fabric": "plain-weave-600", "orientation_deg": 0, "thickness_mm": 0.5},
                {
                    "fabric": "satin-4hs-crowfoot",
                    "orientation_deg": 45,
                    "thickness_mm": 0.3,
                    "part_outline_mm": [[-20, -20], [20, -20], [20, 20], [-20, 20]],
                },
                {"fabric": "plain-weave-600", "orientation_deg": 90, "thickness_mm": 0.5},
            ],
            "ply_outputs": ["drape"],
        },
        "export": {"mesh": str(MESH)},
        "outputs": ["layup", "stack_sections"],
    }
    run = preform.layup(scene)
    # bare elements make the stack partial, as uncovered ones make a single ply's export
    assert run.status == "partial", run.error
    assert "of 64 elements of calculix_cap_mesh.inp; 28 with no ply" in run.reasons[0]
    sections = run.products["stack_sections"]
    counts = sections.present().sum(axis=1)
    assert {0, 2, 3} <= set(counts.tolist())  # bare, a drop-off and the whole stack
    return sections


def mesh_file() -> tuple[dict[int, np.ndarray], dict[int, list[int]]]:
    """Nodes (label -> mm) and elements (label -> the 4 corner labels) of the .inp, as text."""
    nodes: dict[int, np.ndarray] = {}
    elements: dict[int, list[int]] = {}
    block = ""
    for line in MESH.read_text().splitlines():
        if line.startswith("**") or not line.strip():
            continue
        if line.startswith("*"):
            block = line.split(",")[0].upper()
            continue
        values = [v.strip() for v in line.split(",") if v.strip()]
        if block == "*NODE":
            nodes[int(values[0])] = np.array([float(v) for v in values[1:4]])
        elif block == "*ELEMENT":
            elements[int(values[0])] = [int(v) for v in values[1:5]]  # S8R: corners first
    return nodes, elements


def in_plane_unit(vector: np.ndarray, normal: np.ndarray) -> np.ndarray:
    v = vector - np.dot(vector, normal) * normal
    return v / np.linalg.norm(v)


def turned(vector: np.ndarray, axis: np.ndarray, degrees: float) -> np.ndarray:
    """``vector`` turned by ``degrees`` about the unit ``axis``, right-handed (Rodrigues)."""
    t = math.radians(degrees)
    return (
        vector * math.cos(t)
        + np.cross(axis, vector) * math.sin(t)
        + axis * np.dot(axis, vector) * (1 - math.cos(t))
    )


# -- LS-DYNA ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def dyna():
    try:
        from ansys.dyna.core import Deck
    except ImportError:
        if os.environ.get("CI"):
            pytest.fail("CI is set and ansys-dyna-core is missing: it is a test dependency")
        pytest.skip("ansys-dyna-core is not installed: pip install ansys-dyna-core")

    def load(text: str) -> tuple[list, list]:
        deck = Deck()
        result = deck.loads(text)
        return list(deck.all_keywords), list(result.warnings)

    return load


def test_ansys_dyna_core_reads_every_element_and_integration_point(stack, dyna) -> None:
    text = stack_lsdyna_text(stack, material_ids={"plain-weave-600": 3, "satin-4hs-crowfoot": 8})
    lines = text.splitlines()
    assert all(len(line) <= 80 for line in lines)  # LS-DYNA's card width
    keywords, warnings = dyna(text)
    assert not warnings
    assert [k.keyword for k in keywords] == ["ELEMENT", "SET"]
    nodes, corners = mesh_file()
    mids = {"plain-weave-600": 3, "satin-4hs-crowfoot": 8}
    present = stack.present()
    thickness = stack.thickness_mm()
    normal = stack.normal
    ids = stack.mesh.element_ids.tolist()
    # the element cards: the line after the two column comments, then the cards of each element
    at = lines.index("*ELEMENT_SHELL_COMPOSITE") + 3
    end = next(k for k in range(at, len(lines)) if lines[k].startswith("*"))
    body = lines[at:end]
    read = 0
    while body:
        element_card = body[0]
        eid = int(element_card[:8])
        e = ids.index(eid)
        plies = np.nonzero(present[e])[0].tolist()  # the cap's normals point away from the tool
        cards = body[1 : 1 + (len(plies) + 1) // 2]
        body = body[1 + len(cards) :]
        points = []
        for card in cards:
            (kw,), problems = dyna(f"*KEYWORD\n*ELEMENT_SHELL_COMPOSITE\n{element_card}\n{card}\n")
            assert not problems
            assert (kw.eid, kw.pid) == (eid, 1)
            assert [kw.n1, kw.n2, kw.n3, kw.n4] == corners[eid]
            assert [kw.n5, kw.n6, kw.n7, kw.n8] == [0, 0, 0, 0]
            points.append((kw.mid1, kw.thick1, kw.b1))
            if len(card.rstrip()) > 40:
                points.append((kw.mid2, kw.thick2, kw.b2))
            else:  # an odd count: the card's second half is blank
                assert math.isnan(kw.mid2) if isinstance(kw.mid2, float) else not kw.mid2
        assert len(points) == len(plies)
        a, b = (nodes[n] for n in corners[eid][:2])
        for (mid, thick, beta), k in zip(points, plies, strict=True):
            assert mid == mids[stack.plies[k].material]
            assert thick == pytest.approx(thickness[e, k], rel=1e-6)
            # B turns the N1->N2 edge about the normal onto the ply's u fibres
            edge = in_plane_unit(b - a, normal[e])
            fibre = in_plane_unit(stack.plies[k].mapping.fibre_u[e], normal[e])
            assert np.dot(turned(edge, normal[e], beta), fibre) == pytest.approx(1.0, abs=1e-6)
        read += 1
    assert read == int(present.any(axis=1).sum())
    bare = keywords[1]
    assert type(bare).__name__ == "SetShellList"
    assert bare.sid == 1
    listed = [int(v) for v in bare.shells]
    assert sorted(listed) == sorted(np.asarray(ids)[~present.any(axis=1)].tolist())


# -- ANSYS --------------------------------------------------------------------------------------

PARAMETER = re.compile(r"^([A-Za-z][A-Za-z0-9_]{0,31})\s*=\s*(\S+)")


def read_apdl(text: str) -> dict:
    """The model an APDL stack file describes, read as MAPDL's /PREP7 would: parameters,
    local systems, shell sections and what EMODIF gives each element; any command or field
    out of the reference's rules is an assertion."""
    params: dict[str, float] = {}
    systems: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    sections: dict[int, list[tuple[float, int, float, int]]] = {}
    esys: dict[int, int] = {}
    secnum: dict[int, int] = {}
    selected: set[int] | None = None
    components: dict[str, set[int]] = {}
    current: int | None = None
    for number, raw in enumerate(text.splitlines(), 1):
        assert len(raw) <= 640, f"line {number}: longer than an APDL command line"
        line = raw.split("!", 1)[0].strip()
        if not line:
            continue
        match = PARAMETER.match(line)
        if match:
            params[match.group(1).upper()] = float(match.group(2))
            continue
        field = [f.strip() for f in line.split(",")]
        command = field[0].upper()

        def number_of(value: str) -> float:
            return params[value.upper()] if value.upper() in params else float(value)

        if command in ("/PREP7", "CSYS", "ALLSEL"):
            continue
        if command == "LOCAL":
            kcn, kcs = int(field[1]), int(field[2])
            assert kcn > 10 and kcs == 0, f"line {number}: LOCAL {kcn} must be > 10, Cartesian"
            xyz = np.array([number_of(v) for v in field[3:6]])
            thxy, thyz, thzx = (number_of(v) for v in field[6:9])
            # three successive rotations of the global axes, each about an axis of the last
            x, y, z = np.eye(3)
            x, y = turned(x, z, thxy), turned(y, z, thxy)
            y, z = turned(y, x, thyz), turned(z, x, thyz)
            z, x = turned(z, y, thzx), turned(x, y, thzx)
            systems[kcn] = (xyz, x, z)
        elif command == "SECTYPE":
            assert field[2].upper() == "SHELL", f"line {number}: not a shell section"
            current = int(field[1])
            assert current not in sections, f"line {number}: section {current} twice"
            sections[current] = []
        elif command == "SECDATA":
            assert current is not None, f"line {number}: SECDATA before SECTYPE"
            tk, mat, theta, numpt = field[1:5]
            assert number_of(tk) > 0
            assert mat.upper() in params, f"line {number}: material {mat} is no parameter"
            assert int(numpt) in (1, 3, 5, 7, 9), f"line {number}: NUMPT {numpt}"
            sections[current].append(
                (number_of(tk), int(params[mat.upper()]), number_of(theta), int(numpt))
            )
        elif command == "EMODIF":
            element, what, value = int(field[1]), field[2].upper(), int(field[3])
            if what == "ESYS":
                assert value in systems, f"line {number}: ESYS {value} not defined"
                esys[element] = value
            else:
                assert what == "SECNUM" and value in sections, f"line {number}: {what}"
                secnum[element] = value
        elif command == "ESEL":
            if field[1].upper() == "NONE":
                selected = set()
            else:
                assert field[1:3] == ["A", "ELEM"] and selected is not None
                selected.add(int(field[4]))
        elif command == "CM":
            assert field[2].upper() == "ELEM" and selected is not None
            assert re.match(r"^[A-Za-z][A-Za-z0-9_]{0,31}$", field[1])
            components[field[1].upper()] = selected
        else:
            raise AssertionError(f"line {number}: unexpected command {command}")
    return {
        "params": params,
        "systems": systems,
        "sections": sections,
        "esys": esys,
        "secnum": secnum,
        "components": components,
    }


def test_an_apdl_reader_from_the_command_reference_reads_the_stack(stack) -> None:
    text = stack_ansys_text(stack, prefix="LAY")
    model = read_apdl(text)
    names = dict(
        re.findall(r"^(LAY_M\d+) = \d+\s+! (\S+)$", text, re.M)
    )  # the parameters' comments name the materials
    material = {int(model["params"][p]): name for p, name in names.items()}
    present = stack.present()
    thickness = stack.thickness_mm()
    ids = stack.mesh.element_ids.tolist()
    nodes, corners = mesh_file()
    for e, eid in enumerate(ids):
        plies = np.nonzero(present[e])[0].tolist()
        if not plies:
            assert eid not in model["secnum"] and eid not in model["esys"]
            continue
        origin, x_axis, z_axis = model["systems"][model["esys"][eid]]
        # the system sits on its element (10 mm across, its corners' mean off the sphere by
        # less than 0.5 mm)
        middle = np.mean([nodes[n] for n in corners[eid]], axis=0)
        assert np.linalg.norm(origin - middle) < 0.5
        assert np.dot(z_axis, stack.normal[e]) == pytest.approx(1.0, abs=1e-7)
        layers = model["sections"][model["secnum"][eid]]
        assert len(layers) == len(plies)  # bottom (tool side) first: the cap's normals point out
        for (tk, mat, theta, _), k in zip(layers, plies, strict=True):
            assert material[mat] == stack.plies[k].material
            assert tk == pytest.approx(thickness[e, k], rel=1e-7)
            fibre = in_plane_unit(stack.plies[k].mapping.fibre_u[e], stack.normal[e])
            assert np.dot(turned(x_axis, z_axis, theta), fibre) == pytest.approx(1.0, abs=1e-7)
    bare = np.asarray(ids)[~present.any(axis=1)].tolist()
    assert model["components"] == {"LAY_BARE": set(bare)}
