"""CalculiX include of a mapped drape: one explicit orientation and one shell section per element.

Why a flavour of its own: CalculiX (ccx 2.20) reads Abaqus-format decks but not
``*DISTRIBUTION`` tables or ``*ORIENTATION, DEFINITION=COORDINATES``; it runs the Abaqus include
(:mod:`preform.export.abaqus`) with exit 0 and applies none of its orientations. What ccx does
apply is an ``*ORIENTATION, SYSTEM=RECTANGULAR`` with its two points on the data line, named by a
``*SHELL SECTION`` (``tests/export/test_calculix_solver.py`` runs ccx to show both).

What the file holds, for each covered element with label L (``<P>`` the prefix):

- ``*ORIENTATION, NAME=<P>_U<L>``: point a = the u fibre direction (local axis 1), point b =
  n × a (in the element's plane, so local axis 3 is the element normal n), second line ``3, 0.``;
- ``*ELSET, ELSET=<P>_E<L>`` holding the element alone;
- ``*SHELL SECTION, ELSET=<P>_E<L>, MATERIAL=<material>, ORIENTATION=<P>_U<L>`` with the mapped
  thickness t0 · t/t0 [mm] (``form="orthotropic"``: one layer, the fabric's orthotropic
  material with its axis 1 along the u fibres);
- or, with ``form="two-layer"``, also ``<P>_V<L>`` along the v fibres and a ``*SHELL SECTION,
  COMPOSITE`` of two unidirectional layers: u (thickness f·t, ``materials[0]``) and v
  ((1 − f)·t, ``materials[1]``), f = ``u_fraction``: both families of a sheared fabric, whose
  fibres are not at 90°. ccx accepts COMPOSITE only on S8R and S6 elements.

A section names one orientation, so every element has its own section: grouping elements of
equal thickness would not reduce their number. ``*ELSET`` ``<P>_COVERED`` / ``<P>_UNCOVERED``
as in the Abaqus include; uncovered elements get no orientation and no section (the model gives
them what it decides; ccx stops on a shell without a section, "first thickness ... is zero").
The materials are the model's own ``*MATERIAL`` cards, named here. Lengths in mm, angles in
degrees. Include it after the elements (``*INCLUDE, INPUT=drape_calculix.inp``).
"""

from __future__ import annotations

import os
from typing import Any, Literal

import numpy as np

from preform.export.abaqus import _num, _set_lines, write_ascii
from preform.export.fe_mapping import MeshMapping
from preform.export.shell_mesh import ShellMesh

#: CalculiX reads names of at most 80 characters.
MAX_NAME = 80

Form = Literal["orthotropic", "two-layer"]


def deck_name_problem(name: str, what: str) -> str | None:
    """Why ``name`` cannot be a material or ply name in an Abaqus/CalculiX deck (a letter, then
    letters, digits, ``_``, ``-`` or ``.``, at most 80 characters), or None."""
    ok = name[:1].isalpha() and all(c.isalnum() or c in "_-." for c in name)
    if not name or not name.isascii() or len(name) > MAX_NAME or not ok:
        return (
            f"{what} {name!r} is not a deck name: a letter, then ASCII letters, digits, _ - or ."
            f" (at most {MAX_NAME})"
        )
    return None


def orientation_lines(name: str, axis_1: np.ndarray, normal: np.ndarray) -> list[str]:
    """An explicit rectangular ``*ORIENTATION``: axis 1 along ``axis_1``, axis 3 along
    ``normal`` (point b = n × a lies in the shell's plane)."""
    b = np.cross(normal, axis_1)
    return [
        f"*ORIENTATION, NAME={name}, SYSTEM=RECTANGULAR",
        ", ".join(_num(float(x)) for x in (*axis_1, *b)),
        "3, 0.",
    ]


def mesh_name(mesh: ShellMesh) -> str:
    """The mesh file's name without its folder, for a deck's header (a deck goes to other
    machines: it names nothing of the one it was written on)."""
    return mesh.source_name or "a shell mesh"


def covered_sets(mapping: MeshMapping, name: str) -> list[str]:
    """``*ELSET`` cards of the covered and uncovered elements; an empty set is not written
    (a solver refuses an ``*ELSET`` without members) but said in a comment."""
    ids = mapping.mesh.element_ids
    out: list[str] = []
    for label, members in (("COVERED", ids[mapping.covered]), ("UNCOVERED", ids[~mapping.covered])):
        if members.size:
            out += [f"*ELSET, ELSET={name}_{label}", *_set_lines(members)]
        else:
            out.append(f"** No {label.lower()} element: no such set written.")
    return out


