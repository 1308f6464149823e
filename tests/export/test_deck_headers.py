"""What the solver decks say about themselves: nothing of the machine they were written on,
LS-DYNA cards within 80 columns, and every set a comment names is a set the deck defines."""

from __future__ import annotations

import re

import numpy as np
import pytest

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.abaqus import abaqus_include_text
from preform.export.ansys import ansys_macro_text
from preform.export.fe_mapping import map_to_mesh
from preform.export.lsdyna import lsdyna_composite_text, lsdyna_include_text
from preform.export.shell_mesh import read_shell_mesh
from preform.plugins.surfaces.basic import Plane

#: Two 10 mm squares on the plane z = 0; the second lies 400 mm away, past a 100 mm ply.
NODES = [(0, 0), (10, 0), (10, 10), (0, 10), (400, 0), (410, 0), (410, 10), (400, 10)]
LONG_NAME = "tool_surface_of_the_left_hand_door_inner_panel_revision_C_shell_mesh_coarse.inp"


def write_inp(path, elements: int) -> None:
    lines = ["*NODE"]
    lines += [f"{k + 1}, {x}., {y}., 0." for k, (x, y) in enumerate(NODES)]
    lines.append("*ELEMENT, TYPE=S4R, ELSET=SKIN")
    lines += ["1, 1, 2, 3, 4", "2, 5, 6, 7, 8"][:elements]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def net():
    return drape(
        Plane((1.0, 1.0)),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.1, 0.1)),
        generator_angle_rad=np.radians(70.0),
    )


def decks(net, folder, elements: int) -> dict[str, str]:
    """Every deck of a mesh read from a file deep in ``folder`` (so its source is a long
    absolute path): one element covered, and with ``elements`` = 2 one element uncovered."""
    deep = folder / "home" / "someone" / "projects" / "door"
    deep.mkdir(parents=True)
    path = deep / LONG_NAME
    write_inp(path, elements)
    mapping = map_to_mesh(net, read_shell_mesh(path), nominal_thickness_mm=0.3)
    assert str(folder) in mapping.mesh.source  # the reader keeps where it read from
    title = "E-BX-318 over the door panel, least-energy generator angle, ply 3 of 8, " * 2
    return {
        "abaqus": abaqus_include_text(mapping, title=title),
        "lsdyna": lsdyna_include_text(mapping, title=title, uncovered_set_id=7),
        "lsdyna composite": lsdyna_composite_text(mapping, title=title, uncovered_set_id=7),
        "ansys": ansys_macro_text(mapping),
    }


@pytest.mark.parametrize("elements", [1, 2], ids=["all covered", "one uncovered"])
def test_decks_name_the_mesh_by_its_file_name_only(net, tmp_path, elements) -> None:
    for kind, text in decks(net, tmp_path, elements).items():
        assert str(tmp_path) not in text, kind
        assert "/home/someone" not in text and "projects" not in text, kind
        first = text.splitlines()[1 if kind.startswith("lsdyna") else 0]
        assert "preform drape mapped onto" in first, kind
        assert LONG_NAME[:40] in text.replace("\n$   ", ""), kind


@pytest.mark.parametrize("elements", [1, 2], ids=["all covered", "one uncovered"])
def test_lsdyna_lines_fit_80_columns(net, tmp_path, elements) -> None:
    texts = decks(net, tmp_path, elements)
    for kind in ("lsdyna", "lsdyna composite"):
        lines = texts[kind].splitlines()
        too_long = [line for line in lines if len(line) > 80]
        assert not too_long, (kind, too_long)
        # the long title and file name are wrapped onto comment lines, not cut off
        comments = " ".join(line[1:].strip() for line in lines if line.startswith("$ "))
        assert "ply 3 of 8" in comments and "Covered elements: 1 of" in comments


def defined_and_named(text: str, kind: str) -> tuple[set[str], set[str]]:
    """Sets a deck defines, and sets its comments name."""
    comment = {"abaqus": "**", "ansys": "!"}.get(kind, "$")
    lines = text.splitlines()
    notes = "\n".join(line for line in lines if line.startswith(comment))
    if kind == "abaqus":
        defined = {m for line in lines for m in re.findall(r"^\*ELSET, ELSET=(\w+)", line)}
        named = set(re.findall(r"ELSET=(\w+)\)", notes))
    elif kind == "ansys":
        defined = {m for line in lines for m in re.findall(r"^CM,(\w+),ELEM", line)}
        named = set(re.findall(r"component ([A-Z][A-Z0-9_]+)", notes))
    else:
        defined = set()
        for k, line in enumerate(lines):
            if line == "*SET_SHELL_LIST":
                data = [row for row in lines[k + 1 :] if not row.startswith("$")]
                defined.add(str(int(data[0][:10])))
        named = set(re.findall(r"\*SET_SHELL_LIST (\d+)", notes))
    return defined, named


@pytest.mark.parametrize("elements", [1, 2], ids=["all covered", "one uncovered"])
def test_every_set_the_header_names_is_written(net, tmp_path, elements) -> None:
    for kind, text in decks(net, tmp_path, elements).items():
        defined, named = defined_and_named(text, kind)
        assert named <= defined, (kind, named - defined)
        uncovered = {"abaqus": "PREFORM_UNCOVERED", "ansys": "PREFORM_UNCOVERED"}.get(kind, "7")
        # the uncovered set exists exactly when an element is uncovered, and is then named
        assert (uncovered in defined) == (elements == 2), kind
        assert (uncovered in named) == (elements == 2), kind
        if kind.startswith("lsdyna"):
            assert ("*SET_SHELL_LIST" in text) == (elements == 2), kind
