"""preform: fibre-architecture-aware drape simulation of reinforcement fabrics.

The public API; everything else is reached through its module.
"""

from typing import Any

__version__ = "0.1.0"

from preform.material import FabricBase, Location
from preform.pipeline.status import CaseFailure, CaseStatus
from preform.pipeline.step import CaseContext, Step
from preform.plugin_manager import PluginHost, default_host, hookimpl
from preform.registry import RegistrationError, Registry
from preform.shear.law import ShearLaw, force_per_length_N_per_mm


def load_library(*args: Any, **kwargs: Any) -> Any:
    """Load and validate the materials library (see ``preform.library.load_library``)."""
    from preform.library import load_library as _load

    return _load(*args, **kwargs)


__all__ = [
    "CaseContext",
    "CaseFailure",
    "CaseStatus",
    "FabricBase",
    "Location",
    "PluginHost",
    "RegistrationError",
    "Registry",
    "ShearLaw",
    "Step",
    "__version__",
    "default_host",
    "force_per_length_N_per_mm",
    "hookimpl",
    "load_library",
]
