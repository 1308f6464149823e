"""Old names: moved modules stay as aliases that warn until the next minor release (0.2.0);
retired outputs and their writers are refused with a message naming what replaced them."""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import warnings
from pathlib import Path
from types import ModuleType

#: Moved modules, old import path -> new one. Importing the old path gives the new module itself
#: (every name, private ones and patching included) and a DeprecationWarning at the importer's
#: line. Removed at the next minor release (docs/design.md "Layers", CHANGELOG).
MOVED_MODULES: dict[str, str] = {
    # issue 16: the harness and the optimisation on top of the drape engine
    "preform.tradeoff": "preform.bench.tradeoff",
    "preform.drape.search": "preform.optimise.search",
    "preform.drape.curved": "preform.optimise.curved",
    "preform.drape.relax": "preform.optimise.relax",
    "preform.drape.search_steps": "preform.optimise.search_steps",
    # issue 31: the primitives every package uses, at the bottom
    "preform.export.atomic": "preform.base.atomic",
    "preform.pipeline.status": "preform.base.status",
    "preform.pipeline.fidelity": "preform.base.fidelity",
    "preform.pipeline.export_section": "preform.base.export_section",
}

#: Frames of the import machinery, skipped when the warning looks for the importer's line.
_IMPORT_MACHINERY = (__file__, str(Path(importlib.__file__).parent), "<frozen importlib")


def _importer_stacklevel() -> int:
    """The ``stacklevel`` that puts a warning, raised by this module's loader, at the line of
    the code that imports (``import``, ``from ... import`` or ``importlib.import_module``).
    ``warnings`` itself steps over the frames of importlib's bootstrap without counting them."""
    frame = sys._getframe(1)
    level = 1
    while frame.f_back is not None and frame.f_code.co_filename.startswith(_IMPORT_MACHINERY):
        frame = frame.f_back
        filename = frame.f_code.co_filename
        level += not ("importlib" in filename and "_bootstrap" in filename)
    return level


class MovedModuleFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """A ``sys.meta_path`` finder serving ``MOVED_MODULES``: the old path is the new module."""

    def find_spec(
        self, fullname: str, path: object = None, target: object = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED_MODULES:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        new = MOVED_MODULES[spec.name]
        module = importlib.import_module(new)
        # the import system sets the alias spec on the module it is given: keep the real one
        spec.loader_state = module.__spec__
        warnings.warn(
            f"{spec.name} is deprecated: import {new}",
            DeprecationWarning,
            stacklevel=_importer_stacklevel(),
        )
        return module

    def exec_module(self, module: ModuleType) -> None:
        if module.__spec__ is not None and module.__spec__.loader_state is not None:
            module.__spec__ = module.__spec__.loader_state


def install() -> None:
    """Put the finder on ``sys.meta_path`` (once; ``import preform`` does it)."""
    if not any(isinstance(finder, MovedModuleFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, MovedModuleFinder())


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
