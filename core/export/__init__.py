"""Exporters: VTK (.vtu), tables (CSV/Parquet/JSON), flat and cutting patterns (CSV/DXF/SVG),
figures, and the drape mapped onto a user's FE mesh (Abaqus, LS-DYNA, per-element table, VTU).

One format per module; matplotlib, meshio, shapely and ezdxf are optional extras imported when a
writer runs.
"""

from preform.export.abaqus import write_abaqus_include
from preform.export.ansys import write_ansys_macro
from preform.export.cut_pattern import (
    cut_pattern,
    write_cut_pattern_csv,
    write_cut_pattern_dxf,
    write_cut_pattern_svg,
)
from preform.export.element_table import element_table, write_element_table
from preform.export.fe_mapping import MeshMapping, map_to_mesh
from preform.export.fig_curves import energy_vs_angle_figure, shear_curve_figure
from preform.export.fig_drape import fibre_pattern_figure
from preform.export.fig_unit_cell import unit_cell_figure
from preform.export.flat_pattern import (
    flat_pattern,
    write_flat_pattern_csv,
    write_flat_pattern_dxf,
    write_flat_pattern_svg,
)
from preform.export.lsdyna import write_lsdyna_include
from preform.export.mapped_vtu import write_mapped_vtu
from preform.export.shell_mesh import ShellMesh, read_shell_mesh, shell_mesh
from preform.export.tables import cells_table, write_json, write_table
from preform.export.vtu import write_drape_vtu, write_unit_cell_vtu

__all__ = [
    "MeshMapping",
    "ShellMesh",
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
    "write_cut_pattern_csv",
    "write_cut_pattern_dxf",
    "write_cut_pattern_svg",
    "write_drape_vtu",
    "write_element_table",
    "write_flat_pattern_csv",
    "write_flat_pattern_dxf",
    "write_flat_pattern_svg",
    "write_json",
    "write_lsdyna_include",
    "write_mapped_vtu",
    "write_table",
    "write_unit_cell_vtu",
]
