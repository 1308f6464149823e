"""preform: fibre-architecture-aware drape simulation of reinforcement fabrics.

The public API; everything else is reached through its module. In mm and degrees::

    import preform
    lib = preform.load_library()                     # bundled + PREFORM_LIBRARY (+ your paths)
    d = preform.drape("E-BX-318", generator_angle_deg=80)
    best = preform.least_energy("E-BX-318")
    run = preform.run(scenes=["shear"], out_dir="results")

The functions and result classes of ``preform.api`` (``drape``, ``least_energy``, ``run``,
``scene``, ``fabric``, ``load_library``, ``Drape``, ``LeastEnergy``, ``RunResult``) are imported
on first use, so ``import preform`` stays fast (see ``docs/api.md``).
"""

from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

from preform.material import FabricBase, Location
from preform.pipeline.status import CaseFailure, CaseStatus
from preform.plugin_manager import PluginHost, default_host, hookimpl
from preform.registry import RegistrationError, Registry
from preform.shear.law import ShearLaw, force_per_length_N_per_mm
from preform.step import CaseContext, Step

if TYPE_CHECKING:
    from preform.api import (
        CaseRun,
        Drape,
        LeastEnergy,
        RunResult,
        drape,
        fabric,
        least_energy,
        load_library,
        run,
        scene,
    )

#: Names served by ``preform.api``, imported when first asked for. ``preform.drape`` is the
#: subpackage of that name, callable as ``preform.api.drape`` (see ``preform/drape/__init__``).
_API = frozenset(
    {
        "CaseRun",
        "Drape",
        "LeastEnergy",
        "RunResult",
        "fabric",
        "least_energy",
        "load_library",
        "run",
        "scene",
    }
)


def __getattr__(name: str) -> Any:
    if name == "drape":  # the callable subpackage
        import importlib

        return importlib.import_module("preform.drape")
    if name in _API:
        from preform import api

        value = getattr(api, name)
        globals()[name] = value  # once imported, a plain attribute
        return value
    raise AttributeError(f"module 'preform' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)


__all__ = [
    "CaseContext",
    "CaseFailure",
    "CaseRun",
    "CaseStatus",
    "Drape",
    "FabricBase",
    "LeastEnergy",
    "Location",
    "PluginHost",
    "RegistrationError",
    "Registry",
    "RunResult",
    "ShearLaw",
    "Step",
    "__version__",
    "default_host",
    "drape",
    "fabric",
    "force_per_length_N_per_mm",
    "hookimpl",
    "least_energy",
    "load_library",
    "run",
    "scene",
]
