"""preform: fibre-architecture-aware drape simulation of reinforcement fabrics.

The public API; everything else is reached through its module. In mm and degrees::

    import preform
    lib = preform.load_library()                     # bundled + PREFORM_LIBRARY (+ your paths)
    d = preform.drape("E-BX-318", generator_angle_deg=80)
    best = preform.least_energy("E-BX-318")
    run = preform.run(scenes=["shear"], out_dir="results")

The functions and result classes of ``preform.api`` (``drape``, ``least_energy``, ``layup``, ``run``,
``scene``, ``fabric``, ``load_library``, ``Drape``, ``LeastEnergy``, ``RunResult``) are imported
on first use, so ``import preform`` stays fast (see ``docs/api.md``).
"""

import sys
from types import ModuleType
from typing import TYPE_CHECKING, Any

from preform import _moved
from preform.base import __version__

sys.meta_path.insert(0, _moved.MovedModuleFinder())  # old paths of moved modules, warning

if TYPE_CHECKING:
    from preform.api import (
        CaseRun,
        Compared,
        Drape,
        Layup,
        LeastEnergy,
        RunResult,
        calibrate,
        compare_drape,
        drape,
        fabric,
        layup,
        least_energy,
        load_library,
        read_measurement,
        run,
        scene,
    )
    from preform.base.status import CaseFailure, CaseStatus
    from preform.material import FabricBase, Location
    from preform.plugin_manager import PluginHost, default_host, hookimpl
    from preform.registry import RegistrationError, Registry
    from preform.shear.law import ShearLaw, force_per_length_N_per_mm
    from preform.step import CaseContext, Step

#: The plugin contract's names, by the module serving each, also imported when first asked for:
#: ``preform --version`` needs neither numpy (``preform.shear.law``) nor pydantic
#: (``preform.material``), and ``import preform`` alone pays for neither.
_CONTRACT = {
    "FabricBase": "preform.material",
    "Location": "preform.material",
    "CaseFailure": "preform.base.status",
    "CaseStatus": "preform.base.status",
    "PluginHost": "preform.plugin_manager",
    "default_host": "preform.plugin_manager",
    "hookimpl": "preform.plugin_manager",
    "RegistrationError": "preform.registry",
    "Registry": "preform.registry",
    "ShearLaw": "preform.shear.law",
    "force_per_length_N_per_mm": "preform.shear.law",
    "CaseContext": "preform.step",
    "Step": "preform.step",
}


class _DrapePackage(ModuleType):
    """``preform.drape``, called, is the API's ``preform.drape(...)`` (mm, degrees, a case): the
    import system binds the package to the name, so the API function cannot own it. Made so
    here, on binding, as the engine imports nothing of the API above it."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        from preform.api import drape

        return drape(*args, **kwargs)


class _Root(ModuleType):
    def __setattr__(self, name: str, value: Any) -> None:
        if name == "drape" and type(value) is ModuleType:  # the import system binding it
            value.__class__ = _DrapePackage
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Root


def __getattr__(name: str) -> Any:
    import importlib

    if name == "drape":  # the callable subpackage
        return importlib.import_module("preform.drape")
    module = "preform.api" if name in _API else _CONTRACT.get(name)
    if module is None:
        raise AttributeError(f"module 'preform' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # once imported, a plain attribute
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


__all__ = [
    "CaseContext",
    "CaseFailure",
    "CaseRun",
    "CaseStatus",
    "Compared",
    "Drape",
    "FabricBase",
    "Layup",
    "LeastEnergy",
    "Location",
    "PluginHost",
    "RegistrationError",
    "Registry",
    "RunResult",
    "ShearLaw",
    "Step",
    "__version__",
    "calibrate",
    "compare_drape",
    "default_host",
    "drape",
    "fabric",
    "force_per_length_N_per_mm",
    "hookimpl",
    "layup",
    "least_energy",
    "load_library",
    "read_measurement",
    "run",
    "scene",
]

#: Names served by ``preform.api`` (every public name not served otherwise), imported when
#: first asked for. ``preform.drape`` is the subpackage of that name, callable as
#: ``preform.api.drape`` (see ``preform/drape/__init__``).
_API = frozenset(__all__) - _CONTRACT.keys() - {"__version__", "drape"}