def calculix_include_text(
    mapping: MeshMapping,
    *,
    prefix: str = "PREFORM",
    form: Form = "orthotropic",
    material: str | None = None,
    materials: tuple[str, str] | None = None,
    u_fraction: float = 0.5,
    title: str | None = None,
) -> str:
    """The include file's text (module docstring). ``material``: the fabric's material name for
    the orthotropic form (default ``<P>_FABRIC``); ``materials``: the u and v layers' names for
    the two-layer form (default ``<P>_UD`` for both); ``u_fraction``: share of the thickness in
    the u layer. Needs the ply's nominal thickness t0 (a section needs a thickness [mm])."""
    from preform.base.export_section import prefix_problem

    problem = prefix_problem(prefix)
    if problem is not None:
        raise ValueError(problem)
    if form not in ("orthotropic", "two-layer"):
        raise ValueError(f"form must be 'orthotropic' or 'two-layer', got {form!r}")
    if mapping.nominal_thickness_mm is None:
        raise ValueError(
            "a CalculiX shell section needs a thickness: the ply's nominal thickness t0 is not "
            "known (export.nominal_thickness_mm)"
        )
    if not 0.0 < u_fraction < 1.0:
        raise ValueError(f"u_fraction must lie strictly between 0 and 1, got {u_fraction!r}")
    name = prefix.upper()
    fabric = material if material is not None else f"{name}_FABRIC"
    mat_u, mat_v = materials if materials is not None else (f"{name}_UD", f"{name}_UD")
    for what, value in (("material", fabric), ("material", mat_u), ("material", mat_v)):
        problem = deck_name_problem(value, what)
        if problem is not None:
            raise ValueError(problem)
    summary = mapping.summary()
    uses = (
        f"one orthotropic layer of material {fabric}, axis 1 along the u fibres"
        if form == "orthotropic"
        else f"two unidirectional layers (COMPOSITE, S8R/S6 only): u ({mat_u}, {u_fraction:g} "
        f"of t), v ({mat_v}, {1 - u_fraction:g} of t)"
    )
    out = [
        f"** preform drape mapped onto {mesh_name(mapping.mesh)} for CalculiX"
        + (f": {title}" if title else ""),
        "** Units: lengths in mm, angles in degrees. Element labels from the "
        f"{mapping.mesh.labels_from}.",
        f"** Covered elements: {summary['elements_covered']} of {summary['elements']}; "
        f"uncovered: {summary['elements_uncovered']}"
        # the set is named only when it is written
        + (
            f" (ELSET={name}_UNCOVERED), given no section here: give them one."
            if summary["elements_uncovered"]
            else "."
        ),
        f"** Thickness model: {mapping.thickness_words}.",
        f"** Per covered element: explicit orientation(s) and a shell section, {uses}.",
        "** Define the material(s) named here with *MATERIAL in your model.",
    ]
    if form == "orthotropic" and summary["elements_covered"]:
        out.append(
            f"** Largest |shear| {summary['max_abs_shear_deg']:.3g} deg: the v fibres are that "
            "far from axis 2 (the two-layer form models both families)."
        )
    out += covered_sets(mapping, name)
    ids = mapping.mesh.element_ids
    for k in np.nonzero(mapping.covered)[0].tolist():
        label = int(ids[k])
        n = mapping.normal[k]
        t = float(mapping.thickness_mm[k])
        out += orientation_lines(f"{name}_U{label}", mapping.fibre_u[k], n)
        if form == "two-layer":
            out += orientation_lines(f"{name}_V{label}", mapping.fibre_v[k], n)
        out += [f"*ELSET, ELSET={name}_E{label}", str(label)]
        if form == "orthotropic":
            out += [
                f"*SHELL SECTION, ELSET={name}_E{label}, MATERIAL={fabric}, "
                f"ORIENTATION={name}_U{label}",
                _num(t),
            ]
        else:
            out += [
                f"*SHELL SECTION, ELSET={name}_E{label}, COMPOSITE",
                f"{_num(u_fraction * t)}, , {mat_u}, {name}_U{label}",
                f"{_num((1 - u_fraction) * t)}, , {mat_v}, {name}_V{label}",
            ]
    return "\n".join(out) + "\n"


def write_calculix_include(
    mapping: MeshMapping, path: str | os.PathLike[str], **options: Any
) -> None:
    """Write :func:`calculix_include_text` (same options) to ``path``, atomically, in ASCII."""
    write_ascii(calculix_include_text(mapping, **options), path)
