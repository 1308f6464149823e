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
``uncovered_set_id``; no set when every element is covered) so the model can give them what
it decides. Comment lines (``$``) are wrapped at 80 columns, as every card, and name the mesh
by its file name only. The v family is not in this
form: ``*ELEMENT_SHELL_BETA`` carries one angle; the per-element table has both. Lengths in mm
(the user's model must use mm), angles in degrees.

Both families: the ``composite`` form (``lsdyna_composite_text``) writes each covered element
as ``*ELEMENT_SHELL_COMPOSITE`` instead (card 1 as above; card 2 in 10-character fields MID1,
THICK1, B1, blank, MID2, THICK2, B2, blank): two through-thickness integration points, the u
family (material ``materials[0]``, thickness f·t, angle B1 = BETA of the u fibres) and the v
family (``materials[1]``, (1 − f)·t, B2 from the same N1→N2 edge to the v fibres), t the
mapped thickness and f ``u_fraction`` (½ for a balanced fabric): a biaxial fabric as two
unidirectional layers, each material's fibres along its a-axis (AOPT = 0). It needs t0 (a
layer thickness cannot be "the section's").
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from preform.export.abaqus import write_ascii
from preform.export.fe_mapping import MeshMapping

#: Largest id an 8-character field holds.
MAX_ID = 99_999_999
#: Columns of an LS-DYNA card: keyword input is read 80 columns a line, comments included.
CARD_COLUMNS = 80


def _comments(sentences: Iterable[str]) -> list[str]:
    """``$`` comment lines of at most ``CARD_COLUMNS`` columns, one sentence a paragraph
    (a name longer than a line is broken: nothing may pass column 80)."""
    lines: list[str] = []
    for sentence in sentences:
        lines += textwrap.wrap(
            sentence,
            CARD_COLUMNS,
            initial_indent="$ ",
            subsequent_indent="$   ",
            break_on_hyphens=False,
        )
    return lines


def _header(
    mapping: MeshMapping, title: str | None, uncovered_set_id: int, *sentences: str
) -> list[str]:
    """The comment lines that open a deck: the mesh by its file name (nothing of the machine
    it was written on), units, coverage (the uncovered set named only when it is written)."""
    summary = mapping.summary()
    uncovered = summary["elements_uncovered"]
    return _comments(
        [
            "preform drape mapped onto "
            + (mapping.mesh.source_name or "a shell mesh")
            + (f": {title}" if title else ""),
            *sentences,
            f"Covered elements: {summary['elements_covered']} of {summary['elements']}; "
            f"uncovered: {uncovered}"
            + (f" (*SET_SHELL_LIST {uncovered_set_id})." if uncovered else "."),
        ]
    )


def _f10(x: float) -> str:
    """A real in a 10-character field, as many digits as fit."""
    for digits in range(8, 0, -1):
        text = f"{x:10.{digits}g}"
        if len(text) <= 10:
            return text
    raise ValueError(f"{x!r} does not fit a 10-character LS-DYNA field")


def _f16(x: float) -> str:
    text = f"{x:16.9g}"
    if len(text) > 16:
        text = f"{x:16.8e}"[:16]
    return text


def _element_cards(mapping: MeshMapping, part_id: int) -> tuple[Any, Any]:
    """Part id and the four node labels (a triangle repeats its third) of every element, after
    checking the ids fit LS-DYNA's 8-character fields; Nastran's PID is kept where given."""
    mesh = mapping.mesh
    if mesh.element_ids.max(initial=0) > MAX_ID or mesh.node_ids.max(initial=0) > MAX_ID:
        raise ValueError(
            "element or node ids above 99,999,999 do not fit LS-DYNA's 8-character fields"
        )
    pids = np.where(mesh.property_ids > 0, mesh.property_ids, part_id)
    corners = np.where(mesh.corners < 0, mesh.corners[:, [2]], mesh.corners)
    return pids, mesh.node_ids[corners]


def _uncovered_set(element_ids: Any, set_id: int) -> list[str]:
    """A ``*SET_SHELL_LIST`` of the elements the drape does not cover (8 ids a card); none
    when every element is covered (an empty list is no set)."""
    ids = [int(e) for e in element_ids]
    if not ids:
        return []
    lines = ["*SET_SHELL_LIST", "$#     sid", f"{set_id:10d}"]
    for k in range(0, len(ids), 8):
        lines.append("".join(f"{e:10d}" for e in ids[k : k + 8]))
    return lines


def shell_deck(
    mapping: MeshMapping,
    part_id: int,
    opening: list[str],
    written: Any,
    cards: Callable[[int], list[str]],
    set_id: int,
) -> str:
    """A keyword file: ``*KEYWORD``, the ``opening`` lines (comments, the element keyword and
    its column comments), card 1 (EID, PID, N1–N8) then ``cards(k)`` of every element k where
    ``written`` (bool per element), the ``*SET_SHELL_LIST`` ``set_id`` of the others, ``*END``."""
    mesh = mapping.mesh
    pids, node_labels = _element_cards(mapping, part_id)
    lines = ["*KEYWORD", *opening]
    for k in np.nonzero(written)[0].tolist():
        n1, n2, n3, n4 = (int(v) for v in node_labels[k])
        lines.append(
            f"{int(mesh.element_ids[k]):8d}{int(pids[k]):8d}{n1:8d}{n2:8d}{n3:8d}{n4:8d}"
            + f"{0:8d}" * 4
        )
        lines += cards(k)
    lines += _uncovered_set(mesh.element_ids[~written], set_id)
    lines.append("*END")
    return "\n".join(lines) + "\n"


