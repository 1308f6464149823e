"""Composite shell sections of a ply stack, per element, for Abaqus and CalculiX.

For every element with at least one ply (``<P>`` the prefix, L the element label, k the ply's
1-based place in the stack):

- one ``*ORIENTATION, NAME=<P>_<k>_<L>, SYSTEM=RECTANGULAR`` per present ply: point a = the
  ply's u fibres in the element's plane, point b = n × a, second line ``3, 0.`` (no extra
  rotation), so layer axis 3 is the element normal;
- ``*ELSET, ELSET=<P>_E<L>`` and ``*SHELL SECTION, ELSET=<P>_E<L>, COMPOSITE`` with one data
  line per present ply from the element's negative side (tool side first where the normal
  points away from the tool; :meth:`~preform.export.ply_stack.StackSections.layer_order`):
  thickness [mm], section points, material, orientation, and (Abaqus) the ply name.

Explicit orientations rather than ``*DISTRIBUTION`` tables, because the plies present and their
thicknesses differ from element to element (drop-offs, sheared thickness), so each element needs
a section of its own anyway; and because this is the form CalculiX applies. The CalculiX flavour
leaves the section-points field blank (ccx ignores it) and no ply name; ccx accepts COMPOSITE on
S8R and S6 elements only. Elements with no ply are in ``*ELSET, ELSET=<P>_BARE`` and get no
section. Lengths in mm, angles in degrees; the materials are the model's own ``*MATERIAL`` cards.
"""

from __future__ import annotations

import os
from typing import Any, Literal

import numpy as np

from preform.export.abaqus import _num, _set_lines, write_ascii
from preform.export.calculix import mesh_name, orientation_lines
from preform.export.ply_stack import StackSections

Flavour = Literal["abaqus", "calculix"]


def stack_sections_text(
    stack: StackSections,
    *,
    prefix: str = "PREFORM",
    flavour: Flavour = "abaqus",
    section_points: int = 3,
    title: str | None = None,
) -> str:
    """The include's text (module docstring); ``section_points``: integration points through
    each layer (Abaqus; ccx chooses its own)."""
    from preform.base.export_section import prefix_problem

    problem = prefix_problem(prefix)
    if problem is not None:
        raise ValueError(problem)
    if flavour not in ("abaqus", "calculix"):
        raise ValueError(f"flavour must be 'abaqus' or 'calculix', got {flavour!r}")
    if section_points < 1:
        raise ValueError("a layer needs at least one section point")
    name = prefix.upper()
    mesh = stack.mesh
    ids = mesh.element_ids
    present = stack.present()
    thickness = stack.thickness_mm()
    normal = stack.normal
    out = [
        *stack.comment_lines(
            "**",
            f"preform ply stack mapped onto {mesh_name(mesh)}"
            + (f" for {'CalculiX' if flavour == 'calculix' else 'Abaqus'}")
            + (f": {title}" if title else ""),
            f"ELSET={name}_BARE",
        ),
        "** Define these materials with *MATERIAL in your model: " + ", ".join(stack.materials()),
    ]
    if flavour == "calculix":
        out.append("** ccx accepts *SHELL SECTION, COMPOSITE on S8R and S6 elements only.")
    bare = ids[~present.any(axis=1)]
    if bare.size:
        out += [f"*ELSET, ELSET={name}_BARE", *_set_lines(bare)]
    order = stack.layer_order()
    for e in np.nonzero(present.any(axis=1))[0].tolist():
        label = int(ids[e])
        layers = []
        for k in order[e]:
            ply = stack.plies[k]
            orient = f"{name}_{k + 1}_{label}"
            out += orientation_lines(orient, ply.mapping.fibre_u[e], normal[e])
            t = _num(float(thickness[e, k]))
            if flavour == "abaqus":
                layers.append(f"{t}, {section_points}, {ply.material}, {orient}, {ply.name}")
            else:
                layers.append(f"{t}, , {ply.material}, {orient}")
        out += [
            f"*ELSET, ELSET={name}_E{label}",
            str(label),
            f"*SHELL SECTION, ELSET={name}_E{label}, COMPOSITE",
            *layers,
        ]
    return "\n".join(out) + "\n"


def write_stack_sections(
    stack: StackSections, path: str | os.PathLike[str], **options: Any
) -> None:
    """Write :func:`stack_sections_text` (same options) to ``path``, atomically, in ASCII."""
    write_ascii(stack_sections_text(stack, **options), path)
