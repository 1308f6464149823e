"""Old names: a moved module's old path is an alias that warns until the next minor release
(0.2.0); retired outputs and their writers are refused with a message naming what replaced it."""

import importlib
import importlib.util
import warnings
from types import ModuleType
from typing import Any

#: Moved modules, old import path -> new one. The old path gives the new module itself (every
#: name, private ones and patching included) with a DeprecationWarning at the importer's line.
MOVED_MODULES: dict[str, str] = {
    "preform.tradeoff": "preform.bench.tradeoff",
    **{f"preform.drape.{m}": f"preform.optimise.{m}" for m in ("search", "curved", "relax")},
    "preform.drape.search_steps": "preform.optimise.search_steps",
    **{
        f"preform.drape.{module}": f"preform.drape.{room}.{module}"
        for room, modules in {
            "engine": "chebyshev compiled_surface fields generators net offset part ply polygon "
            "result surface",
            "kernels": "field_kernels generator_kernels net_kernels surface_kernels "
            "verdict_kernels",
            "judging": "verdict wrinkling",
            "properties": "preform_fields thickness",
        }.items()
        for module in modules.split()
    },
    # issue 16: the step contract below the pipeline, the harness, the optimisation on the drape
    "preform.pipeline.step": "preform.step",
    # issue 31: the primitives every package uses, at the bottom
    "preform.export.atomic": "preform.base.atomic",
    "preform.export.figures": "preform.base.figures",
    "preform.pipeline.status": "preform.base.status",
    "preform.pipeline.fidelity": "preform.base.fidelity",
    "preform.pipeline.export_section": "preform.base.export_section",
    # issue 31: each where the package order puts it (docs/design.md, "Layers")
    "preform.commands.options": "preform.command_line",
    "preform.stack.cases": "preform.pipeline.layup_case",
    "preform.export.compare_vtu": "preform.compare.vtu",
    "preform.export.fig_compare": "preform.compare.figure",
    "preform.pipeline.export_command": "preform.commands.export",
    # issue 31: numba's cache by content serves every package's kernels; compiling ahead runs
    # a case through the API
    "preform.drape.kernel_cache": "preform.base.kernel_cache",
    "preform.drape.kernel_compile": "preform.commands.kernel_compile",
}


class MovedModuleFinder:
    """The ``sys.meta_path`` finder and loader of ``MOVED_MODULES`` (``import preform`` adds it).
    A plain class, the protocols by their methods: ``importlib.abc`` is not imported at start-up
    otherwise, and importing it starts collections before the command pauses the collector."""

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Any:
        loader: Any = self  # a loader by its methods (typeshed's protocol wants load_module too)
        return importlib.util.spec_from_loader(name, loader) if name in MOVED_MODULES else None

    def create_module(self, spec: Any) -> ModuleType:
        module = importlib.import_module(MOVED_MODULES[spec.name])
        spec.loader_state = module.__spec__  # the import system sets ``spec`` on it: undone below
        # stacklevel 2: the importing line (``warnings`` does not count importlib's bootstrap)
        warnings.warn(f"{spec.name} is deprecated: import {module.__name__}", DeprecationWarning, 2)
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = module.__spec__.loader_state  # type: ignore[union-attr]


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
