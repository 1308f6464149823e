"""LS-DYNA cards of a ply stack: ``*ELEMENT_SHELL_COMPOSITE`` with one integration point per ply.

Each element with at least one ply is written as ``*ELEMENT_SHELL_COMPOSITE`` (the card layout
of :mod:`preform.export.lsdyna`: card 1 EID, PID, N1–N8 in 8-character fields; then cards of two
integration points each in 10-character fields, MID, THICK, B, blank, MID, THICK, B, blank), one
integration point per present ply from the element's bottom (−normal) side up (stacking order,
tool side first, reversed where the normal points into the tool): its material id, its
thickness t0 · t/t0 [mm] and B, the angle [deg] from the element's N1→N2 edge to the ply's u
fibres about the element normal (the material angle a ``*MAT`` with AOPT = 0 adds). An odd
count leaves the last card's second half blank. A ply absent from an element (a drop-off) has no
integration point there. Material ids: ``material_ids`` (name -> MID), default 1, 2, ... in
order of first use, listed in the header. Elements with no ply are not written; they are in
``*SET_SHELL_LIST`` ``bare_set_id``. The cards replace the model's own ``*ELEMENT_SHELL`` cards
of the same elements. Lengths in mm, angles in degrees.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from preform.export.abaqus import write_ascii
from preform.export.calculix import mesh_name
from preform.export.lsdyna import _angle_from_first_edge_to, _f10, shell_deck
from preform.export.ply_stack import StackSections


def stack_material_ids(stack: StackSections, given: Mapping[str, int] | None) -> dict[str, int]:
    """Material name -> positive integer id for every material of the stack (``given``, or
    1, 2, ... in order of first use)."""
    names = stack.materials()
    if given is None:
        return {name: k + 1 for k, name in enumerate(names)}
    missing = [n for n in names if n not in given]
    if missing:
        raise ValueError(f"no material id for: {', '.join(missing)}")
    bad = [n for n in names if int(given[n]) < 1]
    if bad:
        raise ValueError(f"material ids start at 1: {', '.join(bad)}")
    return {n: int(given[n]) for n in names}


def stack_lsdyna_text(
    stack: StackSections,
    *,
    part_id: int = 1,
    bare_set_id: int = 1,
    material_ids: Mapping[str, int] | None = None,
    title: str | None = None,
) -> str:
    """The keyword file's text (module docstring)."""
    mids = stack_material_ids(stack, material_ids)
    present = stack.present()
    thickness = stack.thickness_mm()
    beta = np.column_stack(
        [_angle_from_first_edge_to(p.mapping, p.mapping.fibre_u) for p in stack.plies]
    )
    order = stack.layer_order()

    def integration_points(e: int) -> list[str]:
        points = [
            f"{mids[stack.plies[k].material]:10d}{_f10(float(thickness[e, k]))}"
            f"{_f10(float(beta[e, k]))}{'':10}"
            for k in order[e]
        ]
        return ["".join(points[i : i + 2]).rstrip() for i in range(0, len(points), 2)]

    opening = [
        *stack.comment_lines(
            "$",
            f"preform ply stack mapped onto {mesh_name(stack.mesh)}"
            + (f": {title}" if title else ""),
            f"*SET_SHELL_LIST {bare_set_id}",
        ),
        "$ B: from the N1->N2 edge to the ply's u fibres. Material ids:",
        *(f"$   {name} = {mid}" for name, mid in mids.items()),
        "$ These cards replace your *ELEMENT_SHELL cards of the same elements.",
        "*ELEMENT_SHELL_COMPOSITE",
        "$#   eid     pid      n1      n2      n3      n4      n5      n6      n7      n8",
        "$#    mid1    thick1        b1              mid2    thick2        b2",
    ]
    # the elements with no ply are the set (none when every element has one)
    written = present.any(axis=1)
    return shell_deck(
        stack.plies[0].mapping, part_id, opening, written, integration_points, bare_set_id
    )


def write_stack_lsdyna(stack: StackSections, path: str | os.PathLike[str], **options: Any) -> None:
    """Write :func:`stack_lsdyna_text` (same options) to ``path``, atomically, in ASCII."""
    write_ascii(stack_lsdyna_text(stack, **options), path)
