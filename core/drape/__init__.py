"""The kinematic drape: tool surfaces, the pin-jointed net, its shear and energy fields.

The optimisation on top of it (the least-energy search, curved generators, relaxation) is
``preform.optimise``; ``preform.drape.search``, ``.curved``, ``.relax`` and ``.search_steps``
are deprecated aliases of its modules. Called, this package is the Python API's
``preform.drape(...)``: the root package makes it so (``preform/__init__``), as the engine sits
below the API and imports nothing of it.
"""

from preform.drape.chebyshev import chebyshev_angle
from preform.drape.fields import energy_field, summary
from preform.drape.generators import ClosedFormGeodesics, PlanPolylines
from preform.drape.net import ClosedFormPlacement, DrapeError, drape
from preform.drape.part import HeightCut, Part, PlanPolygon
from preform.drape.ply import PlyOutline
from preform.drape.result import CellStatus, DrapeResult, EnergyField, NodeStatus
from preform.drape.surface import Surface

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
