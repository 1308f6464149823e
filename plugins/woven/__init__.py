"""preform's woven fabric plugin: 2D (plain, twill, satin, basket) and 3D weaves.

Registers the ``woven`` architecture (levels, weaving matrix, tow types; or a weave generator)
and the ``friction_compaction`` shear law (crossover friction plus tow compaction, after the
founding paper). Registered through the ``preform`` entry-point group.
"""

from __future__ import annotations

from preform.plugin_manager import hookimpl
from preform.registry import ArchitectureRegistrar, ShearLawRegistrar


@hookimpl
def preform_register_architectures(register: ArchitectureRegistrar) -> None:
    # by import path: the model (and pydantic) loads when a library first reads such a fabric
    register.add_lazy("woven", model="preform.plugins.woven.model:WovenFabric")


@hookimpl
def preform_register_shear_laws(register: ShearLawRegistrar) -> None:
    # by import path: the law's module loads when a fabric first names it
    register.add_lazy(
        "friction_compaction",
        params="preform.plugins.woven.shear:FrictionCompactionParams",
        build="preform.plugins.woven.shear:build_friction_compaction",
    )
