"""preform's own core plugin: generic shear laws and the fabric-independent pipeline steps.

Registered through the ``preform`` entry-point group like any third-party plugin.
"""

from __future__ import annotations

from preform.plugin_manager import hookimpl
from preform.registry import ExporterRegistrar, ShearLawRegistrar, StepRegistrar


@hookimpl
def preform_register_shear_laws(register: ShearLawRegistrar) -> None:
    from preform.shear.laws import SHEAR_LAWS

    for name, params, build in SHEAR_LAWS:
        register.add(name, params, build)


@hookimpl
def preform_register_steps(register: StepRegistrar) -> None:
    from preform.drape import preform_steps
    from preform.drape import steps as drape_steps
    from preform.export import export_steps
    from preform.optimise import search_steps
    from preform.pipeline.core_steps import STEPS

    for step in [
        *STEPS,
        *drape_steps.STEPS,
        *preform_steps.STEPS,
        *search_steps.STEPS,
        *export_steps.STEPS,
    ]:
        register.add(step)


@hookimpl
def preform_register_exporters(register: ExporterRegistrar) -> None:
    from preform.drape import steps as drape_steps
    from preform.export import export_steps
    from preform.optimise import search_steps
    from preform.pipeline.core_steps import EXPORTERS

    for step in [
        *EXPORTERS,
        *drape_steps.EXPORTERS,
        *search_steps.EXPORTERS,
        *export_steps.EXPORTERS,
    ]:
        register.add(step)
