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
    from preform.plugins.woven.model import WovenFabric

    register.add(WovenFabric)


@hookimpl
def preform_register_shear_laws(register: ShearLawRegistrar) -> None:
    from preform.plugins.woven.shear import SHEAR_LAWS

    for name, params, build in SHEAR_LAWS:
        register.add(name, params, build)