def lsdyna_include_text(
    mapping: MeshMapping,
    *,
    part_id: int = 1,
    uncovered_set_id: int = 1,
    title: str | None = None,
) -> str:
    """The include file's text (module docstring). ``part_id`` is the PID of elements whose
    mesh gave none (Nastran's PID is kept)."""
    beta = _angle_from_first_edge_to(mapping, mapping.fibre_u)

    def thickness_and_beta(k: int) -> list[str]:
        t = mapping.thickness_mm[k]
        t = 0.0 if not np.isfinite(t) else float(t)
        return ["".join(_f16(v) for v in (t, t, t, t, float(beta[k])))]

    opening = [
        *_header(
            mapping,
            title,
            uncovered_set_id,
            "Units: lengths in mm, angles in degrees. BETA from the N1->N2 edge to the u fibres.",
        ),
        *_comments(
            [
                f"Thickness model: {mapping.thickness_words}"
                + (
                    ""
                    if mapping.nominal_thickness_mm is not None
                    else "; t0 unknown: THIC = 0 (section)"
                ),
                "These cards replace your *ELEMENT_SHELL cards of the same elements.",
            ]
        ),
        "*ELEMENT_SHELL_BETA",
        "$#   eid     pid      n1      n2      n3      n4      n5      n6      n7      n8",
        "$#         thic1           thic2           thic3           thic4            beta",
    ]
    return shell_deck(
        mapping, part_id, opening, mapping.covered, thickness_and_beta, uncovered_set_id
    )


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
    write_ascii(text, path)


def _angle_from_first_edge_to(mapping: MeshMapping, fibre: np.ndarray) -> np.ndarray:
    """Angle [deg] from each element's N1→N2 edge to ``fibre``, about the element normal."""
    n = mapping.normal
    # a warped quad's first edge leaves its mean plane: project it back
    edge = mapping.mesh.first_edges()
    edge = edge - np.einsum("ij,ij->i", edge, n)[:, None] * n
    with np.errstate(invalid="ignore", divide="ignore"):
        edge /= np.linalg.norm(edge, axis=1, keepdims=True)
    sin = np.einsum("ij,ij->i", np.cross(edge, fibre), n)
    cos = np.einsum("ij,ij->i", edge, fibre)
    return np.asarray(np.degrees(np.arctan2(sin, cos)))


def lsdyna_composite_text(
    mapping: MeshMapping,
    *,
    part_id: int = 1,
    uncovered_set_id: int = 1,
    materials: tuple[int, int] = (1, 1),
    u_fraction: float = 0.5,
    title: str | None = None,
) -> str:
    """The include in the ``*ELEMENT_SHELL_COMPOSITE`` form (module docstring): both fibre
    families as two integration points; thicknesses [mm], angles [deg]."""
    if mapping.nominal_thickness_mm is None:
        raise ValueError(
            "the composite form needs the ply thickness t0 (export.nominal_thickness_mm)"
        )
    if not 0.0 < u_fraction < 1.0:
        raise ValueError(f"u_fraction must lie strictly between 0 and 1, got {u_fraction!r}")
    if min(materials) < 1:
        raise ValueError("LS-DYNA material ids start at 1")
    beta_u = _angle_from_first_edge_to(mapping, mapping.fibre_u)
    beta_v = _angle_from_first_edge_to(mapping, mapping.fibre_v)

    def two_layers(k: int) -> list[str]:
        t = float(mapping.thickness_mm[k])
        return [
            f"{int(materials[0]):10d}{_f10(u_fraction * t)}{_f10(float(beta_u[k]))}{'':10}"
            f"{int(materials[1]):10d}{_f10((1 - u_fraction) * t)}{_f10(float(beta_v[k]))}"
        ]

    opening = [
        *_header(
            mapping,
            title,
            uncovered_set_id,
            "Units: lengths in mm, angles in degrees. B1/B2 from the N1->N2 edge to the u/v "
            "fibres.",
            f"Two layers: u (MID {materials[0]}, {u_fraction:g} of t), "
            f"v (MID {materials[1]}, {1 - u_fraction:g} of t).",
        ),
        *_comments(
            [
                f"Thickness model: {mapping.thickness_words}",
                "These cards replace your *ELEMENT_SHELL cards of the same elements.",
            ]
        ),
        "*ELEMENT_SHELL_COMPOSITE",
        "$#   eid     pid      n1      n2      n3      n4      n5      n6      n7      n8",
        "$#    mid1    thick1        b1              mid2    thick2        b2",
    ]
    return shell_deck(mapping, part_id, opening, mapping.covered, two_layers, uncovered_set_id)


def write_lsdyna_composite(
    mapping: MeshMapping,
    path: str | os.PathLike[str],
    *,
    part_id: int = 1,
    uncovered_set_id: int = 1,
    materials: tuple[int, int] = (1, 1),
    u_fraction: float = 0.5,
    title: str | None = None,
) -> None:
    """Write :func:`lsdyna_composite_text` to ``path`` (atomically, ASCII)."""
    text = lsdyna_composite_text(
        mapping,
        part_id=part_id,
        uncovered_set_id=uncovered_set_id,
        materials=materials,
        u_fraction=u_fraction,
        title=title,
    )
    write_ascii(text, path)
