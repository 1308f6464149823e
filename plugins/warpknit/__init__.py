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
    # by import path: the model (and pydantic) loads when a library first reads such a fabric
    register.add_lazy("warp_knit", model="preform.plugins.warpknit.model:WarpKnitFabric")


@hookimpl
def preform_register_shear_laws(register: ShearLawRegistrar) -> None:
    # by import path: each law's module loads when a fabric first names it
    register.add_lazy(
        "stitch_polynomial",
        params="preform.plugins.warpknit.shear:StitchPolynomialParams",
        build="preform.plugins.warpknit.shear:build_stitch_polynomial",
    )
    register.add_lazy(
        "stitch_yarn",
        params="preform.plugins.warpknit.stitch_law:StitchYarnParams",
        build="preform.plugins.warpknit.stitch_law:build_stitch_yarn",
    )
