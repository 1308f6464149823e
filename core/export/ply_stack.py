"""A layup's plies mapped onto the user's FE mesh, tool side first: what the solver writers
take to write composite sections (one ply per layer, each with its material and per-element
fibre directions and thickness, ``preform.export.fe_mapping``)."""

from __future__ import annotations

from dataclasses import dataclass

from preform.export.fe_mapping import MeshMapping


@dataclass(frozen=True)
class PlySection:
    """One ply of the stack on the FE mesh: its name, its material (the fabric's name) and
    its drape mapped onto the mesh (mm, degrees)."""

    name: str
    material: str
    mapping: MeshMapping


@dataclass(frozen=True)
class StackSections:
    """The stack on the FE mesh: its plies in stacking order, tool side first."""

    plies: tuple[PlySection, ...]
