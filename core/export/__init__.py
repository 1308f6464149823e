"""Exporters: VTK (.vtu), tables (CSV/Parquet/JSON), flat patterns (CSV/DXF/SVG) and figures.

One format per module; matplotlib and meshio are optional extras imported when a writer runs.
"""

from preform.export.fig_curves import energy_vs_angle_figure, shear_curve_figure
from preform.export.fig_drape import fibre_pattern_figure
from preform.export.fig_unit_cell import unit_cell_figure
from preform.export.flat_pattern import (
    flat_pattern,
    write_flat_pattern_csv,
    write_flat_pattern_dxf,
    write_flat_pattern_svg,
)
from preform.export.tables import cells_table, write_json, write_table
from preform.export.vtu import write_drape_vtu, write_unit_cell_vtu

__all__ = [
    "cells_table",
    "energy_vs_angle_figure",
    "fibre_pattern_figure",
    "flat_pattern",
    "shear_curve_figure",
    "unit_cell_figure",
    "write_drape_vtu",
    "write_flat_pattern_csv",
    "write_flat_pattern_dxf",
    "write_flat_pattern_svg",
    "write_json",
    "write_table",
    "write_unit_cell_vtu",
]
