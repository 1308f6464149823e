"""The kinematic drape, in rooms (``docs/design.md``): ``engine`` (tools, the pin-jointed net,
its fields), ``kernels``, ``judging``, ``properties``, and the steps. The optimisation on top
of it is ``preform.optimise``; old module paths are in ``preform._moved.MOVED_MODULES``.
Called, this package is the Python API's ``preform.drape(...)``: the root package makes it so
(``preform/__init__``), as the engine sits below the API and imports nothing of it.
"""

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
