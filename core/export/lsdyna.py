"""LS-DYNA include of a mapped drape: ``*ELEMENT_SHELL_BETA`` with the fibre angle and thickness.

Each covered element is written as ``*ELEMENT_SHELL_BETA`` (fixed format: card 1 EID, PID,
N1–N8 in 8-character fields; card 2 THIC1–THIC4 and BETA in 16-character fields). BETA is
the angle [deg] from the element's N1→N2 edge to the u fibre family (projected into the
element's plane), about the element normal by the right-hand rule on the node order: the
material angle that a ``*MAT`` with AOPT = 0 adds to the element's own axes. THIC1–THIC4 are
the mapped thickness t0 · t/t0 [mm] at all four nodes (the mapping gives one value per
element), or 0.0, which tells LS-DYNA to take the section's thickness, when t0 is unknown.
Triangles repeat N3 as N4, as LS-DYNA expects.

These cards *define* the elements, so they replace the user's own ``*ELEMENT_SHELL`` cards of
the same elements (LS-DYNA stops on a duplicate element id rather than silently taking one).
Uncovered elements are not written; they are listed in ``*SET_SHELL_LIST`` (SID
``uncovered_set_id``) so the model can give them what it decides. The v family is not in the
file: ``*ELEMENT_SHELL_BETA`` carries one angle; the per-element table has both. Lengths in mm
(the user's model must use mm), angles in degrees.
"""

from __future__ import annotations

import os

import numpy as np

from preform.export.atomic import atomic_open
from preform.export.fe_mapping import MeshMapping

#: Largest id an 8-character field holds.
MAX_ID = 99_999_999


def _angle_from_first_edge_deg(mapping: MeshMapping) -> np.ndarray:
    n = mapping.normal
    edge = mapping.mesh.first_edges()
    # a warped quad's first edge leaves its mean plane: project it back
    edge = edge - np.einsum("ij,ij->i", edge, n)[:, None] * n
    with np.errstate(invalid="ignore", divide="ignore"):
        edge /= np.linalg.norm(edge, axis=1, keepdims=True)
    f = mapping.fibre_u
    sin = np.einsum("ij,ij->i", np.cross(edge, f), n)
    cos = np.einsum("ij,ij->i", edge, f)
    return np.asarray(np.degrees(np.arctan2(sin, cos)))


def _f16(x: float) -> str:
    text = f"{x:16.9g}"
    if len(text) > 16:
        text = f"{x:16.8e}"[:16]
    return text


def lsdyna_include_text(
    mapping: MeshMapping,
    *,
    part_id: int = 1,
    uncovered_set_id: int = 1,
    title: str | None = None,
) -> str:
    """The include file's text (module docstring). ``part_id`` is the PID of elements whose
    mesh gave none (Nastran's PID is kept)."""
    mesh = mapping.mesh
    cov = mapping.covered
    if mesh.element_ids.max(initial=0) > MAX_ID or mesh.node_ids.max(initial=0) > MAX_ID:
        raise ValueError(
            "element or node ids above 99,999,999 do not fit LS-DYNA's 8-character fields"
        )
    pids = np.where(mesh.property_ids > 0, mesh.property_ids, part_id)
    beta = _angle_from_first_edge_deg(mapping)
    corners = np.where(mesh.corners < 0, mesh.corners[:, [2]], mesh.corners)
    node_labels = mesh.node_ids[corners]
    summary = mapping.summary()
    lines = [
        "*KEYWORD",
        "$ preform drape mapped onto "
        + (mesh.source or "a shell mesh")
        + (f": {title}" if title else ""),
        "$ Units: lengths in mm, angles in degrees. BETA from the N1->N2 edge to the u fibres.",
        f"$ Covered elements: {summary['elements_covered']} of {summary['elements']}; "
        f"uncovered: {summary['elements_uncovered']} (*SET_SHELL_LIST {uncovered_set_id}).",
        f"$ Thickness model: {mapping.thickness_model}"
        + ("" if mapping.nominal_thickness_mm is not None else "; t0 unknown: THIC = 0 (section)"),
        "$ These cards replace your *ELEMENT_SHELL cards of the same elements.",
        "*ELEMENT_SHELL_BETA",
        "$#   eid     pid      n1      n2      n3      n4      n5      n6      n7      n8",
        "$#          thic1           thic2           thic3           thic4            beta",
    ]
    for k in np.nonzero(cov)[0].tolist():
        n1, n2, n3, n4 = (int(v) for v in node_labels[k])
        lines.append(
            f"{int(mesh.element_ids[k]):8d}{int(pids[k]):8d}{n1:8d}{n2:8d}{n3:8d}{n4:8d}"
            + f"{0:8d}" * 4
        )
        t = mapping.thickness_mm[k]
        t = 0.0 if not np.isfinite(t) else float(t)
        lines.append("".join(_f16(v) for v in (t, t, t, t, float(beta[k]))))
    lines += ["*SET_SHELL_LIST", "$#     sid"]
    lines.append(f"{uncovered_set_id:10d}")
    uncovered = mesh.element_ids[~cov].tolist()
    for k in range(0, len(uncovered), 8):
        lines.append("".join(f"{int(e):10d}" for e in uncovered[k : k + 8]))
    lines.append("*END")
    return "\n".join(lines) + "\n"


def write_lsdyna_include(
    mapping: MeshMapping,
    path: str | os.PathLike[str],
    *,
    part_id: int = 1,
    uncovered_set_id: int = 1,
    title: str | None = None,
) -> None:
    """Write :func:`lsdyna_include_text` to ``path`` (atomically, ASCII)."""
    text = lsdyna_include_text(
        mapping, part_id=part_id, uncovered_set_id=uncovered_set_id, title=title
    )
    text = text.replace("γ", "gamma").encode("ascii", "replace").decode("ascii")
    with atomic_open(path, "w", encoding="ascii") as handle:
        handle.write(text)
