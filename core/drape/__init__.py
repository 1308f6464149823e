"""The kinematic drape, in rooms (``docs/design.md``): ``engine`` (tools, the pin-jointed net,
its fields), ``kernels``, ``judging``, ``properties``, and the steps. The optimisation on top
of it is ``preform.optimise``; old module paths are in ``preform._moved.MOVED_MODULES``."""

import sys as _sys
import types as _types
from typing import Any as _Any

from preform.drape.engine.chebyshev import chebyshev_angle
from preform.drape.engine.fields import energy_field, summary
from preform.drape.engine.generators import ClosedFormGeodesics, PlanPolylines
from preform.drape.engine.net import ClosedFormPlacement, DrapeError, drape
from preform.drape.engine.part import HeightCut, Part, PlanPolygon
from preform.drape.engine.ply import PlyOutline
from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField, NodeStatus
from preform.drape.engine.surface import Surface

__all__ = [
    "CellStatus",
    "ClosedFormGeodesics",
    "ClosedFormPlacement",
    "DrapeError",
    "DrapeResult",
    "EnergyField",
    "HeightCut",
    "NodeStatus",
    "Part",
    "PlanPolygon",
    "PlanPolylines",
    "PlyOutline",
    "Surface",
    "chebyshev_angle",
    "drape",
    "energy_field",
    "summary",
]


class _DrapePackage(_types.ModuleType):
    """``preform.drape`` is this package and, called, the Python API's ``preform.drape(...)``
    (``preform.api.drape``: mm and degrees, a pipeline case). The import system binds the
    package to ``preform.drape`` whenever it is imported, so the API function cannot own the
    name; a callable package gives ``preform.drape(fabric, ...)`` and keeps
    ``preform.drape.engine.net`` and ``from preform.drape import drape`` (the SI engine) working."""

    def __call__(self, *args: _Any, **kwargs: _Any) -> _Any:
        from preform.api import drape as api_drape

        return api_drape(*args, **kwargs)


_sys.modules[__name__].__class__ = _DrapePackage
