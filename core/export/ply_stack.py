"""A ply stack on the user's FE mesh: what the composite-section writers take.

A layup drape (one :class:`~preform.export.fe_mapping.MeshMapping` per ply, all on the same
shell mesh) becomes a :class:`StackSections`: the plies in stacking order, tool side first, each
with its material name. Per element, the plies present are those whose mapping covers the
element; a ply that does not cover an element is *absent* there (a drop-off): it is left out of
that element's section and counted, never given a default angle or thickness.

Layer order. Solvers list a composite section's layers from the element's negative side to its
positive side (the normal by the right-hand rule on the element's nodes). The tool side is
where the drape's outward normal u × v points away from (a ply's generator angle is counted
counter-clockwise seen from outside), so where an element's normal points into the tool
(n · (u × v) < 0 for its first present ply) its layers are written outermost ply first;
:meth:`StackSections.layer_order` gives the order and the files' headers count those elements.
The section's reference surface is the solver's default, the element's mid-surface.

The writers (Abaqus and CalculiX :mod:`preform.export.stack_abaqus`, LS-DYNA
:mod:`preform.export.stack_lsdyna`, ANSYS :mod:`preform.export.stack_ansys`) write, per element,
each present ply as one layer: its thickness t0 · t/t0 [mm], its material, and its material
axis 1 along the ply's u fibres projected into the element's plane (axis 3 the element normal).
A ply's material is the fabric's orthotropic (or smeared) material in those axes; the v fibres
of a sheared ply are then not along axis 2 (the single-ply two-layer forms model both families).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from preform.export.fe_mapping import MeshMapping
from preform.export.shell_mesh import ShellMesh


@dataclass(frozen=True)
class PlySection:
    """One ply of a stack on the user's mesh."""

    name: str  # ply name, e.g. "ply-1"
    material: str  # material (fabric) name as written in the deck
    mapping: MeshMapping  # that ply mapped onto the user's FE mesh (core/export/fe_mapping.py):
    # per-element fibre directions, thickness_mm, covered

    def __post_init__(self) -> None:
        from preform.export.calculix import deck_name_problem

        for what, value in (("ply name", self.name), ("material", self.material)):
            problem = deck_name_problem(value, what)
            if problem is not None:
                raise ValueError(problem)
        if self.mapping.nominal_thickness_mm is None:
            raise ValueError(
                f"ply {self.name}: its thickness is not known (the mapping has no t0); a "
                "composite section needs every layer's thickness"
            )
        t = self.mapping.thickness_mm[self.mapping.covered]
        if not np.all(np.isfinite(t) & (t > 0)):
            raise ValueError(f"ply {self.name}: a covered element has no positive thickness")


