"""Old names: moved modules stay one release as an alias that warns; retired outputs and
their writers are refused with a message naming what replaced them."""

import importlib
import sys
import warnings


def alias_moved_module(old: str, new: str) -> None:
    """Make the module being imported as ``old`` the module ``new`` itself (every name, private
    ones and patching included), with a DeprecationWarning at the importer's line."""
    moved = importlib.import_module(new)
    # 1: here, 2: the alias module's body, 3+: the import machinery, then the importer
    warnings.warn(f"{old} is deprecated: import {new}", DeprecationWarning, stacklevel=3)
    sys.modules[old] = moved


#: Every moved module, old path -> new path (issue 16: the optimisation out of the drape, the
#: trade study into ``bench``; issue 31: the drape's modules into its rooms).
MOVED_MODULES: dict[str, str] = {
    "preform.tradeoff": "preform.bench.tradeoff",
    **{f"preform.drape.{m}": f"preform.optimise.{m}" for m in ("search", "curved", "relax")},
    "preform.drape.search_steps": "preform.optimise.search_steps",
    **{
        f"preform.drape.{module}": f"preform.drape.{room}.{module}"
        for room, modules in {
            "engine": "chebyshev compiled_surface fields generators net offset part ply polygon "
            "result surface",
            "kernels": "field_kernels generator_kernels kernel_cache kernel_compile net_kernels "
            "surface_kernels verdict_kernels",
            "judging": "verdict wrinkling",
            "properties": "preform_fields thickness",
        }.items()
        for module in modules.split()
    },
}

#: Scene outputs (and ``preform export`` targets) that were replaced: old name -> the message
#: that refuses it, naming what replaced it. Refused rather than aliased: the old output wrote
#: other files under other names, so running the new one silently would surprise a script.
RETIRED_OUTPUTS: dict[str, str] = {
    "flat_pattern": (
        "the output 'flat_pattern' (the cells' staircase in the flat) was replaced by "
        "'cut_pattern': the part clipped in the flat, smooth, with seam allowance, darts and "
        "cuts (cut_pattern.dxf/.svg/.csv; docs/exports.md). Ask for 'cut_pattern' instead"
    ),
}
#: ``preform export`` targets, likewise.
RETIRED_TARGETS: dict[str, str] = {
    "flat-pattern": (
        "'flat-pattern' is now 'cut-pattern' (the part clipped in the flat: "
        "cut_pattern.dxf/.svg/.csv; docs/exports.md)"
    ),
}
#: Names of ``preform.export`` that were removed with the retired outputs: name -> message.
RETIRED_NAMES: dict[str, str] = {
    f"write_flat_pattern_{kind}": (
        f"preform.export.write_flat_pattern_{kind} was removed with the 'flat_pattern' output: "
        f"use write_cut_pattern_{kind}(cut_pattern(result)); cut_pattern(result, smoothing=0) "
        "is the cells' exact staircase"
    )
    for kind in ("csv", "dxf", "svg")
}
