"""Exporters: VTK (.vtu), tables (CSV/Parquet/JSON), the cutting pattern (CSV/DXF/SVG),
figures, and the drape mapped onto a user's FE mesh (Abaqus, CalculiX, LS-DYNA, ANSYS,
per-element table, VTU), one ply or a ply stack (composite sections per element).

One format per module; matplotlib, meshio, shapely and ezdxf are optional extras imported when a
writer runs.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from preform.export.abaqus import write_abaqus_include
    from preform.export.ansys import write_ansys_macro
    from preform.export.calculix import write_calculix_include
    from preform.export.cut_pattern import (
        cut_pattern,
        write_cut_pattern_csv,
        write_cut_pattern_dxf,
        write_cut_pattern_svg,
    )
    from preform.export.element_table import element_table, write_element_table
    from preform.export.fe_mapping import MeshMapping, map_to_mesh
    from preform.export.fig_curves import energy_vs_angle_figure
    from preform.export.fig_drape import fibre_pattern_figure
    from preform.export.fig_unit_cell import unit_cell_figure
    from preform.export.flat_pattern import flat_pattern
    from preform.export.lsdyna import write_lsdyna_include
    from preform.export.mapped_vtu import write_mapped_vtu
    from preform.export.ply_stack import PlySection, StackSections
    from preform.export.shell_mesh import ShellMesh, read_shell_mesh, shell_mesh
    from preform.export.stack_abaqus import write_stack_sections
    from preform.export.stack_ansys import write_stack_ansys
    from preform.export.stack_files import write_stack_files
    from preform.export.stack_lsdyna import write_stack_lsdyna
    from preform.export.tables import cells_table, write_json, write_table
    from preform.export.vtu import write_drape_vtu, write_unit_cell_vtu
    from preform.shear.figures import shear_curve_figure

# Each writer is imported when first asked for: `import preform.export.export_steps` (every
# command's plugin registration) must not pay for every format's module.
_HOME = {
    "MeshMapping": "preform.export.fe_mapping",
    "PlySection": "preform.export.ply_stack",
    "StackSections": "preform.export.ply_stack",
    "ShellMesh": "preform.export.shell_mesh",
    "cells_table": "preform.export.tables",
    "cut_pattern": "preform.export.cut_pattern",
    "element_table": "preform.export.element_table",
    "energy_vs_angle_figure": "preform.export.fig_curves",
    "fibre_pattern_figure": "preform.export.fig_drape",
    "flat_pattern": "preform.export.flat_pattern",
    "map_to_mesh": "preform.export.fe_mapping",
    "read_shell_mesh": "preform.export.shell_mesh",
    "shear_curve_figure": "preform.shear.figures",
    "shell_mesh": "preform.export.shell_mesh",
    "unit_cell_figure": "preform.export.fig_unit_cell",
    "write_abaqus_include": "preform.export.abaqus",
    "write_ansys_macro": "preform.export.ansys",
    "write_calculix_include": "preform.export.calculix",
    "write_cut_pattern_csv": "preform.export.cut_pattern",
    "write_cut_pattern_dxf": "preform.export.cut_pattern",
    "write_cut_pattern_svg": "preform.export.cut_pattern",
    "write_drape_vtu": "preform.export.vtu",
    "write_element_table": "preform.export.element_table",
    "write_json": "preform.export.tables",
    "write_lsdyna_include": "preform.export.lsdyna",
    "write_mapped_vtu": "preform.export.mapped_vtu",
    "write_stack_ansys": "preform.export.stack_ansys",
    "write_stack_files": "preform.export.stack_files",
    "write_stack_lsdyna": "preform.export.stack_lsdyna",
    "write_stack_sections": "preform.export.stack_abaqus",
    "write_table": "preform.export.tables",
    "write_unit_cell_vtu": "preform.export.vtu",
}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        value = getattr(importlib.import_module(_HOME[name]), name)
        globals()[name] = value
        return value
    from preform._moved import RETIRED_NAMES

    if name in RETIRED_NAMES:
        raise AttributeError(RETIRED_NAMES[name])
    raise AttributeError(f"module 'preform.export' has no attribute {name!r}")


__all__ = [
    "MeshMapping",
    "PlySection",
    "ShellMesh",
    "StackSections",
    "cells_table",
    "cut_pattern",
    "element_table",
    "energy_vs_angle_figure",
    "fibre_pattern_figure",
    "flat_pattern",
    "map_to_mesh",
    "read_shell_mesh",
    "shear_curve_figure",
    "shell_mesh",
    "unit_cell_figure",
    "write_abaqus_include",
    "write_ansys_macro",
    "write_calculix_include",
    "write_cut_pattern_csv",
    "write_cut_pattern_dxf",
    "write_cut_pattern_svg",
    "write_drape_vtu",
    "write_element_table",
    "write_json",
    "write_lsdyna_include",
    "write_mapped_vtu",
    "write_stack_ansys",
    "write_stack_files",
    "write_stack_lsdyna",
    "write_stack_sections",
    "write_table",
    "write_unit_cell_vtu",
]
