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

from typing import TYPE_CHECKING, Any

from preform import _moved
from preform.base import __version__

_moved.install()  # the old paths of moved modules, with a warning (preform._moved)

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

#: Names served by ``preform.api``, imported when first asked for. ``preform.drape`` is the
#: subpackage of that name, callable as ``preform.api.drape`` (see ``preform/drape/__init__``).
_API = frozenset(
    {
        "CaseRun",
        "Compared",
        "Drape",
        "Layup",
        "LeastEnergy",
        "RunResult",
        "calibrate",
        "compare_drape",
        "fabric",
        "layup",
        "least_energy",
        "load_library",
        "read_measurement",
        "run",
        "scene",
    }
)


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
