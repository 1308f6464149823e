"""preform's own core plugin: generic shear laws and the fabric-independent pipeline steps.

Registered through the ``preform`` entry-point group like any third-party plugin. Everything is
registered by import path (``add_lazy``): starting the plugin host (``preform --help``,
``materials list``) imports none of the step, law or export modules; each is imported when a
run plans it or a fabric names it. ``tests/framework/test_lazy_registration.py`` loads every
entry and checks it against what is declared here.
"""

from __future__ import annotations

from preform.plugin_manager import hookimpl
from preform.registry import ExporterRegistrar, ShearLawRegistrar, StepRegistrar

#: Steps, in planning order: (name, import path of the module's list holding it, the scene
#: sections it owns and checks, ``Step.sections``). Every built-in step provides the one
#: product of its own name.
STEPS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("unit_cell", "preform.pipeline.core_steps:STEPS", ()),
    ("shear_law", "preform.pipeline.core_steps:STEPS", ()),
    ("shear_curve", "preform.pipeline.core_steps:STEPS", ("shear",)),
    ("surface", "preform.drape.steps:STEPS", ()),
    ("drape", "preform.drape.steps:STEPS", ("tool", "ply", "start", "part")),
    ("thickness", "preform.drape.preform_steps:STEPS", ()),
    ("permeability", "preform.drape.preform_steps:STEPS", ()),
    ("energy_vs_angle", "preform.optimise.search_steps:STEPS", ()),
    ("optimum", "preform.optimise.search_steps:STEPS", ("search",)),
    ("mesh_mapping", "preform.export.export_steps:STEPS", ("export",)),
    ("layup", "preform.stack.steps:STEPS", ("layup",)),
    ("stack_sections", "preform.stack.steps:STEPS", ()),
)

#: Exporters (steps writing files): (name, import path), as STEPS.
EXPORTERS: tuple[tuple[str, str], ...] = (
    ("shear_curve_json", "preform.pipeline.core_steps:EXPORTERS"),
    ("shear_curve_png", "preform.pipeline.core_steps:EXPORTERS"),
    ("unit_cell_png", "preform.pipeline.core_steps:EXPORTERS"),
    ("unit_cell_vtu", "preform.pipeline.core_steps:EXPORTERS"),
    ("cells_csv", "preform.export.drape_outputs:EXPORTERS"),
    ("vtu", "preform.export.drape_outputs:EXPORTERS"),
    ("fibre_pattern_png", "preform.export.drape_outputs:EXPORTERS"),
    ("energy_plot_png", "preform.optimise.search_steps:EXPORTERS"),
    ("energy_vs_angle_csv", "preform.optimise.search_steps:EXPORTERS"),
    ("library_energy_png", "preform.optimise.search_steps:EXPORTERS"),
    ("element_table", "preform.export.export_steps:EXPORTERS"),
    ("element_vtu", "preform.export.export_steps:EXPORTERS"),
    ("abaqus_include", "preform.export.export_steps:EXPORTERS"),
    ("lsdyna_include", "preform.export.export_steps:EXPORTERS"),
    ("ansys_macro", "preform.export.export_steps:EXPORTERS"),
    ("calculix_include", "preform.export.export_steps:EXPORTERS"),
    ("cut_pattern", "preform.export.export_steps:EXPORTERS"),
    ("stack_csv", "preform.stack.steps:EXPORTERS"),
    ("stack_thickness_png", "preform.stack.steps:EXPORTERS"),
    ("stack_abaqus", "preform.stack.steps:EXPORTERS"),
    ("stack_calculix", "preform.stack.steps:EXPORTERS"),
    ("stack_lsdyna", "preform.stack.steps:EXPORTERS"),
    ("stack_ansys", "preform.stack.steps:EXPORTERS"),
)

#: Shear laws: (name, params model, builder), as import paths.
SHEAR_LAWS: tuple[tuple[str, str, str], ...] = (
    ("polynomial", "preform.shear.laws:PolynomialParams", "preform.shear.laws:build_polynomial"),
    ("tabulated", "preform.shear.laws:TabulatedParams", "preform.shear.laws:build_tabulated"),
)


@hookimpl
def preform_register_shear_laws(register: ShearLawRegistrar) -> None:
    for name, params, build in SHEAR_LAWS:
        register.add_lazy(name, params=params, build=build)


@hookimpl
def preform_register_steps(register: StepRegistrar) -> None:
    for name, target, sections in STEPS:
        register.add_lazy(name, provides=(name,), target=target, sections=sections)


@hookimpl
def preform_register_exporters(register: ExporterRegistrar) -> None:
    for name, target in EXPORTERS:
        register.add_lazy(name, provides=(name,), target=target)
