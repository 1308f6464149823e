"""ANSYS Mechanical APDL input of a mapped drape: an element coordinate system per element.

For each covered element the file defines a local Cartesian system with ``LOCAL`` (origin at the
element centroid; x along the u fibres, z along the element normal, y = z × x) and points the
element at it with ``EMODIF, elem, ESYS, n``. APDL's ``LOCAL`` takes three rotations from the
global axes: THXY about Z, then THYZ about the new X, then THZX about the new Y (degrees); the
angles are solved from the frame here. Shell elements project the system's x axis onto their
plane (ANSYS's ESYS rule); x already lies in it, so the element's x axis is the u fibre
direction. Uncovered elements get no system and are grouped in the component
``<P>_UNCOVERED`` (``CM``), covered ones in ``<P>_COVERED``.

Thickness and the v family, when the nominal thickness t0 is known: ANSYS gives a shell its
thickness and layers through its section, so each covered element gets a section of its own
(``SECTYPE, s, SHELL``, numbered from ``first_section``) with two layers (``SECDATA, TK, MAT,
THETA, NUMPT``): the u family (thickness f·t, material ``materials[0]``, THETA 0: along the
element x axis, which is the u fibres) and the v family ((1 − f)·t, ``materials[1]``, THETA
the angle from the u to the v fibres about the element normal, i.e. 90° minus the shear),
t the mapped thickness t0 · t/t0 and f ``u_fraction`` (½ for a balanced fabric); then
``EMODIF, elem, SECNUM, s``. A two-layer section is how ANSYS models a biaxial fabric as two
unidirectional layers, the usual smeared model of an NCF; each layer's material is a
unidirectional one with its fibres along its own x. The material numbers are APDL
parameters at the top of the file (``<P>_MAT_U``, ``<P>_MAT_V``), to be pointed at the
model's materials. Without t0 no section is written (the element keeps its own) and the v
family is only in the per-element table. Lengths in mm, angles in degrees.
"""

from __future__ import annotations

import os

import numpy as np

from preform.base.arrays import FloatArray
from preform.base.atomic import atomic_open
from preform.export.fe_mapping import MeshMapping


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


def layer_angle_v_deg(mapping: MeshMapping) -> FloatArray:
    """THETA of the v layer [deg]: the angle from the u to the v fibres about the element
    normal (right-hand rule), in (−180, 180]; NaN where not covered."""
    u, v, n = mapping.fibre_u, mapping.fibre_v, mapping.normal
    sin = np.einsum("ij,ij->i", np.cross(u, v), n)
    cos = np.einsum("ij,ij->i", u, v)
    return np.asarray(np.degrees(np.arctan2(sin, cos)))


def ansys_macro_text(
    mapping: MeshMapping,
    *,
    prefix: str = "PREFORM",
    first_system: int = 1001,
    first_section: int = 1001,
    materials: tuple[int, int] = (1, 1),
    u_fraction: float = 0.5,
) -> str:
    """The APDL input (module docstring); systems are numbered from ``first_system`` (> 10),
    sections from ``first_section``; ``materials`` the MAT numbers of the u and v layers,
    ``u_fraction`` the share of the thickness [mm] in the u layer."""
    if first_system <= 10:
        raise ValueError("ANSYS local coordinate system numbers must be greater than 10")
    if first_section < 1 or min(materials) < 1:
        raise ValueError("ANSYS section and material numbers start at 1")
    if not 0.0 < u_fraction < 1.0:
        raise ValueError(f"u_fraction must lie strictly between 0 and 1, got {u_fraction!r}")
    name = prefix.upper()
    mesh = mapping.mesh
    cov = mapping.covered
    x = mapping.fibre_u
    z = mapping.normal
    y = np.cross(z, x)
    frames = np.stack([x, y, z], axis=-1)
    summary = mapping.summary()
    sections = mapping.nominal_thickness_mm is not None
    theta_v = layer_angle_v_deg(mapping)
    lines = [
        f"! preform drape mapped onto {mesh.source_name or 'a shell mesh'}",
        "! Units: lengths in mm, angles in degrees. Element x axis = u fibre direction.",
        f"! Covered elements: {summary['elements_covered']} of {summary['elements']}; "
        f"uncovered: {summary['elements_uncovered']}"
        # the component is named only when it is written
        + (f" (component {name}_UNCOVERED, no system)." if summary["elements_uncovered"] else "."),
        (
            f"! Thickness and both fibre families: a two-layer shell section per element, "
            f"u layer {u_fraction:g} of t at THETA 0, v layer {1 - u_fraction:g} of t at THETA "
            f"= angle u->v (thickness model: {mapping.thickness_words})."
            if sections
            else "! Thickness is not set here: t0 unknown (see the per-element table)."
        ),
        "/PREP7",
    ]
    if sections:
        lines += [
            "! Materials of the u and v layers (unidirectional, fibres along the layer x):",
            f"{name}_MAT_U = {int(materials[0])}",
            f"{name}_MAT_V = {int(materials[1])}",
        ]
    ids = mesh.element_ids
    system = first_system
    for k in np.nonzero(cov)[0].tolist():
        a, b, c = local_angles_deg(frames[k : k + 1])[0]
        cx, cy, cz = mapping.centroid_mm[k]
        lines.append(f"LOCAL,{system},0,{cx:.9g},{cy:.9g},{cz:.9g},{a:.9g},{b:.9g},{c:.9g}")
        lines.append(f"EMODIF,{int(ids[k])},ESYS,{system}")
        system += 1
        if sections:
            section = first_section + system - first_system - 1
            t = float(mapping.thickness_mm[k])
            lines += [
                f"SECTYPE,{section},SHELL",
                f"SECDATA,{u_fraction * t:.9g},{name}_MAT_U,0,3",
                f"SECDATA,{(1 - u_fraction) * t:.9g},{name}_MAT_V,{theta_v[k]:.9g},3",
                f"EMODIF,{int(ids[k])},SECNUM,{section}",
            ]
    lines.append("CSYS,0")
    for label, members in (("COVERED", ids[cov]), ("UNCOVERED", ids[~cov])):
        if members.size == 0:
            lines.append(f"! no {label.lower()} element: no such component written")
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
    first_section: int = 1001,
    materials: tuple[int, int] = (1, 1),
    u_fraction: float = 0.5,
) -> None:
    """Write :func:`ansys_macro_text` to ``path`` (atomically, ASCII)."""
    text = ansys_macro_text(
        mapping,
        prefix=prefix,
        first_system=first_system,
        first_section=first_section,
        materials=materials,
        u_fraction=u_fraction,
    )
    with atomic_open(path, "w", encoding="ascii") as handle:
        handle.write(text.encode("ascii", "replace").decode("ascii"))
