"""Abaqus include file of a mapped drape: local fibre directions and thickness per element.

What the file holds (keyword syntax after the Abaqus Keywords Reference: *DISTRIBUTION TABLE,
*DISTRIBUTION, *ORIENTATION, *ELSET):

- ``*ELSET`` ``<P>_COVERED`` and ``<P>_UNCOVERED`` (``<P>`` the prefix, default PREFORM):
  the elements the drape covers and those it does not. Uncovered elements appear in no
  data line.
- For each fibre family (u, v): a ``*DISTRIBUTION`` (LOCATION=ELEMENT, table COORD3D,
  COORD3D) whose data line per covered element gives point a = the fibre direction (local
  axis 1) and point b = n × a (in the element's plane, so local axis 3 is the element
  normal), and an ``*ORIENTATION`` (<P>_U, <P>_V) that references it, with the second line
  ``3, 0.`` that shells require (no extra rotation about the normal). Two orientations because
  a sheared fabric's families are not at 90°: model the ply as two layers, or one orthotropic
  layer along u, as the material model asks.
- A ``*DISTRIBUTION`` of thickness (table LENGTH) in mm: t0 · t/t0 per covered element, for
  ``*SHELL SECTION, SHELL THICKNESS=<P>_THICKNESS``; written only when t0 is known.

Abaqus requires the first data line of a distribution to be the default (blank element
field), used for any element of a section that has no line of its own. The file gives the
global x axis and t0 there, and a comment says the defaults are *not* drape results: apply the
orientations and thickness to ``ELSET=<P>_COVERED`` only, and decide what ``<P>_UNCOVERED``
gets. Lengths in mm (the user's model must be in mm too), angles in degrees.
Include it inside the ``*PART`` that holds the elements (or the flat model).
"""

from __future__ import annotations

import os
from collections.abc import Iterable

import numpy as np

from preform.base.atomic import atomic_open
from preform.export.fe_mapping import MeshMapping

#: Abaqus allows at most 16 entries on a data line of a set.
PER_LINE = 16


def _set_lines(labels: Iterable[int]) -> list[str]:
    items = [str(int(x)) for x in labels]
    return [", ".join(items[k : k + PER_LINE]) for k in range(0, len(items), PER_LINE)]


def _num(x: float) -> str:
    # Abaqus reads up to 256 characters a line; 10 significant digits keeps unit vectors unit
    # to 1e-10 and each line short.
    return f"{x:.10g}" if "e" in f"{x:.10g}" or "." in f"{x:.10g}" else f"{x:.10g}."


def abaqus_include_text(
    mapping: MeshMapping, *, prefix: str = "PREFORM", title: str | None = None
) -> str:
    """The include file's text (module docstring)."""
    from preform.base.export_section import prefix_problem

    problem = prefix_problem(prefix)
    if problem is not None:
        raise ValueError(problem)
    name = prefix.upper()
    cov = mapping.covered
    ids = mapping.mesh.element_ids
    summary = mapping.summary()
    out = [
        f"** preform drape mapped onto {mapping.mesh.source_name or 'a shell mesh'}"
        + (f": {title}" if title else ""),
        "** Units: lengths in mm, angles in degrees. Element labels from the "
        f"{mapping.mesh.labels_from}.",
        f"** Covered elements: {summary['elements_covered']} of {summary['elements']}; "
        f"uncovered: {summary['elements_uncovered']}"
        # the set is named only when it is written (Abaqus refuses an empty *ELSET)
        + (f" (ELSET={name}_UNCOVERED)." if summary["elements_uncovered"] else "."),
        f"** Thickness model: {mapping.thickness_words}.",
        f"** Node spacing of the drape: {mapping.node_spacing_mm:g} mm; mapping by closest "
        "point on the net, bilinear inside cells.",
        "** The first data line of each *DISTRIBUTION is the default Abaqus requires; it is NOT",
        f"** a drape result. Use the orientations and thickness with ELSET={name}_COVERED only.",
    ]
    if mapping.thickness_cap_ratio is not None:
        out.append(
            f"** Elements above the compaction cap t/t0 = {mapping.thickness_cap_ratio:g}: "
            f"{summary['elements_above_thickness_cap']} (not capped; "
            f"ELSET={name}_ABOVE_CAP)."
        )
    for label, members in (("COVERED", ids[cov]), ("UNCOVERED", ids[~cov])):
        # Abaqus refuses an *ELSET without data lines: an empty set is said in a comment
        if members.size:
            out.append(f"*ELSET, ELSET={name}_{label}")
            out += _set_lines(members)
        else:
            out.append(f"** No {label.lower()} element: no such set written.")
    for flag, label in (
        (mapping.past_locking, "PAST_LOCKING"),
        (mapping.past_failure, "PAST_FAILURE"),
        (mapping.above_thickness_cap, "ABOVE_CAP"),
    ):
        if flag.any():
            out.append(f"*ELSET, ELSET={name}_{label}")
            out += _set_lines(ids[flag])
    out += [f"*DISTRIBUTION TABLE, NAME={name}_COORD_TABLE", "COORD3D, COORD3D"]
    normal = mapping.normal
    for family, vectors in (("U", mapping.fibre_u), ("V", mapping.fibre_v)):
        dist = f"{name}_DIR_{family}"
        out.append(f"*DISTRIBUTION, NAME={dist}, LOCATION=ELEMENT, TABLE={name}_COORD_TABLE")
        out.append(", 1., 0., 0., 0., 1., 0.")
        second = np.cross(normal, vectors)
        for label, a, b in zip(ids[cov], vectors[cov], second[cov], strict=True):
            out.append(f"{int(label)}, " + ", ".join(_num(float(x)) for x in (*a, *b)))
        out += [
            f"*ORIENTATION, NAME={name}_{family}, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR",
            dist,
            "3, 0.",
        ]
    if mapping.nominal_thickness_mm is not None:
        out += [
            f"*DISTRIBUTION TABLE, NAME={name}_LENGTH_TABLE",
            "LENGTH",
            f"*DISTRIBUTION, NAME={name}_THICKNESS, LOCATION=ELEMENT, TABLE={name}_LENGTH_TABLE",
            f", {_num(mapping.nominal_thickness_mm)}",
        ]
        for label, t in zip(ids[cov], mapping.thickness_mm[cov], strict=True):
            out.append(f"{int(label)}, {_num(float(t))}")
        out += [
            "** Use in your model, e.g.:",
            f"** *SHELL SECTION, ELSET={name}_COVERED, MATERIAL=<yours>, "
            f"ORIENTATION={name}_U, SHELL THICKNESS={name}_THICKNESS",
            f"** {_num(mapping.nominal_thickness_mm)}, 5",
        ]
    else:
        out.append("** No thickness distribution: the ply's nominal thickness t0 is not known.")
    return "\n".join(out) + "\n"


def write_abaqus_include(
    mapping: MeshMapping,
    path: str | os.PathLike[str],
    *,
    prefix: str = "PREFORM",
    title: str | None = None,
) -> None:
    """Write :func:`abaqus_include_text` to ``path`` (atomically)."""
    write_ascii(abaqus_include_text(mapping, prefix=prefix, title=title), path)


def write_ascii(text: str, path: str | os.PathLike[str]) -> None:
    """Write a deck's text to ``path`` atomically as ASCII (γ spelt, anything else replaced):
    Abaqus, CalculiX and LS-DYNA input is ASCII."""
    text = text.replace("γ", "gamma").encode("ascii", "replace").decode("ascii")
    with atomic_open(path, "w", encoding="ascii") as handle:
        handle.write(text)
