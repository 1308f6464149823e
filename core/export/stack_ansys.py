"""ANSYS Mechanical APDL input of a ply stack: a layered shell section per element.

For each element with at least one ply: a local Cartesian system (``LOCAL``, origin at the
element centroid, x along the u fibres of the element's first layer,
z along the element normal; angles as :func:`preform.export.ansys.local_angles_deg` solves
them) pointed at with ``EMODIF, elem, ESYS``; and a section of its own (``SECTYPE, s, SHELL``)
with one ``SECDATA, TK, MAT, THETA, NUMPT`` layer per present ply from the element's
bottom (−normal) side, as ANSYS numbers layers (stacking order, reversed where the normal
points into the tool): the ply's thickness t0 · t/t0 [mm], its material, THETA the
angle [deg] from the element x axis to the ply's u fibres about the normal (0 for the first
layer), then ``EMODIF, elem, SECNUM, s``. A ply absent from an element (a drop-off) has no layer
there. Material numbers are APDL parameters at the top (``<P>_M1``, ``<P>_M2``, ... with the
material names in comments; default 1, 2, ... in order of first use), to be pointed at the
model's materials. Elements with no ply are the component ``<P>_BARE``. Lengths in mm, angles
in degrees.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from preform.export.abaqus import write_ascii
from preform.export.ansys import local_angles_deg
from preform.export.calculix import mesh_name
from preform.export.ply_stack import StackSections
from preform.export.stack_lsdyna import stack_material_ids


def _signed_angle_deg(a: np.ndarray, b: np.ndarray, n: np.ndarray) -> np.ndarray:
    sin = np.einsum("ij,ij->i", np.cross(a, b), n)
    return np.asarray(np.degrees(np.arctan2(sin, np.einsum("ij,ij->i", a, b))))


def stack_ansys_text(
    stack: StackSections,
    *,
    prefix: str = "PREFORM",
    first_system: int = 1001,
    first_section: int = 1001,
    material_ids: Mapping[str, int] | None = None,
    points_per_layer: int = 3,
) -> str:
    """The APDL input (module docstring); systems numbered from ``first_system`` (> 10),
    sections from ``first_section``."""
    from preform.base.export_section import prefix_problem

    problem = prefix_problem(prefix)
    if problem is not None:
        raise ValueError(problem)
    if first_system <= 10:
        raise ValueError("ANSYS local coordinate system numbers must be greater than 10")
    if first_section < 1:
        raise ValueError("ANSYS section numbers start at 1")
    name = prefix.upper()
    mids = stack_material_ids(stack, material_ids)
    param = {m: f"{name}_M{k + 1}" for k, m in enumerate(mids)}
    mesh = stack.mesh
    ids = mesh.element_ids
    present = stack.present()
    thickness = stack.thickness_mm()
    z = stack.normal
    fibres = np.stack([p.mapping.fibre_u for p in stack.plies], axis=1)  # (m, plies, 3)
    has = present.any(axis=1)
    order = stack.layer_order()
    first_ply = np.array([o[0] if o else 0 for o in order], dtype=np.int64)
    x = fibres[np.arange(len(ids)), first_ply]
    frames = np.stack([x, np.cross(z, x), z], axis=-1)
    centroid = stack.plies[0].mapping.centroid_mm
    lines = [
        *stack.comment_lines(
            "!", f"preform ply stack mapped onto {mesh_name(mesh)}", f"component {name}_BARE"
        ),
        "! Element x axis = u fibres of the element's first layer; THETA from it.",
        "/PREP7",
        "! Material numbers (point them at your materials):",
    ]
    for m, mid in mids.items():
        lines.append(f"{param[m]} = {mid}  ! {m}")
    system, section = first_system, first_section
    for e in np.nonzero(has)[0].tolist():
        a, b, c = local_angles_deg(frames[e : e + 1])[0]
        cx, cy, cz = centroid[e]
        label = int(ids[e])
        lines += [
            f"LOCAL,{system},0,{cx:.9g},{cy:.9g},{cz:.9g},{a:.9g},{b:.9g},{c:.9g}",
            f"EMODIF,{label},ESYS,{system}",
            f"SECTYPE,{section},SHELL",
        ]
        theta = _signed_angle_deg(
            np.repeat(x[e : e + 1], len(stack.plies), axis=0),
            fibres[e],
            np.repeat(z[e : e + 1], len(stack.plies), axis=0),
        )
        for k in order[e]:
            lines.append(
                f"SECDATA,{float(thickness[e, k]):.9g},{param[stack.plies[k].material]},"
                f"{float(theta[k]):.9g},{points_per_layer}"
            )
        lines.append(f"EMODIF,{label},SECNUM,{section}")
        system += 1
        section += 1
    lines.append("CSYS,0")
    bare = ids[~has]
    if bare.size:
        lines.append("ESEL,NONE")
        lines += [f"ESEL,A,ELEM,,{int(e)}" for e in bare.tolist()]
        lines += [f"CM,{name}_BARE,ELEM", "ALLSEL"]
    return "\n".join(lines) + "\n"


def write_stack_ansys(stack: StackSections, path: str | os.PathLike[str], **options: Any) -> None:
    """Write :func:`stack_ansys_text` (same options) to ``path``, atomically, in ASCII."""
    write_ascii(stack_ansys_text(stack, **options), path)