@dataclass(frozen=True)
class StackSections:
    """The plies of a stack on one FE mesh."""

    plies: tuple[PlySection, ...]  # stacking order, tool side first

    def __post_init__(self) -> None:
        if not self.plies:
            raise ValueError("a stack needs at least one ply")
        names = [p.name for p in self.plies]
        doubled = sorted({n for n in names if names.count(n) > 1})
        if doubled:
            raise ValueError(f"ply names must differ; repeated: {', '.join(doubled)}")
        first = self.plies[0].mapping.mesh
        for ply in self.plies[1:]:
            mesh = ply.mapping.mesh
            same = mesh is first or (
                np.array_equal(mesh.element_ids, first.element_ids)
                and np.array_equal(mesh.corners, first.corners)
                and np.allclose(mesh.points, first.points)
            )
            if not same:
                raise ValueError(
                    f"ply {ply.name} is mapped onto another mesh than ply {self.plies[0].name}: "
                    "a stack's plies must share the user's FE mesh"
                )

    @property
    def mesh(self) -> ShellMesh:
        """The FE mesh all plies are mapped onto."""
        return self.plies[0].mapping.mesh

    @property
    def normal(self) -> NDArray[np.float64]:
        """Unit element normals (m, 3): axis 3 of every layer."""
        return self.plies[0].mapping.normal

    def present(self) -> NDArray[np.bool_]:
        """(m, n_plies): ply p is present on element e (its mapping covers e)."""
        return np.column_stack([p.mapping.covered for p in self.plies])

    def thickness_mm(self) -> NDArray[np.float64]:
        """(m, n_plies) layer thickness [mm], 0 where the ply is absent."""
        present = self.present()
        t = np.column_stack([p.mapping.thickness_mm for p in self.plies])
        return np.where(present, t, 0.0)

    def total_thickness_mm(self) -> NDArray[np.float64]:
        """Stack thickness per element [mm]: the sum of the present plies (0 where bare)."""
        return np.asarray(self.thickness_mm().sum(axis=1))

    def normal_into_tool(self) -> NDArray[np.bool_]:
        """(m,): the element's normal points into the tool (n · (u × v) < 0 for its first
        present ply); False where no ply is present."""
        present = self.present()
        first = np.argmax(present, axis=1)
        rows = np.arange(len(first))
        u = np.stack([p.mapping.fibre_u for p in self.plies], axis=1)[rows, first]
        v = np.stack([p.mapping.fibre_v for p in self.plies], axis=1)[rows, first]
        outward = np.einsum("ij,ij->i", np.cross(u, v), self.normal)
        return np.asarray(present.any(axis=1) & (np.nan_to_num(outward, nan=1.0) < 0))

    def layer_order(self) -> list[list[int]]:
        """Per element, the indices of its present plies from the element's negative side to
        its positive side: stacking order, reversed where the normal points into the tool."""
        present = self.present()
        into = self.normal_into_tool()
        out = []
        for e in range(present.shape[0]):
            order = np.nonzero(present[e])[0].tolist()
            out.append(order[::-1] if into[e] else order)
        return out

    def materials(self) -> list[str]:
        """Material names in order of first use (tool side first)."""
        return list(dict.fromkeys(p.material for p in self.plies))

    def summary(self) -> dict[str, Any]:
        """JSON-ready counts: elements, bare elements (no ply), and per ply the elements where
        it is absent although another ply is there (its drop-offs)."""
        present = self.present()
        any_ply = present.any(axis=1)
        ids = self.mesh.element_ids
        return {
            "elements": len(ids),
            "plies": [p.name for p in self.plies],
            "materials": self.materials(),
            "elements_bare": int(np.count_nonzero(~any_ply)),
            "bare_element_ids": ids[~any_ply].tolist(),
            "elements_all_plies": int(np.count_nonzero(present.all(axis=1))),
            "ply_absent_elements": {
                p.name: int(np.count_nonzero(any_ply & ~present[:, k]))
                for k, p in enumerate(self.plies)
            },
            "elements_normal_into_tool": int(np.count_nonzero(self.normal_into_tool())),
            "max_total_thickness_mm": float(self.total_thickness_mm().max(initial=0.0)),
            "length_unit": "mm",
            "angle_unit": "deg",
        }

    def comment_lines(self, mark: str, first: str, bare_set: str) -> list[str]:
        """A deck's header: ``first`` (what the deck is), then the stack's summary, as comment
        lines (``mark``: ``**``, ``$`` or ``!``) of at most 80 columns, LS-DYNA's card width
        (a long name is broken, never cut off). ``bare_set`` names the set of elements with
        no ply, named only when there are such elements (it is written only then)."""
        s = self.summary()
        sentences = [
            first,
            "Stack, tool side first: "
            + ", ".join(f"{p.name} ({p.material})" for p in self.plies)
            + ".",
            "Units: lengths in mm, angles in degrees. Layer axis 1 = the ply's u fibres.",
            f"Elements: {s['elements']}; with every ply: {s['elements_all_plies']}; with no "
            f"ply: {s['elements_bare']}"
            + (f" ({bare_set}, no section here)." if s["elements_bare"] else "."),
        ]
        if s["elements_normal_into_tool"]:
            sentences.append(
                "Elements whose normal points into the tool, layers listed outermost ply "
                f"first (from the normal's negative side): {s['elements_normal_into_tool']}."
            )
        absent = [f"{name} {n}" for name, n in s["ply_absent_elements"].items() if n]
        if absent:
            sentences.append(
                "Drop-offs (elements where a ply is absent and left out): "
                + ", ".join(absent)
                + "."
            )
        lines: list[str] = []
        for sentence in sentences:
            lines += textwrap.wrap(
                sentence,
                80,
                initial_indent=f"{mark} ",
                subsequent_indent=f"{mark}   ",
                break_on_hyphens=False,
            )
        return lines
