"""ANSYS Mechanical APDL input of a mapped drape: an element coordinate system per element.

For each covered element the file defines a local Cartesian system with ``LOCAL`` (origin at the
element centroid; x along the u fibres, z along the element normal, y = z × x) and points the
element at it with ``EMODIF, elem, ESYS, n``. APDL's ``LOCAL`` takes three rotations from the
global axes: THXY about Z, then THYZ about the new X, then THZX about the new Y (degrees); the
angles are solved from the frame here. Shell elements project the system's x axis onto their
plane (ANSYS's ESYS rule); x already lies in it, so the element's x axis is the u fibre
direction. Uncovered elements get no system and are grouped in the component
``<P>_UNCOVERED`` (``CM``), covered ones in ``<P>_COVERED``.

Not in the file: the v family (one element system carries one direction; both are in the
per-element table) and the thickness (ANSYS gives shells their thickness per section, so a
per-element thickness needs a section per value or a ``SECFUNCTION`` table: left to the
user, with ``thickness_mm`` from the table). Lengths in mm, angles in degrees.
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import NDArray

from preform.export.atomic import atomic_open
from preform.export.fe_mapping import MeshMapping

FloatArray = NDArray[np.float64]


def local_angles_deg(frames: FloatArray) -> FloatArray:
    """THXY, THYZ, THZX [deg] (k, 3) of orthonormal frames (k, 3, 3) whose columns are the local
    x, y, z axes in global coordinates, for R = Rz(THXY) · Rx(THYZ) · Ry(THZX)."""
    r = np.asarray(frames, dtype=float)
    # R[2, 1] = sin THYZ and (R[0, 1], R[1, 1]) = cos THYZ (−sin THXY, cos THXY): atan2 keeps
    # THYZ accurate near ±90° where asin would not
    b = np.arctan2(r[:, 2, 1], np.hypot(r[:, 0, 1], r[:, 1, 1]))
    a = np.arctan2(-r[:, 0, 1], r[:, 1, 1])
    # THZX from what is left, Ry(c) = (Rz(a) Rx(b))ᵀ R, so the three always rebuild R even
    # where THXY is ill-defined (local y along ±Z, then a is arbitrary and c makes up for it)
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    zx = np.zeros((len(r), 3, 3))
    zx[:, 0, 0], zx[:, 0, 1], zx[:, 0, 2] = ca, -sa * cb, sa * sb
    zx[:, 1, 0], zx[:, 1, 1], zx[:, 1, 2] = sa, ca * cb, -ca * sb
    zx[:, 2, 1], zx[:, 2, 2] = sb, cb
    rest = np.einsum("kji,kjl->kil", zx, r)
    c = np.arctan2(rest[:, 0, 2], rest[:, 0, 0])
    return np.degrees(np.column_stack([a, b, c]))


def ansys_macro_text(
    mapping: MeshMapping, *, prefix: str = "PREFORM", first_system: int = 1001
) -> str:
    """The APDL input (module docstring); systems are numbered from ``first_system`` (> 10)."""
    if first_system <= 10:
        raise ValueError("ANSYS local coordinate system numbers must be greater than 10")
    name = prefix.upper()
    mesh = mapping.mesh
    cov = mapping.covered
    x = mapping.fibre_u
    z = mapping.normal
    y = np.cross(z, x)
    frames = np.stack([x, y, z], axis=-1)
    summary = mapping.summary()
    lines = [
        f"! preform drape mapped onto {mesh.source or 'a shell mesh'}",
        "! Units: lengths in mm, angles in degrees. Element x axis = u fibre direction.",
        f"! Covered elements: {summary['elements_covered']} of {summary['elements']}; "
        f"uncovered: {summary['elements_uncovered']} (component {name}_UNCOVERED, no system).",
        "! Thickness is not set here (see the per-element table, thickness_mm).",
        "/PREP7",
    ]
    ids = mesh.element_ids
    system = first_system
    for k in np.nonzero(cov)[0].tolist():
        a, b, c = local_angles_deg(frames[k : k + 1])[0]
        cx, cy, cz = mapping.centroid_mm[k]
        lines.append(f"LOCAL,{system},0,{cx:.9g},{cy:.9g},{cz:.9g},{a:.9g},{b:.9g},{c:.9g}")
        lines.append(f"EMODIF,{int(ids[k])},ESYS,{system}")
        system += 1
    lines.append("CSYS,0")
    for label, members in (("COVERED", ids[cov]), ("UNCOVERED", ids[~cov])):
        if members.size == 0:
            lines.append(f"! component {name}_{label} would be empty")
            continue
        lines.append("ESEL,NONE")
        lines += [f"ESEL,A,ELEM,,{int(e)}" for e in members.tolist()]
        lines.append(f"CM,{name}_{label},ELEM")
    lines.append("ALLSEL")
    return "\n".join(lines) + "\n"


def write_ansys_macro(
    mapping: MeshMapping,
    path: str | os.PathLike[str],
    *,
    prefix: str = "PREFORM",
    first_system: int = 1001,
) -> None:
    """Write :func:`ansys_macro_text` to ``path`` (atomically, ASCII)."""
    text = ansys_macro_text(mapping, prefix=prefix, first_system=first_system)
    with atomic_open(path, "w", encoding="ascii") as handle:
        handle.write(text.encode("ascii", "replace").decode("ascii"))
