"""preform's warp-knitted (stitch-bonded, non-crimp) fabric plugin.

Registers the ``warp_knit`` architecture (tow layers held by guide-bar stitching in lapping
notation), the ``stitch_polynomial`` shear law (separate branches parallel and perpendicular
to the stitch, with stitch failure, fitted to measured curves) and the ``stitch_yarn`` law (the
same asymmetry and failure derived from the stitch yarn's path and tensile data). Registered through the ``preform`` entry-point group.
"""

from __future__ import annotations

from preform.plugin_manager import hookimpl
from preform.registry import ArchitectureRegistrar, ShearLawRegistrar


@hookimpl
def preform_register_architectures(register: ArchitectureRegistrar) -> None:
    from preform.plugins.warpknit.model import WarpKnitFabric

    register.add(WarpKnitFabric)


@hookimpl
def preform_register_shear_laws(register: ShearLawRegistrar) -> None:
    from preform.plugins.warpknit.shear import SHEAR_LAWS
    from preform.plugins.warpknit.stitch_law import SHEAR_LAWS as STITCH_YARN_LAWS

    for name, params, build in [*SHEAR_LAWS, *STITCH_YARN_LAWS]:
        register.add(name, params, build)
